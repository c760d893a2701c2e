// Bindings 0-9 of the kernels that optimize the overlapped rounds' treelets (waves_optimize.wgsl,
// waves_climb.wgsl): the rounds' parameters, the working tree (nodes, parent links, primitive
// counts, SAH costs), the next round's levels, which the overlapped rounds do not use
// (params.next_gamma is NO_NEXT_ROUND: treelet_dp.wgsl stores none), and the waves' state
// (treelet_waves.wgsl: each node's wave done per round, the candidates' waves, the lists, the
// counts and tickets).
#include "bvh_node.wgsl"
#include "treelet_round.wgsl"

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read_write> parents: array<u32>;
@group(0) @binding(3) var<storage, read_write> prim_counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> costs: array<f32>;
@group(0) @binding(5) var<storage, read_write> next_levels: array<u32>;
@group(0) @binding(6) var<storage, read_write> done: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> candidate_waves: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> lists: array<u32>;
@group(0) @binding(9) var<storage, read_write> wave_state: array<atomic<u32>>;
