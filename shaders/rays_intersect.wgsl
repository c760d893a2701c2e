// Ray queries through the binary BVH: ray_queries.wgsl over the traversal of bvh_traverse.wgsl.
#include "bvh_traverse.wgsl"
#include "ray_queries.wgsl"

@group(0) @binding(0) var<uniform> params: QueryParams;
@group(0) @binding(1) var<storage, read> triangles: array<vec4<f32>>; // Triangle, three words each
@group(0) @binding(2) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(3) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(4) var<storage, read> rays: array<Ray>;
@group(0) @binding(5) var<storage, read_write> hits: array<Hit>;
// [0]: stack overflows; with COUNT_STEPS, [1 + 2 i] and [2 + 2 i]: ray i's steps
@group(0) @binding(6) var<storage, read_write> counters: array<atomic<u32>>;
