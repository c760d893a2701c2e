// Scene centroid bounds by parallel reduction (LBVH stage 1, Karras 2012 §3), in one dispatch:
// each workgroup reduces a tile of REDUCE_TILE elements in workgroup memory and adds its box to the
// eight box words with six atomicMax (box_reduce.wgsl): the bounds of the primitive boxes'
// centroids, where the boxes are not the triangles' (pre-split references; triangles_bounds.wgsl
// reduces as it computes them). min/max are exact, so the result is bit-identical to the CPU twin
// in any order.
#include "box_words.wgsl"

struct ReduceParams {
    count: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ReduceParams;
@group(0) @binding(1) var<storage, read> boxes_in: array<Aabb>;
// The box words (box_words.wgsl), zeroed before the dispatch.
@group(0) @binding(2) var<storage, read_write> box_words: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): the kernel reduces min(params.count, count_limit[0])
// items; tiles past them add nothing.
@group(0) @binding(3) var<storage, read> count_limit: array<u32>;

#include "box_reduce.wgsl"

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tile = tile_index(wid, groups);
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(-F32_MAX);
    let count = min(params.count, count_limit[0]);
    for (var k = 0u; k < PER_INVOCATION; k++) {
        let i = tile * REDUCE_TILE + k * WORKGROUP + lid;
        if i < count {
            let c = (boxes_in[i].min + boxes_in[i].max) * 0.5;
            lo = min(lo, c);
            hi = max(hi, c);
        }
    }
    add_to_box_words(lid, lo, hi);
}
