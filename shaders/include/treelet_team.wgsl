// One treelet's restructuring by a team of TEAM_LANES invocations (Karras & Aila 2013, §4: "we
// process the subsets of one size in parallel"), for levels of few treelets, where one invocation
// per treelet (treelet_dp.wgsl) leaves the device idle while each runs its ~1000 partition tests
// alone. The same four steps, with the same operations and tie-breaking, so the same topology:
//   1. lane 0: the root's cost and the formation (treelet_dp.wgsl's form_treelet), the leaves'
//      boxes and counts into workgroup memory;
//   2. lanes 0-15 and 16-31: the half tables' 16 entries each, straight from their leaves;
//   3. the DP by subset size k = 2 ..= m: the C(m, k) subsets of size k (the table
//      `subset_order`, `treelet::subsets_by_size`) side by side. When there are fewer subsets than
//      lanes, each subset gets L = 2^b lanes (at most one per partition) that split its partitions
//      by their b lowest bits: a lane fixes those to its own b bits and runs over every subset of
//      the others, so it tests about 1/L of them, in increasing order, with no step skipped. The
//      lanes then reduce to the least cost, ties to the smallest P, which is the partition the
//      serial search keeps (it keeps the first of equal costs, in increasing order). Costs and
//      best partitions live in workgroup memory; a barrier separates sizes;
//   4. lane 0: the write-back, taking each internal subset's partition from the DP instead of
//      searching it again;
//   5. lane 0: the next round's levels (treelet_dp.wgsl).
// The including kernel declares TEAMS (teams per workgroup), `subset_order` and what
// treelet_dp.wgsl needs, and includes treelet_dp.wgsl first. `optimize_treelet_team` contains
// barriers: every invocation of the workgroup calls it, teams without a treelet with
// `has_treelet = false`.

const TEAM_LANES: u32 = 32u;
// Subsets of up to MAX_TREELET leaves, indexed by their bits.
const TEAM_SUBSETS: u32 = 1u << MAX_TREELET;

var<workgroup> team_leaf_node: array<u32, TEAMS * MAX_TREELET>;
var<workgroup> team_leaf_min: array<vec3<f32>, TEAMS * MAX_TREELET>;
var<workgroup> team_leaf_max: array<vec3<f32>, TEAMS * MAX_TREELET>;
var<workgroup> team_leaf_prims: array<u32, TEAMS * MAX_TREELET>;
var<workgroup> team_low_min: array<vec3<f32>, TEAMS * 16u>;
var<workgroup> team_low_max: array<vec3<f32>, TEAMS * 16u>;
var<workgroup> team_low_prims: array<u32, TEAMS * 16u>;
var<workgroup> team_high_min: array<vec3<f32>, TEAMS * 16u>;
var<workgroup> team_high_max: array<vec3<f32>, TEAMS * 16u>;
var<workgroup> team_high_prims: array<u32, TEAMS * 16u>;
// c(S) and the best partition of S (internal subsets), per team.
var<workgroup> team_cost: array<f32, TEAMS * TEAM_SUBSETS>;
var<workgroup> team_split: array<u32, TEAMS * TEAM_SUBSETS>;
// Each lane's best (cost, P) during a reduction.
var<workgroup> team_best_cost: array<f32, TEAMS * TEAM_LANES>;
var<workgroup> team_best_split: array<u32, TEAMS * TEAM_LANES>;

// 1: this pipeline holds the team path; 0: it does not, and its threshold (params.team_below) is
// 0, so that the path would never run (`TreeletKernels::get`). The schedules' defaults give teams
// no threshold, and a GPU compiler then drops the path's code and workgroup memory instead of
// allocating registers and instruction cache for it.
override TREELET_TEAMS: u32 = 1u;

// Whether a dispatched level's or wave's `treelets` go to teams, one per workgroup.
fn by_teams(treelets: u32) -> bool {
    return TREELET_TEAMS != 0u && treelets < params.team_below;
}

// A climb's wave (treelets_climb.wgsl, waves_climb.wgsl: TEAMS teams, a treelet per team at a
// time) goes to the teams below this many treelets and below the team threshold: from TEAM_WAVE
// treelets on, it takes longer by teams than with a treelet per invocation.
const TEAM_WAVE: u32 = 32u;

fn climb_wave_by_teams(treelets: u32) -> bool {
    return by_teams(treelets) && treelets < TEAM_WAVE;
}

fn team_subset_min(base: u32, s: u32) -> vec3<f32> {
    return min(team_low_min[base + (s & 15u)], team_high_min[base + (s >> 4u)]);
}

fn team_subset_max(base: u32, s: u32) -> vec3<f32> {
    return max(team_low_max[base + (s & 15u)], team_high_max[base + (s >> 4u)]);
}

fn team_subset_prims(base: u32, s: u32) -> u32 {
    return team_low_prims[base + (s & 15u)] + team_high_prims[base + (s >> 4u)];
}

// Steps 1 and 2 (lane 0): the root's cost (returned) and the treelet (treelet_dp.wgsl's
// form_treelet, whose private arrays lane 0 keeps for the write-back), its leaves copied into the
// team's arrays.
fn team_form(root: u32, team: u32) -> f32 {
    let current = form_treelet(root);
    let leaves = team * MAX_TREELET;
    for (var i = 0u; i < MAX_TREELET; i++) {
        team_leaf_node[leaves + i] = leaf_node[i];
        team_leaf_min[leaves + i] = leaf_min[i];
        team_leaf_max[leaves + i] = leaf_max[i];
        team_leaf_prims[leaves + i] = leaf_prims[i];
    }
    return current;
}

// Steps 4 and 5 (lane 0): treelet_dp.wgsl's write_back, each internal subset's partition and
// cost taken from the DP, its box from the team's half tables.
fn team_write_back(team: u32, full_split: u32, full_cost: f32) {
    let subsets = team * TEAM_SUBSETS;
    let halves = team * 16u;
    let leaf_levels = leaf_next_levels();
    var queue: WriteQueue;
    begin_write_back(&queue);
    for (var head = 0u; head < queued; head++) {
        let s = queue.subsets[head];
        var split = full_split;
        var cost = full_cost;
        if head != 0u {
            split = team_split[subsets + s];
            cost = team_cost[subsets + s];
        }
        write_entry(&queue, head, split, cost, team_subset_min(halves, s), team_subset_max(halves, s), team_subset_prims(halves, s));
    }
    store_next_levels(&queue, leaf_levels);
}

// Steps 1-5 for the treelet rooted at `root`, by the invocation in lane `lane` of team `team`.
fn optimize_treelet_team(root: u32, has_treelet: bool, team: u32, lane: u32) {
    let m = TREELET_SIZE;
    let leaves = team * MAX_TREELET;
    let subsets = team * TEAM_SUBSETS;
    let halves = team * 16u;
    let lanes = team * TEAM_LANES;
    // Lane 0's: the root's cost before restructuring.
    var current = 0.0;
    if has_treelet && lane == 0u {
        current = team_form(root, team);
    }
    workgroupBarrier();
    // Step 2: entry t of the low (lanes 0-15) or high (lanes 16-31) half table; and the leaves'
    // costs, the DP's subsets of size 1.
    let t = lane & 15u;
    let first_leaf = select(0u, 4u, lane >= 16u);
    var box_min = vec3<f32>(F32_MAX);
    var box_max = vec3<f32>(-F32_MAX);
    var prims = 0u;
    // Highest leaf first: the order in which build_half_tables unites them (the same box, also
    // in the sign of a zero).
    for (var b = 3u; b < 4u; b--) {
        let i = first_leaf + b;
        if has_treelet && (t & (1u << b)) != 0u && i < m {
            box_min = min(box_min, team_leaf_min[leaves + i]);
            box_max = max(box_max, team_leaf_max[leaves + i]);
            prims += team_leaf_prims[leaves + i];
        }
    }
    if lane < 16u {
        team_low_min[halves + t] = box_min;
        team_low_max[halves + t] = box_max;
        team_low_prims[halves + t] = prims;
    } else {
        team_high_min[halves + t] = box_min;
        team_high_max[halves + t] = box_max;
        team_high_prims[halves + t] = prims;
    }
    if has_treelet && lane < m {
        team_cost[subsets + (1u << lane)] = costs[team_leaf_node[leaves + lane]];
    }
    workgroupBarrier();
    // Step 3.
    var full_split = 0u;
    var full_best = F32_MAX;
    // Per size k, carried from size to size with one exact division each (C(n, k + 1) =
    // C(n, k)·(n − k) / (k + 1)), not recomputed by loops of divisions: the subsets of size k,
    // C(m, k), and where they start in `subset_order`, the subsets of fewer leaves of
    // MAX_TREELET, Σ_{j<k} C(MAX_TREELET, j).
    var count = m * (m - 1u) / 2u;
    var first = 1u + MAX_TREELET;
    var of_max_size = MAX_TREELET * (MAX_TREELET - 1u) / 2u;
    for (var k = 2u; k <= m; k++) {
        // Lanes per subset, 2^b: the largest power of two with count * L <= TEAM_LANES, at least
        // 1, and at most the subset's 2^(k-1) - 1 partitions (rounded up).
        let b = min(firstLeadingBit(max(TEAM_LANES / count, 1u)), k - 1u);
        let per_subset = 1u << b;
        let side_by_side = TEAM_LANES >> b;
        let group = lane >> b;
        let turn = lane & (per_subset - 1u);
        for (var done = 0u; done < count; done += side_by_side) {
            let index = done + group;
            let valid = has_treelet && index < count;
            var best = F32_MAX;
            var best_p = 0u;
            var s = 0u;
            if valid {
                s = subset_order[first + index];
                // P over the non-empty subsets of S without its lowest bit (treelet_dp.wgsl's
                // best_partition). This lane's: the b lowest of those bits set as the bits of
                // `turn`, the others (`high`) over all their subsets, in increasing order.
                let delta = (s - 1u) & s;
                var high = delta;
                var fixed = 0u;
                for (var j = 0u; j < b; j++) {
                    let bit = high & (0u - high);
                    fixed |= select(0u, bit, ((turn >> j) & 1u) != 0u);
                    high ^= bit;
                }
                var h = 0u;
                loop {
                    let p = fixed | h;
                    if p != 0u {
                        let c = team_cost[subsets + p] + team_cost[subsets + (s ^ p)];
                        if c < best {
                            best = c;
                            best_p = p;
                        }
                    }
                    h = (h - high) & high;
                    if h == 0u {
                        break;
                    }
                }
            }
            team_best_cost[lanes + lane] = best;
            team_best_split[lanes + lane] = best_p;
            workgroupBarrier();
            for (var half = per_subset >> 1u; half > 0u; half >>= 1u) {
                if turn < half {
                    let other_cost = team_best_cost[lanes + lane + half];
                    let other_p = team_best_split[lanes + lane + half];
                    if other_cost < best || (other_cost == best && other_p < best_p) {
                        best = other_cost;
                        best_p = other_p;
                        team_best_cost[lanes + lane] = best;
                        team_best_split[lanes + lane] = best_p;
                    }
                }
                workgroupBarrier();
            }
            if valid && turn == 0u {
                if k < m {
                    let area = surface_area(team_subset_min(halves, s), team_subset_max(halves, s), params.zero);
                    team_cost[subsets + s] = combine_cost(area, team_subset_prims(halves, s), best);
                    team_split[subsets + s] = best_p;
                } else {
                    full_split = best_p;
                    full_best = best;
                }
            }
            workgroupBarrier();
        }
        first += of_max_size;
        of_max_size = of_max_size * (MAX_TREELET - k) / (k + 1u);
        count = count * (m - k) / (k + 1u);
    }
    // Step 4: lane 0 holds the full set's partition (its only subset of size m); a treelet of
    // fewer leaves (phased rounds) finds its own among the subsets the DP stored.
    if has_treelet && lane == 0u {
        let full = treelet_full_set();
        var full_cost: f32;
        if treelet_leaves < m {
            full_split = team_split[subsets + full];
            full_cost = team_cost[subsets + full];
        } else {
            full_cost = internal_cost(team_subset_min(halves, full), team_subset_max(halves, full), team_subset_prims(halves, full), full_best);
        }
        if treelet_leaves > 2u && full_cost < current {
            team_write_back(team, full_split, full_cost);
        } else {
            store_root_next_level(root);
        }
    }
}
