// What both traversals share (binary: bvh_traverse.wgsl, wide: wide_traverse.wgsl): the ray as
// the box test needs it, the robust slab test and the result type.
#include "bvh_node.wgsl"
#include "ray_triangle.wgsl"

const NO_ENTRY: f32 = 3.0e38;

// The ray as the box test needs it.
struct BoxRay {
    origin: vec3<f32>,
    // 1 / direction, with components below 1e-30 replaced by 1e-30 (no 0 * inf = NaN).
    inv_dir: vec3<f32>,
    // 3e38 on axes the ray does not move along (|d| < 1e-30), 0 elsewhere: such an axis bounds
    // nothing (its slab becomes (-inf, inf)), so a ray lying in the plane of a flat box's face
    // still enters the box. Boxes beside the ray on that axis are then entered too: extra work on
    // such rays, never a lost hit.
    slab_pad: vec3<f32>,
}

fn box_ray(origin: vec3<f32>, dir: vec3<f32>) -> BoxRay {
    let flat = abs(dir) < vec3<f32>(1e-30);
    let safe_dir = select(dir, vec3<f32>(1e-30), flat);
    return BoxRay(origin, 1.0 / safe_dir, select(vec3<f32>(0.0), vec3<f32>(3.0e38), flat));
}

// Entry distance of the ray into the box, or NO_ENTRY if it misses within [t_min, t_max].
// The exit distance is widened so that rounding never culls a box the ray touches (Ize 2013,
// "Robust BVH Ray Traversal"): each slab distance carries a subtraction, a reciprocal (2.5 ulp
// allowed by Vulkan) and a product, ~7 unit roundoffs, and enter <= exit compares two of them;
// 1 + 2^-19 covers that with room to spare.
fn box_entry(bmin: vec3<f32>, bmax: vec3<f32>, ray: BoxRay, t_min: f32, t_max: f32) -> f32 {
    let t0 = (bmin - ray.origin) * ray.inv_dir;
    let t1 = (bmax - ray.origin) * ray.inv_dir;
    let near = min(t0, t1) - ray.slab_pad;
    let far = max(t0, t1) + ray.slab_pad;
    let enter = max(max(near.x, near.y), max(near.z, t_min));
    let exit = min(min(far.x, far.y), min(far.z, t_max)) * BOX_EXIT_SLACK;
    return select(NO_ENTRY, enter, enter <= exit);
}

struct TraceResult {
    hit: Hit,
    // 1 when the traversal stack overflowed (the result may have missed geometry).
    overflow: u32,
    // The hit triangle's material (0 on a miss), kept from the triangle test's loads: a path
    // tracer's load of the material then waits for no load of the triangle.
    material: u32,
    // The traversal's steps: the internal nodes whose children's boxes it tested (binary: two
    // boxes, wide: eight) and the triangles it tested. Kept in registers; a kernel writes them
    // out only with COUNT_STEPS, so that without it the compiler drops the counting.
    steps: vec2<u32>,
}

// 1: the kernel writes out its traversals' steps (`TraceResult::steps`; `trace::TraversalSteps`),
// 0: a pipeline that counts nothing.
override COUNT_STEPS: u32 = 0u;

