// What the kernels of one treelet restructuring round share (Karras & Aila 2013, §3-4): their
// parameters, the schedule buffer's layout, a node's surface area and its SAH cost. Twins:
// `RoundParams` (src/bvh/treelet/rounds.rs), `surface_area` and `CostModel::combine`
// (src/bvh/treelet/dp.rs).

#include "constants.wgsl"
#include "unfused.wgsl"

struct RoundParams {
    // Leaves of the working tree (at most; see count_limit): it has 2n - 1 nodes.
    count: u32,
    row_pitch: u32,
    // Nodes with at least gamma primitives root a treelet.
    gamma: u32,
    max_leaf_size: u32,
    ci: f32,
    ct: f32,
    // Always 0 (see unfused.wgsl).
    zero: u32,
    // Levels processed by one dispatch each (treelets_optimize); the levels above them are
    // processed by treelets_climb.
    level_dispatches: u32,
    // The level a treelets_optimize dispatch processes (1 = treelets without treelets below).
    level: u32,
    // 1 after the first round: counts and costs are still those of the tree (the treelet kernels
    // rewrite both consistently), and so are the levels of the new gamma (the treelet kernels of
    // the round before computed them), so nodes_level only counts the roots per level.
    levels_only: u32,
    // A level of fewer treelets is optimized by teams of invocations, a treelet per team: the
    // dispatched levels' (or waves') threshold in nodes_level.wgsl, treelets_optimize.wgsl,
    // waves_find.wgsl and waves_optimize.wgsl, the climb's in treelets_climb.wgsl and
    // waves_climb.wgsl (`RoundSchedule::climb_team_below`).
    team_below: u32,
    // gamma of the next round (NO_NEXT_ROUND: none), whose levels the treelet kernels compute.
    next_gamma: u32,
    // level_start(level), computed by the CPU (treelets_optimize: the level dispatched;
    // treelets_climb: level_dispatches + 1).
    level_first: u32,
    // The overlapped rounds (treelet_waves.wgsl): how many, the reach and the wave a dispatch
    // processes (the first for the climb); 0 elsewhere.
    rounds: u32,
    reach: u32,
    wave: u32,
    // K > 0: the treelets of levels 1 ..= K are optimized per subtree, a few subtrees per
    // workgroup (subtrees_optimize.wgsl), whose roots (the cut roots: of level K at most, their
    // parent above K or none) take the buckets of their levels (the only roots there), and level
    // 1's indirect arguments count the workgroups of all K. 0: by level.
    subtree_levels: u32,
    // The most cut roots of level l a workgroup of subtrees_optimize.wgsl takes besides its
    // list's bound: subtree_width >> (l - 1), at least 1 (`subtrees_per_workgroup`).
    subtree_width: u32,
    // Phased rounds (roots_phase.wgsl): the phases per round and the depth residue of this
    // phase's roots; 0 elsewhere.
    phases: u32,
    residue: u32,
}

// `RoundParams::next_gamma` of a round without a next one (the last, the overlapped and the
// phased rounds).
const NO_NEXT_ROUND: u32 = 0xffffffffu;

// The schedule buffer (u32 words): per level L = 1 ..= MAX_LEVEL_DISPATCHES + 1, the number of
// treelet roots at L bucketed so far (word L - 1); with subtrees, the workgroups of
// subtrees_optimize.wgsl counted so far (nodes_level.wgsl); then the indirect dispatch arguments
// (x, y, z) of each level's treelets_optimize dispatch.
const SCHEDULE_SUBTREE_GROUPS: u32 = MAX_LEVEL_DISPATCHES + 1u;
const SCHEDULE_ARGS: u32 = MAX_LEVEL_DISPATCHES + 2u;

// Invocations per workgroup of treelets_optimize.wgsl.
const OPTIMIZE_WORKGROUP: u32 = 32u;

// Workgroups of a treelets_optimize dispatch over `treelets` treelets: one per OPTIMIZE_WORKGROUP
// treelets, or one per treelet (its team) where they are fewer than params.team_below.
fn optimize_workgroups(treelets: u32) -> u32 {
    let per_group = select(OPTIMIZE_WORKGROUP, 1u, treelets < params.team_below);
    return (treelets + per_group - 1u) / per_group;
}

// Workgroups one row of a dispatch holds at most.
const MAX_WORKGROUPS_X: u32 = 65535u;

// The indirect arguments (x, y, z) of a dispatch of `groups` workgroups: rows of at most
// MAX_WORKGROUPS_X (the treelet kernels number a workgroup wid.x + wid.y · x and skip those past
// their count).
fn dispatch_args(groups: u32) -> vec3<u32> {
    let y = (groups + MAX_WORKGROUPS_X - 1u) / MAX_WORKGROUPS_X;
    return vec3<u32>(select(0u, (groups + y - 1u) / max(y, 1u), y > 0u), y, 1u);
}

// First slot of level `level`'s roots in the roots buffer (twin: `level_start` in
// src/bvh/treelet/rounds.rs). Level l has ⌊count / (gamma + l - 1)⌋ slots: the roots of a level
// are disjoint subtrees, and a root of level l holds at least gamma + l - 1 leaves (gamma, and
// one more than its child of level l - 1).
fn level_start(level: u32) -> u32 {
    var first = 0u;
    for (var l = 1u; l < level; l++) {
        first += params.count / (params.gamma + l - 1u);
    }
    return first;
}

// Invocations per workgroup of subtrees_optimize.wgsl.
const SUBTREE_WORKGROUP: u32 = 32u;

// Subtrees per workgroup of subtrees_optimize.wgsl whose cut roots are of level `level`: as many
// as its list holds when each has the most roots, 2^level - 1, at most one per invocation, and
// at most params.subtree_width >> (level - 1) (at least one): a subtree of level l has up to
// 2^(l - 1) roots at its lowest depth, so a width of 32 keeps about one lowest depth per
// invocation (the workgroup's steps about its depths: latency) and a width of SUBTREE_LIST or
// more fills the list (fewer idle invocations in the top depths: throughput).
fn subtrees_per_workgroup(level: u32) -> u32 {
    let bound = min(SUBTREE_LIST / ((1u << level) - 1u), SUBTREE_WORKGROUP);
    return min(bound, max(params.subtree_width >> (level - 1u), 1u));
}

// Cost of a node of area a and n primitives whose children cost `children` in total:
// min(Ci·a + children, Ct·a·n where a leaf of n primitives is allowed).
fn combine_cost(a: f32, n: u32, children: f32) -> f32 {
    var c = params.ci * a + children;
    if n <= params.max_leaf_size {
        c = min(c, params.ct * a * f32(n));
    }
    return c;
}
