// BVH traversal with a per-invocation stack (children tested together, nearer first): closest hit
// (`trace_closest`), or any hit (`trace_any`, for shadow rays: stops at the first leaf hit), with
// the watertight triangle test. The including kernel declares the storage arrays `nodes`,
// `prim_indices` and `triangles`, and passes a zero from a uniform (`opaque_zero`, see
// ray_triangle.wgsl). CPU twin: `Bvh::closest_hit` / `Bvh::any_hit` (src/bvh/traverse.rs).
#include "bvh_node.wgsl"
#include "ray_triangle.wgsl"

const STACK_SIZE: u32 = 64u;
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
}

fn trace_closest(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, opaque_zero: u32) -> TraceResult {
    return traverse(origin, dir, t_min, t_max, opaque_zero, false);
}

// Some hit in [t_min, t_max] (not necessarily the closest), or MISS.
fn trace_any(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, opaque_zero: u32) -> TraceResult {
    return traverse(origin, dir, t_min, t_max, opaque_zero, true);
}

fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, opaque_zero: u32, any_hit: bool) -> TraceResult {
    var best = Hit(t_max, MISS, 0.0, 0.0);
    let test = ray_triangle_test(origin, dir, opaque_zero);
    var overflow = 0u;
    let boxes = box_ray(origin, dir);
    let root = nodes[0];
    if box_entry(root.min, root.max, boxes, t_min, best.t) == NO_ENTRY {
        return TraceResult(best, 0u);
    }
    var stack: array<u32, STACK_SIZE>;
    var stack_entry: array<f32, STACK_SIZE>;
    var sp = 0u;
    var index = 0u;
    loop {
        let node = nodes[index];
        var descend = false;
        if (node.right_or_count & LEAF_FLAG) != 0u {
            let first = node.left_or_first;
            let end = first + (node.right_or_count & ~LEAF_FLAG);
            for (var i = first; i < end; i++) {
                let tri_index = prim_indices[i];
                let h = intersect_triangle(test, triangles[tri_index], t_min, best.t);
                if h.w != 0.0 {
                    best = Hit(h.x, tri_index, h.y, h.z);
                }
            }
            if any_hit && best.tri != MISS {
                return TraceResult(best, overflow);
            }
        } else {
            let left = nodes[node.left_or_first];
            let right = nodes[node.right_or_count];
            let tl = box_entry(left.min, left.max, boxes, t_min, best.t);
            let tr = box_entry(right.min, right.max, boxes, t_min, best.t);
            let hit_left = tl != NO_ENTRY;
            let hit_right = tr != NO_ENTRY;
            if hit_left && hit_right {
                var near = node.left_or_first;
                var far = node.right_or_count;
                var far_t = tr;
                if tr < tl {
                    near = node.right_or_count;
                    far = node.left_or_first;
                    far_t = tl;
                }
                if sp < STACK_SIZE {
                    stack[sp] = far;
                    stack_entry[sp] = far_t;
                    sp++;
                } else {
                    overflow = 1u;
                }
                index = near;
                descend = true;
            } else if hit_left {
                index = node.left_or_first;
                descend = true;
            } else if hit_right {
                index = node.right_or_count;
                descend = true;
            }
        }
        if !descend {
            // Pop the next subtree that can still hold a closer hit (its entry, rounded, may lie
            // a little beyond one).
            var found = false;
            while sp > 0u {
                sp--;
                if stack_entry[sp] <= best.t * BOX_EXIT_SLACK {
                    index = stack[sp];
                    found = true;
                    break;
                }
            }
            if !found {
                break;
            }
        }
    }
    return TraceResult(best, overflow);
}
