// Treelet round, step 2 per subtree (params.subtree_levels = K > 0): the treelets of levels
// 1 ..= K in one dispatch instead of one per level. nodes_level.wgsl bucketed the cut roots, the
// roots of level K at most whose parent is above K (or that root the tree), each in its level's
// bucket. Their subtrees are disjoint and hold every root of level K at most, each exactly once.
// A workgroup takes subtrees_per_workgroup(l) cut roots of one level l (treelet_round.wgsl; the
// workgroups of level 1's cut roots first, then level 2's, ...), lists their roots breadth first
// (a root's child roots one depth below it: at most 2^l - 1 roots per subtree, as a root of level
// l has at most two child roots, each of a lower level, and at most l depths) and optimizes them a
// depth at a time, the deepest first, one treelet per invocation (treelet_dp.wgsl), with a
// workgroup barrier between depths where the levels take a dispatch each. A root is optimized
// after every root below it and no two roots of one depth share a node (neither is below the
// other), so the tree is the one of the paper's bottom-up order (the CPU
// twin `WorkingTree::optimize_round`; a treelet changes no node above its root, so the deeper
// depths leave the roots listed where they were). The levels above K follow as without subtrees
// (treelets_optimize.wgsl, treelets_climb.wgsl). Node data is only shared within the workgroup:
// storageBarriers order it.
#include "treelet_roots.wgsl"
// The next round's level of each node a treelet finishes (treelet_dp.wgsl).
@group(0) @binding(7) var<storage, read_write> next_levels: array<u32>;

#include "treelet_dp.wgsl"

// The subtrees' roots, breadth first.
var<workgroup> subtree_roots: array<u32, SUBTREE_LIST>;
var<workgroup> listed: atomic<u32>;
// The workgroup's cut roots: how many and where they start in the roots buffer; the roots listed
// after a depth (workgroup-uniform copies).
var<workgroup> cut_roots: u32;
var<workgroup> cut_first: u32;
var<workgroup> listed_after: u32;

@compute @workgroup_size(SUBTREE_WORKGROUP)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    if lid == 0u {
        // The workgroups of the levels' cut roots one level after another, as nodes_level.wgsl
        // counted them.
        var group = wid.x + wid.y * groups.x;
        cut_roots = 0u;
        for (var level = 1u; level <= params.subtree_levels; level++) {
            let count = schedule[level - 1u];
            let per = subtrees_per_workgroup(level);
            let level_groups = (count + per - 1u) / per;
            if group < level_groups {
                cut_roots = min(per, count - group * per);
                cut_first = level_start(level) + group * per;
                break;
            }
            group -= level_groups;
        }
    }
    // Depth 0: the workgroup's cut roots.
    var end = workgroupUniformLoad(&cut_roots);
    if end == 0u {
        return;
    }
    let first = cut_first;
    for (var i = lid; i < end; i += SUBTREE_WORKGROUP) {
        subtree_roots[i] = roots[first + i];
    }
    if lid == 0u {
        atomicStore(&listed, end);
    }
    // Depth d's roots are subtree_roots[depth_start[d] .. depth_start[d + 1]], d < depths.
    var depth_start: array<u32, MAX_SUBTREE_LEVELS + 1u>;
    var depths = 0u;
    var begin = 0u;
    loop {
        workgroupBarrier();
        // The child roots of this depth's roots: the next depth.
        for (var i = begin + lid; i < end; i += SUBTREE_WORKGROUP) {
            let root = nodes[subtree_roots[i]];
            for (var side = 0u; side < 2u; side++) {
                let child = select(root.left_or_first, root.right_or_count, side == 1u);
                if prim_counts[child] >= params.gamma {
                    subtree_roots[atomicAdd(&listed, 1u)] = child;
                }
            }
        }
        workgroupBarrier();
        if lid == 0u {
            listed_after = atomicLoad(&listed);
        }
        let next_end = workgroupUniformLoad(&listed_after);
        depths++;
        depth_start[depths] = end;
        if next_end == end {
            break;
        }
        begin = end;
        end = next_end;
    }
    // The deepest depth first; each depth's node data is stored before the depth above reads it.
    for (var d = depths; d > 0u; d--) {
        for (var i = depth_start[d - 1u] + lid; i < depth_start[d]; i += SUBTREE_WORKGROUP) {
            optimize_treelet(subtree_roots[i]);
        }
        storageBarrier();
    }
}
