// Primitive boxes for the BVH build: one AABB per triangle (the input of LBVH stage 1 when no
// triangle is pre-split; pre-splitting writes several clipped boxes per triangle instead).
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "items.wgsl"

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read_write> prim_boxes: array<Aabb>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= params.count {
        return;
    }
    let t = triangles[i];
    prim_boxes[i] = Aabb(min(t.v0, min(t.v1, t.v2)), 0u, max(t.v0, max(t.v1, t.v2)), 0u);
}
