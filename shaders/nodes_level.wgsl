// Treelet round, step 1 (Karras & Aila 2013, §4 "processing nodes bottom-up"): the schedule. A
// bottom-up climb (one invocation per leaf, the second arrival at a node goes on, as in
// lbvh_climb.wgsl) gives every node its primitive count N and SAH cost
//     C(n) = min(Ci·A(n) + C(left) + C(right),  Ct·A(n)·N(n) if N(n) <= max leaf size)
// and its level: 0 below gamma primitives, else one more than the highest level of its children.
// Nodes with N >= gamma root a treelet; two roots of one level are never ancestor and
// descendant, so each level's treelets are disjoint and can be optimized at once, after the
// levels below (treelets_optimize.wgsl, treelets_climb.wgsl). Costs of nodes below gamma are
// final here; a root's cost is recomputed when its level is processed. The roots of each level
// up to level_dispatches + 1 go into that level's bucket as they are found (treelet_round.wgsl:
// a counter per level in the schedule buffer, the level's slots of `roots`; a workgroup reserves
// the slots of the roots it found together, one atomic per level), and each workgroup whose
// slots need more workgroups of a level's dispatch raises its indirect arguments to cover them
// (`atomicMax`: the schedule is zero at the round's start; a workgroup per treelet below
// params.team_below treelets, else per 32 treelets, treelets_optimize.wgsl; `raise_arguments`),
// so no workgroup waits for the others and none finishes the schedule (as roots_phase.wgsl).
// With subtrees (params.subtree_levels = K > 0) the buckets of levels 1 ..= K hold only the cut
// roots of their level (of level K at most, whose parent is above K, or the tree's root), and
// level 1's arguments count the workgroups of all K (subtrees_optimize.wgsl), summed in the
// schedule.
// The first round's climb also builds the LBVH over the sorted keys, as lbvh_climb.wgsl does for a
// plain LBVH: its hierarchy (Karras 2012's radix tree and layout, found bottom-up as in Apetrei
// 2014: radix_climb.wgsl) with the parent links, and its boxes (Karras 2012 §4), each leaf's from
// its primitive, each internal node's from its children. After the first round (levels_only),
// boxes, counts, costs and the roots' levels of the new gamma are those the treelet kernels of
// the round before left (treelet_dp.wgsl, step 5): one invocation per internal node only buckets
// the roots, without a climb, and zeroes the node's arrival counter for treelets_climb.wgsl (the
// first round's climb leaves every arrival word zero).
// The node data this climb writes is shared across workgroups, so it all goes through atomics
// (node words, node_words.wgsl), ordered around the arrivals by radix_climb.wgsl's `climb`, which
// calls `finish_parent` below for each parent.
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "treelet_round.wgsl"

// Invocations per workgroup: 64, or the device's climb width (`Kernel::climb`; 8 on CPU devices).
override WORKGROUP_WIDTH: u32 = 64u;

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read_write> node_words: array<atomic<u32>>;
@group(0) @binding(2) var<storage, read_write> parents: array<u32>;
@group(0) @binding(3) var<storage, read_write> prim_counts: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> costs: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> levels: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> arrivals: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> schedule: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): the tree has min(params.count, count_limit[0]) leaves.
@group(0) @binding(8) var<storage, read> count_limit: array<u32>;
// First round: the primitive boxes and the primitive of each leaf (the sorted order).
@group(0) @binding(9) var<storage, read> prim_boxes: array<Aabb>;
@group(0) @binding(10) var<storage, read> order: array<u32>;
// The roots of each bucketed level, in its slots (level_start).
@group(0) @binding(11) var<storage, read_write> roots: array<u32>;
// First round: the sorted keys (low word first), from which the climb finds the hierarchy.
@group(0) @binding(12) var<storage, read> keys: array<vec2<u32>>;

#include "node_words.wgsl"
#include "treelet_arguments.wgsl"
#include "radix_climb.wgsl"

fn is_root(node: u32) -> bool {
    return atomicLoad(&prim_counts[node]) >= params.gamma;
}

// The level a parent takes from `child` (0: no root).
fn child_level(child: u32) -> u32 {
    return select(0u, atomicLoad(&levels[child]), is_root(child));
}

// The roots of each bucketed level this workgroup found (in the first round's climb, or in a
// later round's pass), and where their slots start in the level's bucket.
var<workgroup> workgroup_roots: array<atomic<u32>, MAX_LEVEL_DISPATCHES + 1u>;
var<workgroup> workgroup_slots: array<u32, MAX_LEVEL_DISPATCHES + 1u>;

// The bucket of a root of level `level` (0: no root) that is no cut root: its level's, if that
// level is bucketed (1 ..= level_dispatches + 1, those up to params.subtree_levels excepted); 0:
// none.
fn level_bucket(level: u32) -> u32 {
    let bucketed = level > params.subtree_levels && level <= params.level_dispatches + 1u;
    return select(0u, level, bucketed);
}

// With subtrees (params.subtree_levels = K > 0), the bucket of a root of level `level` (0: no
// root) whose parent is above K: its level's if it is a cut root (of level K at most), else none.
fn cut_bucket(level: u32) -> u32 {
    return select(0u, level, level <= params.subtree_levels);
}

// Per bucketed level, the end of the slots this workgroup's roots took one at a time
// (`bucket_alone`; 0: none), and with subtrees, the subtrees' workgroups that the workgroup's
// slots of levels 1 ..= K newly need (`raise_arguments`).
var<workgroup> alone_ends: array<atomic<u32>, MAX_LEVEL_DISPATCHES + 1u>;
var<workgroup> subtree_groups_added: atomic<u32>;

// Raises the arguments of level `level`'s dispatch (levels 1 ..= params.level_dispatches; the
// one above them is climbed) for this workgroup's slots there: those it took together, from
// `before` to `after`, and those its roots took one at a time, up to `alone_end` (0: none). Slots
// taken together raise them where their count needs other workgroups than the count before them;
// slots taken alone, for the last one's count. So the final count, or one that needs as many
// workgroups, has raised them: going down from the final count, the slots taken together that
// raised nothing reach a count that raised them, as their workgroups' other slots lie elsewhere.
// Each word ends as the most any count raised it to, whose x times y covers the final count (a
// dispatch of teams that turns lone past params.team_below keeps the teams' larger grid, whose
// extra workgroups find no treelet). With subtrees, a level up to K adds the workgroups its
// slots taken together newly need to the workgroup's sum instead (`raise_subtree_arguments`).
fn raise_arguments(level: u32, before: u32, after: u32, alone_end: u32) {
    if level > params.level_dispatches {
        return;
    }
    if level <= params.subtree_levels {
        let per = subtrees_per_workgroup(level);
        let added = (after + per - 1u) / per - (before + per - 1u) / per;
        if added != 0u {
            atomicAdd(&subtree_groups_added, added);
        }
        return;
    }
    let needs_more = optimize_workgroups(after) != optimize_workgroups(before);
    let count = max(select(0u, after, needs_more), alone_end);
    if count != 0u {
        raise_level_arguments(level, optimize_workgroups(count));
    }
}

// With subtrees, level 1's arguments count the workgroups of every level's cut roots
// (subtrees_optimize.wgsl): the workgroup adds those its slots newly need to their sum in the
// schedule and raises level 1's arguments to the sum. Slots taken together add ⌈end / per⌉ −
// ⌈start / per⌉ for their level, a slot taken alone one (at least its share), so the additions
// add up to at least the levels' ⌈count / per⌉ (extra workgroups find no cut roots), and the last
// to add raises the arguments for the final sum.
fn raise_subtree_arguments() {
    let added = atomicLoad(&subtree_groups_added);
    if added != 0u {
        raise_level_arguments(1u, atomicAdd(&schedule[SCHEDULE_SUBTREE_GROUPS], added) + added);
    }
}

// Once the workgroup has counted its roots per level: reserves their slots, one device atomic
// per level (between two barriers), and raises the levels' arguments.
fn reserve_workgroup_slots(lid: u32) {
    workgroupBarrier();
    for (var l = lid; l <= params.level_dispatches; l += WORKGROUP_WIDTH) {
        let count = atomicLoad(&workgroup_roots[l]);
        var first = 0u;
        if count != 0u {
            first = atomicAdd(&schedule[l], count);
            workgroup_slots[l] = first;
        }
        raise_arguments(l + 1u, first, first + count, atomicLoad(&alone_ends[l]));
    }
    workgroupBarrier();
    if lid == 0u {
        raise_subtree_arguments();
    }
}

// Puts the root `node` into bucket `bucket` (level_bucket, cut_bucket; 0: none): the workgroup
// counts its roots per bucket and reserves their slots with one device atomic per bucket, not one
// per root on the bucket's word (which a GPU serializes). Every invocation of the workgroup calls
// it (uniform control flow).
fn bucket_together(node: u32, bucket: u32, lid: u32) {
    var rank = 0u;
    if bucket != 0u {
        rank = atomicAdd(&workgroup_roots[bucket - 1u], 1u);
    }
    reserve_workgroup_slots(lid);
    if bucket != 0u {
        roots[level_start(bucket) + workgroup_slots[bucket - 1u] + rank] = node;
    }
}

// The first round's roots of bucketed levels and its cut roots, queued by the workgroup during its
// climb (node, bucket, rank in the bucket) and bucketed together after it; a root past the
// queue's room is bucketed on its own (`bucket_alone`). A workgroup finishes about one node per
// invocation, plus the climbs above its leaves: a queue of two per invocation holds most of a
// workgroup's roots (the rest, from the long climbs near the top, take an atomic each; CPU
// devices' 8-wide workgroups use both paths).
override ROOT_QUEUE: u32 = 2u * WORKGROUP_WIDTH;
var<workgroup> root_queue: array<vec3<u32>, ROOT_QUEUE>;
var<workgroup> queued_roots: atomic<u32>;
var<workgroup> queue_length: u32;

// Adds the root `node` to bucket `bucket` (>= 1), with a device atomic of its own; the workgroup
// raises the bucket's arguments for it after the climb (`reserve_workgroup_slots`).
fn bucket_alone(node: u32, bucket: u32) {
    let slot = atomicAdd(&schedule[bucket - 1u], 1u);
    roots[level_start(bucket) + slot] = node;
    atomicMax(&alone_ends[bucket - 1u], slot + 1u);
    if bucket <= params.subtree_levels {
        atomicAdd(&subtree_groups_added, 1u);
    }
}

// Queues the root `node` for bucket `bucket` (0: none) for `bucket_queue`.
fn queue_root(node: u32, bucket: u32) {
    if bucket == 0u {
        return;
    }
    let at = atomicAdd(&queued_roots, 1u);
    if at < ROOT_QUEUE {
        root_queue[at] = vec3<u32>(node, bucket, 0u);
    } else {
        bucket_alone(node, bucket);
    }
}

// After the climb: the queued roots into their buckets, one device atomic per level for the
// workgroup. Call from uniform control flow.
fn bucket_queue(lid: u32) {
    workgroupBarrier();
    if lid == 0u {
        queue_length = min(atomicLoad(&queued_roots), ROOT_QUEUE);
    }
    let length = workgroupUniformLoad(&queue_length);
    for (var i = lid; i < length; i += WORKGROUP_WIDTH) {
        root_queue[i].z = atomicAdd(&workgroup_roots[root_queue[i].y - 1u], 1u);
    }
    reserve_workgroup_slots(lid);
    for (var i = lid; i < length; i += WORKGROUP_WIDTH) {
        let root = root_queue[i];
        roots[level_start(root.y) + workgroup_slots[root.y - 1u] + root.z] = root.x;
    }
}

// A later round's schedule: internal node j (if it is one) zeroes its arrival word and buckets
// itself if it roots a treelet (node 0 roots the tree; a root's parent roots a treelet too, so
// its level is this round's). Call from uniform control flow.
fn bucket_internal_node(j: u32, n: u32, lid: u32) {
    var bucket = 0u;
    if j + 1u < n {
        atomicStore(&arrivals[j], 0u);
        if is_root(j) {
            let level = atomicLoad(&levels[j]);
            bucket = level_bucket(level);
            // Only with subtrees: the parent's level is one more dependent load.
            if level <= params.subtree_levels {
                if j == 0u || atomicLoad(&levels[parents[j]]) > params.subtree_levels {
                    bucket = cut_bucket(level);
                }
            }
        }
    }
    bucket_together(j, bucket, lid);
}

// The climbing node, its count, cost and level (what it stored), carried up the climb: only the
// sibling's are loaded.
var<private> climbing_node: u32;
var<private> climbing_prims: u32;
var<private> climbing_cost: f32;
var<private> climbing_level: u32;

// The first round's climb: a parent's count, cost and level from its children (emit_parent
// stored its children, links and box), and its bucket if it roots a treelet; with subtrees, a
// parent above their levels buckets its children that are cut roots, and the tree's root is one
// if it is not above them.
fn finish_parent(p: EmittedParent) {
    let node = p.range.node;
    let other = p.sibling;
    let prims = climbing_prims + atomicLoad(&prim_counts[other]);
    let children = climbing_cost + bitcast<f32>(atomicLoad(&costs[other]));
    let cost = combine_cost(surface_area(p.lo, p.hi, params.zero), prims, children);
    atomicStore(&prim_counts[node], prims);
    atomicStore(&costs[node], bitcast<u32>(cost));
    var level = 0u;
    if prims >= params.gamma {
        let own_level = select(0u, climbing_level, climbing_prims >= params.gamma);
        let other_level = child_level(other);
        level = max(own_level, other_level) + 1u;
        if level > params.subtree_levels {
            queue_root(node, level_bucket(level));
            queue_root(climbing_node, cut_bucket(own_level));
            queue_root(other, cut_bucket(other_level));
        } else if node == 0u {
            queue_root(node, level);
        }
    }
    atomicStore(&levels[node], level);
    climbing_node = node;
    climbing_prims = prims;
    climbing_cost = cost;
    climbing_level = level;
}

@compute @workgroup_size(WORKGROUP_WIDTH)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(local_invocation_index) lid: u32,
) {
    let j = gid.x + gid.y * params.row_pitch;
    let n = min(params.count, count_limit[0]);
    leaf_count = n;
    var leaf = RangeNode(0u, 0u, 0u, 0u, 0u, false);
    var leaf_box: Aabb;
    let has_leaf = params.levels_only == 0u && j < n;
    if params.levels_only != 0u {
        // Invocation j: internal node j, whose level the round before computed; no climb.
        bucket_internal_node(j, n, lid);
    } else if has_leaf {
        leaf_box = prim_boxes[order[j]];
        leaf = emit_leaf(j, leaf_box);
        climbing_node = leaf.node;
        climbing_prims = 1u;
        climbing_cost = params.ct * surface_area(leaf_box.min, leaf_box.max, params.zero);
        climbing_level = 0u;
        atomicStore(&prim_counts[leaf.node], climbing_prims);
        atomicStore(&costs[leaf.node], bitcast<u32>(climbing_cost));
        atomicStore(&levels[leaf.node], climbing_level);
    }
    // Uniform control flow (params), so the climb's barriers stay valid; the later rounds'
    // workgroups skip them.
    if params.levels_only == 0u {
        climb(leaf, leaf_box, has_leaf, lid);
        bucket_queue(lid);
    }
}
