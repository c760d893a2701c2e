// One treelet's restructuring by one invocation (Karras & Aila 2013, §4; the paper spreads it over
// a warp): many treelets of one level are optimized side by side, one per invocation, and every
// invocation runs the same code (the treelet size is a pipeline constant), so a SIMD or SIMT
// machine runs them in lockstep without divergence.
//   1. cost: the root's cost from its children, whose subtrees are final now;
//   2. formation: start from the root's two children, then repeatedly expand the treelet leaf of
//      largest surface area that is an internal node (first on ties), up to treelet_size leaves
//      (always reached, a root having at least gamma >= treelet_size primitives, except in phased
//      rounds of P < treelet_size phases, which expand no leaf P − 1 levels below the root and
//      may end with fewer: `treelet_leaves`, the others empty). Each leaf's node (box and
//      children), primitive count and cost are loaded once, together, when it joins the treelet:
//      an expansion waits for one round trip to memory, not two, and the DP's inputs need none;
//   3. dynamic programming over the subsets S of the leaves in increasing order (a subset's proper
//      subsets come first): c(S) = min(Ci·a(S) + min_P (c(P) + c(S\P)), Ct·a(S)·t(S)), each
//      unordered partition once (P over the non-empty subsets of S without its lowest bit, in
//      increasing order, the first of equal costs kept). Written out per treelet size
//      (`subset_costs`, generated: treelet_dp_unrolled.wgsl), so that the costs are values in
//      registers, not words of a private array indexed by S and P; they are also stored in
//      `dp_cost` for step 4. a(S) and t(S) come from S's box and count, each a value made from
//      S without its lowest leaf and that leaf: no table of subset boxes (tables of the 16
//      subsets of each half of the leaves are ~220 words, and with them the DP spilled:
//      `scripts/shader-stats.sh`, README "Kernel statistics");
//   4. if the optimal cost is lower than the current one, the new topology is written back
//      breadth-first (left child = the best P, right = S\P), reusing the treelet's internal
//      nodes in formation order (the root keeps its index), with boxes, N, C and parent links.
//      The best P of an internal subset is found again from the stored costs (the same search);
//   5. the next round's level (gamma = params.next_gamma) of every node the treelet finished,
//      children first: one more than its children's highest, for nodes of at least next_gamma
//      primitives. Each such node is a root of this round or an internal node of one of its
//      treelets, finished after its children, so the next round needs no climb for its levels
//      (none without a next round).
// The CPU twin is `WorkingTree::optimize_treelet` (same operations in the same order; costs agree
// to a few ulps where the GPU fuses Ci·a into the following add).
// The including kernel declares `params: RoundParams` (treelet_round.wgsl), `nodes:
// array<BvhNode>`, `parents: array<u32>`, `prim_counts: array<u32>`, `costs: array<f32>` (all
// read_write storage) and `next_levels: array<u32>` (read_write storage).

// Leaves per treelet, fixed per pipeline (`bvh::treelet`; MIN_TREELET_SIZE..=MAX_TREELET).
override TREELET_SIZE: u32;
// 1: the generated `subset_costs()` is the loop form, else written out for TREELET_SIZE
// (`bvh::treelet::dp_unrolled` reads it when it generates the include; the code has no use
// for it).
override TREELET_DP_LOOP: u32 = 0u;
// 1: step 5 is compiled in (a round with a next round: params.next_gamma); 0: a pipeline for the
// treelets of a last round, of the phased rounds and of the overlapped rounds' waves, which holds
// no code for the next round's levels (RADV, treelets_optimize: 240 → 216 registers).
override NEXT_LEVELS: u32 = 1u;

// Whether the treelets compute the next round's levels (step 5). The pipeline is chosen by the same
// test of the round's next γ (`TreeletKernels::get`), so the two agree.
fn has_next_round() -> bool {
    return NEXT_LEVELS != 0u && params.next_gamma != NO_NEXT_ROUND;
}

// Subsets 1 ..= 2^MAX_TREELET - 2 (the full set is never stored).
const DP_SLOTS: u32 = (1u << MAX_TREELET) - 2u;

var<private> dp_cost: array<f32, DP_SLOTS>;

var<private> leaf_node: array<u32, MAX_TREELET>;
var<private> leaf_min: array<vec3<f32>, MAX_TREELET>;
var<private> leaf_max: array<vec3<f32>, MAX_TREELET>;
var<private> leaf_prims: array<u32, MAX_TREELET>;
// The leaves' subtree costs (final: their subtrees were finished before the treelet).
var<private> leaf_cost: array<f32, MAX_TREELET>;
// During the formation: each leaf's children (left, right) and area, -1 for a tree leaf (never
// expanded).
var<private> leaf_children: array<vec2<u32>, MAX_TREELET>;
var<private> leaf_area: array<f32, MAX_TREELET>;
var<private> internal_node: array<u32, MAX_TREELET>;
// The treelet's leaves (treelet_size, or fewer where the formation's depth bound stopped it).
var<private> treelet_leaves: u32;
// The root's primitive count, and the next round's levels of its children before restructuring
// (0 for a child of fewer than next_gamma primitives), for store_root_next_level.
var<private> root_prims: u32;
var<private> root_child_levels: vec2<u32>;

fn subset_cost(s: u32) -> f32 {
    return dp_cost[s - 1u];
}

// A subset of the treelet's leaves: its box and primitive count.
struct SubsetBox {
    min: vec3<f32>,
    max: vec3<f32>,
    prims: u32,
}

// `b` united with the leaves first..=last of subset s, highest first. The loop runs over every
// leaf of the range whatever s holds, so that the leaves' arrays are indexed by the loop alone
// (`i <= last` ends it when i wraps below 0).
fn unite_highest_first(s: u32, first: u32, last: u32, b: SubsetBox) -> SubsetBox {
    var out = b;
    for (var i = last; i >= first && i <= last; i--) {
        let take = ((s >> i) & 1u) != 0u;
        out.min = select(out.min, min(out.min, leaf_min[i]), take);
        out.max = select(out.max, max(out.max, leaf_max[i]), take);
        out.prims += select(0u, leaf_prims[i], take);
    }
    return out;
}

const NO_BOX = SubsetBox(vec3<f32>(F32_MAX), vec3<f32>(-F32_MAX), 0u);

// The box of subset s for the DP's costs: its leaves united highest first (box(S) = box(S without
// its lowest leaf) ∪ its lowest leaf), as the written-out DP unites them (treelet_dp_unrolled.wgsl).
fn dp_subset_box(s: u32) -> SubsetBox {
    return unite_highest_first(s, 0u, MAX_TREELET - 1u, NO_BOX);
}

// The box of subset s for the write-back, united as the team's tables unite it
// (treelet_team.wgsl: leaves 0-3 highest first, leaves 4-7 the same, then the two halves), so
// that lone invocations and teams write the same boxes, also in the sign of a zero. No tables
// here: with them beside the DP's ~127 live costs the DP spilled (README, "Kernel statistics").
fn subset_box(s: u32) -> SubsetBox {
    let low = unite_highest_first(s, 0u, 3u, NO_BOX);
    let high = unite_highest_first(s, 4u, MAX_TREELET - 1u, NO_BOX);
    return SubsetBox(min(low.min, high.min), max(low.max, high.max), low.prims + high.prims);
}

// c(S) of a subset of at least two leaves, of box [lo, hi] and `prims` primitives, whose best
// partition costs `best`.
fn internal_cost(lo: vec3<f32>, hi: vec3<f32>, prims: u32, best: f32) -> f32 {
    return combine_cost(surface_area(lo, hi, params.zero), prims, best);
}

// The same for subset s, its box as the DP unites it.
fn internal_subset_cost(s: u32, best: f32) -> f32 {
    let b = dp_subset_box(s);
    return internal_cost(b.min, b.max, b.prims, best);
}

#include "treelet_dp_unrolled.wgsl"

// The best partition P of s (s has at least two leaves; the costs of its proper subsets are
// stored) and its cost c(P) + c(S\P).
fn best_partition(s: u32) -> vec2<u32> {
    let delta = (s - 1u) & s;
    var p = (0u - delta) & s;
    var best = F32_MAX;
    var best_p = 0u;
    loop {
        let c = subset_cost(p) + subset_cost(s ^ p);
        if c < best {
            best = c;
            best_p = p;
        }
        p = (p - delta) & s;
        if p == 0u {
            break;
        }
    }
    return vec2<u32>(best_p, bitcast<u32>(best));
}

// Makes `node` the treelet's leaf i: its box, children, area, primitive count and cost, from
// loads that go out together (the DP's inputs come with the formation, not one more round trip to
// memory after it); an area of -1 if the formation may not expand it (a tree leaf, or
// `expandable` false). The count and the cost, which the DP reads, are written by selects over
// every leaf, so that no index a lane computes puts them in memory (RADV: the lone DP's latency
// estimate 38249 cycles with `leaf_cost[i] = ...`, 34504 with the selects).
fn take_leaf(i: u32, node: u32, expandable: bool) {
    let n = nodes[node];
    leaf_node[i] = node;
    let prims = prim_counts[node];
    let cost = costs[node];
    for (var t = 0u; t < MAX_TREELET; t++) {
        leaf_prims[t] = select(leaf_prims[t], prims, t == i);
        leaf_cost[t] = select(leaf_cost[t], cost, t == i);
    }
    leaf_min[i] = n.min;
    leaf_max[i] = n.max;
    leaf_children[i] = vec2<u32>(n.left_or_first, n.right_or_count);
    leaf_area[i] = select(-1.0, surface_area(n.min, n.max, params.zero), expandable && (n.right_or_count & LEAF_FLAG) == 0u);
}

// The depth below the root of the formation's leaves: 4 bits per leaf (a treelet of 8 leaves
// reaches 7 levels), a register rather than a private array indexed by the leaf.
fn leaf_depth(depths: u32, i: u32) -> u32 {
    return (depths >> (4u * i)) & 15u;
}

// Steps 1 and 2: the root's cost from its children (final now), stored and returned; the treelet
// below `root` into the private leaf arrays (leaves past `treelet_leaves` empty, their node the
// root's, so that every load of a leaf's node stays in bounds).
fn form_treelet(root: u32) -> f32 {
    let r = nodes[root];
    root_prims = prim_counts[root];
    // Phased rounds (params.phases = P): leaves at most P - 1 levels below the root, a bound a
    // treelet of at most P leaves never reaches.
    let max_depth = select(MAX_TREELET, params.phases - 1u, params.phases != 0u);
    take_leaf(0u, r.left_or_first, 1u < max_depth);
    take_leaf(1u, r.right_or_count, 1u < max_depth);
    // Loaded with the first leaves, so that a treelet that keeps its topology stores its root's
    // next level without a round trip to memory after the DP.
    if has_next_round() {
        root_child_levels = vec2<u32>(
            select(0u, next_levels[r.left_or_first], leaf_prims[0] >= params.next_gamma),
            select(0u, next_levels[r.right_or_count], leaf_prims[1] >= params.next_gamma),
        );
    }
    let current = combine_cost(surface_area(r.min, r.max, params.zero), root_prims, leaf_cost[0] + leaf_cost[1]);
    costs[root] = current;
    internal_node[0] = root;
    var depths = 0x11u;
    treelet_leaves = 2u;
    for (var count = 2u; count < TREELET_SIZE; count++) {
        var best = 0u;
        var best_area = -1.0;
        for (var i = 0u; i < count; i++) {
            if leaf_area[i] > best_area {
                best_area = leaf_area[i];
                best = i;
            }
        }
        if best_area < 0.0 {
            break;
        }
        let depth = leaf_depth(depths, best) + 1u;
        depths += (1u << (4u * best)) + (depth << (4u * count));
        internal_node[count - 1u] = leaf_node[best];
        let children = leaf_children[best];
        take_leaf(best, children.x, depth < max_depth);
        take_leaf(count, children.y, depth < max_depth);
        treelet_leaves = count + 1u;
    }
    for (var i = 0u; i < MAX_TREELET; i++) {
        if i >= treelet_leaves {
            leaf_node[i] = root;
            leaf_min[i] = vec3<f32>(F32_MAX);
            leaf_max[i] = vec3<f32>(-F32_MAX);
            leaf_prims[i] = 0u;
            leaf_cost[i] = 0.0;
        }
    }
    return current;
}

// The set of the treelet's leaves (all but the empty ones).
fn treelet_full_set() -> u32 {
    return (1u << treelet_leaves) - 1u;
}

// Step 4's breadth-first queue: the subsets still to write, entry e going to internal_node[e]
// (entry 0: the full set, the root), `queued` entries so far; per written entry also its primitive
// count and its children, each as a code: leaf i (< MAX_TREELET) or entry j (MAX_TREELET + j)
// (step 5). A variable of the write-back, not of the module: a private variable is zeroed when
// the invocation starts, so its registers would be held through the DP.
struct WriteQueue {
    subsets: array<u32, MAX_TREELET>,
    prims: array<u32, MAX_TREELET>,
    children: array<vec2<u32>, MAX_TREELET>,
}
// Entries the last write-back queued (0 when the treelet kept its topology; the overlapped
// rounds' `finish_entry` reads it).
var<private> queued: u32;

// The code of a write-back's child `part` (a subset of the leaves): the leaf, or the entry it is
// queued as (`queued`).
fn child_code(part: u32, queued: u32) -> u32 {
    return select(MAX_TREELET + queued, firstTrailingBit(part), countOneBits(part) == 1u);
}

// Step 5's input: the next round's level of each treelet leaf of at least next_gamma primitives
// (0 for the others), all loaded at once. The write-back loads them before its searches and
// stores, so that their round trip to memory overlaps those instead of following them (the
// write-back writes no level of a leaf). Zeros without a next round.
fn leaf_next_levels() -> array<u32, MAX_TREELET> {
    var levels: array<u32, MAX_TREELET>;
    if has_next_round() {
        for (var i = 0u; i < MAX_TREELET; i++) {
            let is_root = i < TREELET_SIZE && leaf_prims[i] >= params.next_gamma;
            levels[i] = select(0u, next_levels[leaf_node[min(i, TREELET_SIZE - 1u)]], is_root);
        }
    }
    return levels;
}

// Step 5 after a write-back: the next round's level of each node written, children first, from
// the treelet leaves' levels (`leaf_levels`, leaf_next_levels) and the entries' own; no node data
// is read back. Nothing without a next round (its levels would all be 0, and nothing reads them:
// the last round, the overlapped and the phased rounds).
fn store_next_levels(queue: ptr<function, WriteQueue>, leaf_levels: array<u32, MAX_TREELET>) {
    if !has_next_round() {
        return;
    }
    var level_of: array<u32, 2u * MAX_TREELET>;
    for (var i = 0u; i < MAX_TREELET; i++) {
        level_of[i] = leaf_levels[i];
    }
    for (var e = queued; e > 0u; e--) {
        let entry = e - 1u;
        var level = 0u;
        if (*queue).prims[entry] >= params.next_gamma {
            let children = (*queue).children[entry];
            level = 1u + max(level_of[children.x], level_of[children.y]);
        }
        level_of[MAX_TREELET + entry] = level;
        next_levels[internal_node[entry]] = level;
    }
}

// Step 5 when the treelet keeps its topology: only the root is new to finish (its children were
// finished before it). Nothing without a next round.
fn store_root_next_level(root: u32) {
    if !has_next_round() {
        return;
    }
    var level = 0u;
    if root_prims >= params.next_gamma {
        level = 1u + max(root_child_levels.x, root_child_levels.y);
    }
    next_levels[root] = level;
}

// Step 4, start: the full set goes to the root (internal_node[0]).
fn begin_write_back(queue: ptr<function, WriteQueue>) {
    (*queue).subsets[0] = treelet_full_set();
    queued = 1u;
}

// Step 4 for queue entry `head`: its node gets the children `split` and the rest of its subset
// (a treelet leaf, or the next internal node of the treelet, queued), the box [lo, hi], `prims`
// and `cost`; its count and children are kept for step 5.
fn write_entry(queue: ptr<function, WriteQueue>, head: u32, split: u32, cost: f32, lo: vec3<f32>, hi: vec3<f32>, prims: u32) {
    let s = (*queue).subsets[head];
    let node = internal_node[head];
    let parts = array<u32, 2>(split, s ^ split);
    var child = array<u32, 2>(0u, 0u);
    var code = vec2<u32>(0u);
    for (var k = 0u; k < 2u; k++) {
        let part = parts[k];
        code[k] = child_code(part, queued);
        if countOneBits(part) == 1u {
            child[k] = leaf_node[firstTrailingBit(part)];
        } else {
            child[k] = internal_node[queued];
            (*queue).subsets[queued] = part;
            queued++;
        }
        parents[child[k]] = node;
    }
    nodes[node] = BvhNode(lo, child[0], hi, child[1]);
    prim_counts[node] = prims;
    costs[node] = cost;
    (*queue).prims[head] = prims;
    (*queue).children[head] = code;
}

// Steps 4 and 5: the new topology of the treelet below `root` from the DP's costs (`full_split`:
// the full set's best partition, `full_cost`: its cost).
fn write_back(full_split: u32, full_cost: f32) {
    let leaf_levels = leaf_next_levels();
    var queue: WriteQueue;
    begin_write_back(&queue);
    for (var head = 0u; head < queued; head++) {
        let s = queue.subsets[head];
        var split = full_split;
        var cost = full_cost;
        if head != 0u {
            split = best_partition(s).x;
            cost = subset_cost(s);
        }
        let b = subset_box(s);
        write_entry(&queue, head, split, cost, b.min, b.max, b.prims);
    }
    store_next_levels(&queue, leaf_levels);
}

// Steps 1-5 for the treelet rooted at `root`. A treelet of fewer leaves than treelet_size takes
// its full set's partition from the subsets' costs the DP stored (the empty leaves' subsets are
// computed alongside, and unused); one of 2 leaves has no other topology.
fn optimize_treelet(root: u32) {
    let current = form_treelet(root);
    var best = subset_costs();
    let full = treelet_full_set();
    if treelet_leaves < TREELET_SIZE {
        best = best_partition(full);
    }
    let full_cost = internal_subset_cost(full, bitcast<f32>(best.y));
    if treelet_leaves > 2u && full_cost < current {
        write_back(best.x, full_cost);
    } else {
        store_root_next_level(root);
    }
}
