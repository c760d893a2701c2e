// Bindings 0-6 of the kernels that optimize a round's bucketed treelet roots
// (treelets_optimize.wgsl, subtrees_optimize.wgsl, treelets_climb.wgsl): the round's parameters,
// the working tree (nodes, parent links, primitive counts, SAH costs), the schedule (roots per
// bucket, nodes_level.wgsl) and the roots in their buckets' slots (`level_start`).
#include "bvh_node.wgsl"
#include "treelet_round.wgsl"

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read_write> parents: array<u32>;
@group(0) @binding(3) var<storage, read_write> prim_counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> costs: array<f32>;
@group(0) @binding(5) var<storage, read> schedule: array<u32>;
@group(0) @binding(6) var<storage, read> roots: array<u32>;
