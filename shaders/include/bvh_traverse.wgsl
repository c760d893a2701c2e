// BVH traversal with a per-invocation stack (children tested together, nearer first): closest hit
// (`trace_closest`), or any hit (`trace_any`, for shadow rays: stops at the first leaf hit).
// The including kernel declares the storage arrays `nodes`, `prim_indices` and `triangles`.
#include "bvh_node.wgsl"
#include "ray_triangle.wgsl"

const STACK_SIZE: u32 = 64u;
const NO_ENTRY: f32 = 3.0e38;

// Entry distance of the ray into the box, or NO_ENTRY if it misses within [t_min, t_max].
// The exit distance is widened by a few ulps so that grazing rays and flat boxes are not lost.
fn box_entry(bmin: vec3<f32>, bmax: vec3<f32>, origin: vec3<f32>, inv_dir: vec3<f32>, t_min: f32, t_max: f32) -> f32 {
    let t0 = (bmin - origin) * inv_dir;
    let t1 = (bmax - origin) * inv_dir;
    let near = min(t0, t1);
    let far = max(t0, t1);
    let enter = max(max(near.x, near.y), max(near.z, t_min));
    let exit = min(min(far.x, far.y), min(far.z, t_max)) * 1.0000004;
    return select(NO_ENTRY, enter, enter <= exit);
}

struct TraceResult {
    hit: Hit,
    // 1 when the traversal stack overflowed (the result may have missed geometry).
    overflow: u32,
}

fn trace_closest(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> TraceResult {
    return traverse(origin, dir, t_min, t_max, false);
}

// Some hit in [t_min, t_max] (not necessarily the closest), or MISS.
fn trace_any(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32) -> TraceResult {
    return traverse(origin, dir, t_min, t_max, true);
}

fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, any_hit: bool) -> TraceResult {
    var best = Hit(t_max, MISS, 0.0, 0.0);
    var overflow = 0u;
    // Zero direction components become tiny ones so that 0 * inf never produces NaN.
    let safe_dir = select(dir, vec3<f32>(1e-30), abs(dir) < vec3<f32>(1e-30));
    let inv_dir = 1.0 / safe_dir;
    let root = nodes[0];
    if box_entry(root.min, root.max, origin, inv_dir, t_min, best.t) == NO_ENTRY {
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
                let h = intersect_triangle(origin, dir, t_min, best.t, triangles[tri_index]);
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
            let tl = box_entry(left.min, left.max, origin, inv_dir, t_min, best.t);
            let tr = box_entry(right.min, right.max, origin, inv_dir, t_min, best.t);
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
            // Pop the next subtree that can still hold a closer hit.
            var found = false;
            while sp > 0u {
                sp--;
                if stack_entry[sp] < best.t {
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
