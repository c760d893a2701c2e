// Treelet round, step 3: the treelets of one level (params.level <= level_dispatches), bucketed by
// roots_bucket.wgsl, one invocation each (treelet_dp.wgsl). Dispatched indirectly with the
// level's workgroup count; the dispatches of the levels below have finished, so node data is read
// with plain loads.
#include "bvh_node.wgsl"
#include "treelet_round.wgsl"

const WORKGROUP: u32 = 32u;

@group(0) @binding(0) var<uniform> params: RoundParams;
@group(0) @binding(1) var<storage, read_write> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read_write> parents: array<u32>;
@group(0) @binding(3) var<storage, read_write> prim_counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> costs: array<f32>;
@group(0) @binding(5) var<storage, read> schedule: array<u32>;
@group(0) @binding(6) var<storage, read> roots: array<u32>;

#include "treelet_dp.wgsl"

@compute @workgroup_size(WORKGROUP)
fn main(
    @builtin(global_invocation_id) gid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let i = gid.x + gid.y * groups.x * WORKGROUP;
    var first = 0u;
    for (var below = 1u; below < params.level; below++) {
        first += schedule[below - 1u];
    }
    if i < schedule[params.level - 1u] {
        optimize_treelet(roots[first + i]);
    }
}
