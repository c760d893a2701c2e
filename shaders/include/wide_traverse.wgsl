// Traversal of the compressed 8-wide BVH (Ylitie, Karras & Laine 2017, §4): `traverse` finds the
// closest hit or any hit with the watertight triangle test. A node's eight quantized child boxes
// are tested four at a time, with the near and far planes chosen once per node from the ray's
// direction. The leaves it hits are intersected at once, near-first, each
// skipped when a hit closer than its box was found. The internal children it hits become a node
// group (child base, hit bits | imask << 8, nearest entry distance) visited in ray-octant order:
// a child's hit bit sits at `slot ^ octant_flip`, so taking the highest bit first gives
// front-to-back order for children placed by the conversion's octant assignment. A group with
// children left is pushed while one child is visited (one stack entry per wide level at most) and
// dropped when popped if its nearest child lies beyond the closest hit. The including kernel
// declares `wide_nodes`, `prim_indices` and `triangles`, and passes a zero from a uniform
// (`opaque_zero`). CPU twin of the layout: `WideBvh` (src/bvh/wide/node.rs).
#include "wide_node.wgsl"
#include "ray_triangle.wgsl"
#include "ray_box.wgsl"

// Bit s^flip of the result is bit s of `mask` (8 bits): the slot order seen from a ray octant.
fn slots_in_octant_order(mask: u32, flip: u32) -> u32 {
    var m = mask;
    if (flip & 1u) != 0u {
        m = ((m & 0x55u) << 1u) | ((m >> 1u) & 0x55u);
    }
    if (flip & 2u) != 0u {
        m = ((m & 0x33u) << 2u) | ((m >> 2u) & 0x33u);
    }
    if (flip & 4u) != 0u {
        m = ((m & 0x0fu) << 4u) | ((m >> 4u) & 0x0fu);
    }
    return m;
}

// The smallest entry distance among the slots of `mask`.
fn nearest_entry(entry: array<vec4<f32>, 2>, mask: u32) -> f32 {
    let bits = vec4<u32>(1u, 2u, 4u, 8u);
    let low = select(vec4<f32>(3.0e38), entry[0], (vec4<u32>(mask) & bits) != vec4<u32>(0u));
    let high = select(vec4<f32>(3.0e38), entry[1], (vec4<u32>(mask >> 4u) & bits) != vec4<u32>(0u));
    let both = min(low, high);
    return min(min(both.x, both.y), min(both.z, both.w));
}

fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, opaque_zero: u32, any_hit: bool) -> TraceResult {
    var best = Hit(t_max, MISS, 0.0, 0.0);
    let test = ray_triangle_test(origin, dir, opaque_zero);
    let boxes = box_ray(origin, dir);
    // Slots of children on the ray's negative side of an axis come first along it.
    let near_is_lo = boxes.inv_dir >= vec3<f32>(0.0);
    let octant_flip = 7u ^ (select(0u, 1u, dir.x < 0.0) | select(0u, 2u, dir.y < 0.0) | select(0u, 4u, dir.z < 0.0));
    var overflow = 0u;
    var stack: array<vec3<u32>, STACK_SIZE>;
    var sp = 0u;
    var index = 0u;
    loop {
        let node = wide_nodes[index];
        let scale = vec3<f32>(
            exponent_scale(node.exponents & 0xffu),
            exponent_scale((node.exponents >> 8u) & 0xffu),
            exponent_scale((node.exponents >> 16u) & 0xffu),
        ) * boxes.inv_dir;
        let offset = (node.origin - boxes.origin) * boxes.inv_dir;
        // The padding of flat axes (see BoxRay) goes into the offsets of the near and far planes.
        let near_offset = offset - boxes.slab_pad;
        let far_offset = offset + boxes.slab_pad;
        let imask = node.exponents >> 24u;
        // Which quantized planes are near and far along each axis for this ray.
        let near_x = select(node.hi_x, node.lo_x, near_is_lo.x);
        let near_y = select(node.hi_y, node.lo_y, near_is_lo.y);
        let near_z = select(node.hi_z, node.lo_z, near_is_lo.z);
        let far_x = select(node.lo_x, node.hi_x, near_is_lo.x);
        let far_y = select(node.lo_y, node.hi_y, near_is_lo.y);
        let far_z = select(node.lo_z, node.hi_z, near_is_lo.z);
        // Slots 0..3, then 4..7, four boxes at a time.
        var entered = 0u;
        var entry: array<vec4<f32>, 2>;
        for (var half = 0u; half < 2u; half++) {
            let enter = max(
                max(
                    vec4<f32>(unpack4xU8(near_x[half])) * scale.x + near_offset.x,
                    vec4<f32>(unpack4xU8(near_y[half])) * scale.y + near_offset.y,
                ),
                max(vec4<f32>(unpack4xU8(near_z[half])) * scale.z + near_offset.z, vec4<f32>(t_min)),
            );
            let exit = min(
                min(
                    vec4<f32>(unpack4xU8(far_x[half])) * scale.x + far_offset.x,
                    vec4<f32>(unpack4xU8(far_y[half])) * scale.y + far_offset.y,
                ),
                min(vec4<f32>(unpack4xU8(far_z[half])) * scale.z + far_offset.z, vec4<f32>(best.t)),
            ) * BOX_EXIT_SLACK;
            entry[half] = enter;
            let bits = select(vec4<u32>(0u), vec4<u32>(1u, 2u, 4u, 8u), enter <= exit);
            entered |= (bits.x | bits.y | bits.z | bits.w) << (4u * half);
        }
        let occupied = imask | slot_mask(node.leaf_counts);
        entered &= occupied;
        // Leaves near-first (octant order), each skipped once a hit nearer than its box is found.
        var leaves = slots_in_octant_order(entered & ~imask, octant_flip);
        let hits = slots_in_octant_order(entered & imask, octant_flip);
        while leaves != 0u {
            let position = firstLeadingBit(leaves);
            leaves ^= 1u << position;
            let slot = position ^ octant_flip;
            if entry[slot >> 2u][slot & 3u] > best.t * BOX_EXIT_SLACK {
                continue;
            }
            let first = leaf_first(node, slot);
            let end = first + slot_byte(node.leaf_counts, slot);
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
        }
        // The node group to continue with: this node's hit children (with the nearest entry among
        // them, to cull the group once a closer hit is found), or the last pushed group that
        // may still hold a closer hit.
        var group = vec3<u32>(node.child_base, hits | (imask << 8u), bitcast<u32>(nearest_entry(entry, entered & imask)));
        if hits == 0u {
            var found = false;
            while sp > 0u {
                sp--;
                if bitcast<f32>(stack[sp].z) <= best.t * BOX_EXIT_SLACK {
                    group = stack[sp];
                    found = true;
                    break;
                }
            }
            if !found {
                break;
            }
        }
        let position = firstLeadingBit(group.y & 0xffu);
        group.y ^= 1u << position;
        let slot = position ^ octant_flip;
        index = group.x + countOneBits((group.y >> 8u) & ((1u << slot) - 1u));
        if (group.y & 0xffu) != 0u {
            if sp < STACK_SIZE {
                stack[sp] = group;
                sp++;
            } else {
                overflow = 1u;
            }
        }
    }
    return TraceResult(best, overflow);
}
