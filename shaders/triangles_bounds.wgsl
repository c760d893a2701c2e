// The triangles' boxes reduced to one box (box_reduce.wgsl), in one dispatch: with
// params.lbvh_input = 1, the primitive boxes of the BVH build, one AABB per triangle (the input of
// LBVH stage 1 when no triangle is pre-split; pre-splitting writes several clipped boxes per
// triangle instead), and the bounds of their centroids, which the LBVH's Morton grid spans; with
// 0, only the scene box, which pre-splitting's grid spans. Each workgroup takes a tile of
// REDUCE_TILE triangles.
#include "bvh_node.wgsl"
#include "box_words.wgsl"

// Rust twin: `TriangleBoundsParams` (src/bvh/lbvh/triangles_bounds.rs).
struct TriangleBoundsParams {
    count: u32,
    // 1: write the boxes and reduce their centroids, 0: reduce the boxes.
    lbvh_input: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: TriangleBoundsParams;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
// LBVH input only (else a placeholder).
@group(0) @binding(2) var<storage, read_write> prim_boxes: array<Aabb>;
// The box words (box_words.wgsl), zeroed before the dispatch.
@group(0) @binding(3) var<storage, read_write> box_words: array<atomic<u32>>;

#include "box_reduce.wgsl"

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tile = tile_index(wid, groups);
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(-F32_MAX);
    for (var k = 0u; k < PER_INVOCATION; k++) {
        let i = tile * REDUCE_TILE + k * WORKGROUP + lid;
        if i < params.count {
            let t = triangles[i];
            let box_min = min(t.v0, min(t.v1, t.v2));
            let box_max = max(t.v0, max(t.v1, t.v2));
            if params.lbvh_input != 0u {
                prim_boxes[i] = Aabb(box_min, 0u, box_max, 0u);
                let c = (box_min + box_max) * 0.5;
                lo = min(lo, c);
                hi = max(hi, c);
            } else {
                lo = min(lo, box_min);
                hi = max(hi, box_max);
            }
        }
    }
    add_to_box_words(lid, lo, hi);
}
