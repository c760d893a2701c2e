// Ray queries through the compressed wide BVH (rays_intersect.wgsl through the binary one): one
// invocation per ray, its closest hit (or any hit) written per ray.
// Used by tests (against CPU brute force) and by anyone who needs batched ray queries.
#include "wide_traverse.wgsl"

struct QueryParams {
    ray_count: u32,
    row_pitch: u32,
    // Always 0 (see `opaque` in ray_triangle.wgsl).
    opaque_zero: u32,
    // 1: any hit in the interval, 0: the closest hit.
    any_hit: u32,
}

@group(0) @binding(0) var<uniform> params: QueryParams;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read> wide_nodes: array<WideNode>;
@group(0) @binding(3) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(4) var<storage, read> rays: array<Ray>;
@group(0) @binding(5) var<storage, read_write> hits: array<Hit>;
// [0]: stack overflows
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= params.ray_count {
        return;
    }
    let ray = rays[i];
    let result = traverse(ray.origin, ray.dir, ray.t_min, ray.t_max, params.opaque_zero, params.any_hit != 0u);
    if result.overflow != 0u {
        atomicAdd(&counters[0], 1u);
    }
    hits[i] = result.hit;
    if result.hit.tri == MISS {
        hits[i].t = 3.0e38;
    }
}
