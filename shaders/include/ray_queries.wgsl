// Batched ray queries, the body of the query kernels (rays_intersect.wgsl: binary BVH,
// rays_intersect_wide.wgsl: wide BVH), which declare the bindings and include their traversal
// (`traverse`) before this file: one invocation per ray, its closest hit (or any hit) written per
// ray, and with COUNT_STEPS its traversal's steps (internal nodes, triangles) after the
// overflow count. Used by tests (against CPU brute force) and by anyone who needs batched ray
// queries.

struct QueryParams {
    ray_count: u32,
    row_pitch: u32,
    // Always 0 (see unfused.wgsl).
    opaque_zero: u32,
    pad: u32,
}

// 1: any hit in the interval, 0: the closest hit; a pipeline each (`trace::rays_intersect`), so
// that the closest-hit traversal holds no any-hit exit (RADV: the wide kernel 84 -> 72 vector
// registers).
override ANY_HIT: u32 = 0u;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= params.ray_count {
        return;
    }
    let ray = rays[i];
    var stack: TraversalStack;
    let result = traverse(ray.origin, ray.dir, ray.t_min, ray.t_max, params.opaque_zero, ANY_HIT != 0u, &stack);
    if result.overflow != 0u {
        atomicAdd(&counters[0], 1u);
    }
    if COUNT_STEPS != 0u {
        atomicStore(&counters[1u + 2u * i], result.steps.x);
        atomicStore(&counters[2u + 2u * i], result.steps.y);
    }
    hits[i] = result.hit;
    if result.hit.tri == MISS {
        hits[i].t = 3.0e38;
    }
}
