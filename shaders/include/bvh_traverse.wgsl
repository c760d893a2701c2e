// BVH traversal with a per-invocation stack (children tested together, nearer first): `traverse`
// finds the closest hit, or any hit (for shadow rays: stops at the first leaf hit), with the
// watertight triangle test. The including kernel declares the storage arrays `nodes`,
// `prim_indices` and `triangles`, and passes a zero from a uniform (`opaque_zero`, see
// ray_triangle.wgsl) and its stack (see `TraversalStack`). CPU twin: `Bvh::closest_hit` /
// `Bvh::any_hit` (src/bvh/traverse.rs).
#include "bvh_node.wgsl"
#include "ray_triangle.wgsl"
#include "ray_box.wgsl"

// Intersects the triangles of references first..end-1, keeping the closest hit in `best` and its
// material in `best_material`.
fn intersect_leaf(first: u32, end: u32, test: RayTriangleTest, t_min: f32, best: ptr<function, Hit>, best_material: ptr<function, u32>) {
    for (var i = first; i < end; i++) {
        let tri_index = prim_indices[i];
        let tri = load_triangle(tri_index);
        let h = intersect_triangle(test, tri, t_min, (*best).t);
        if h.w != 0.0 {
            *best = Hit(h.x, tri_index, h.y, h.z);
            *best_material = tri.material;
        }
    }
}

// The subtrees still to visit: (node, bits of its entry distance) per entry. The caller declares
// it once per invocation and passes it to every `traverse`: WGSL zero-fills every variable, so a
// stack declared in `traverse` would be cleared on every call (512 bytes of private memory).
const STACK_SIZE: u32 = 64u;
alias TraversalStack = array<vec2<u32>, STACK_SIZE>;

fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, opaque_zero: u32, any_hit: bool, stack: ptr<function, TraversalStack>) -> TraceResult {
    var best = Hit(t_max, MISS, 0.0, 0.0);
    var best_material = 0u;
    let test = ray_triangle_test(origin, dir, opaque_zero);
    var overflow = 0u;
    let boxes = box_ray(origin, dir);
    let root = nodes[0];
    if box_entry(root.min, root.max, boxes, t_min, best.t) == NO_ENTRY {
        return TraceResult(best, 0u, 0u, vec2<u32>(0u));
    }
    var steps = vec2<u32>(0u);
    var sp = 0u;
    var index = 0u;
    loop {
        let node = nodes[index];
        var descend = false;
        if (node.right_or_count & LEAF_FLAG) != 0u {
            let first = node.left_or_first;
            intersect_leaf(first, first + (node.right_or_count & ~LEAF_FLAG), test, t_min, &best, &best_material);
            steps.y += node.right_or_count & ~LEAF_FLAG;
            if any_hit && best.tri != MISS {
                return TraceResult(best, overflow, best_material, steps);
            }
        } else {
            steps.x++;
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
                    (*stack)[sp] = vec2<u32>(far, bitcast<u32>(far_t));
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
                let entry = (*stack)[sp];
                if bitcast<f32>(entry.y) <= best.t * BOX_EXIT_SLACK {
                    index = entry.x;
                    found = true;
                    break;
                }
            }
            if !found {
                break;
            }
        }
    }
    return TraceResult(best, overflow, best_material, steps);
}
