// Traversal of the compressed 8-wide BVH (Ylitie, Karras & Laine 2017, §4): `traverse` finds the
// closest hit or any hit with the watertight triangle test. A node's eight quantized child boxes
// are tested four at a time, with the near and far planes chosen once per node from the ray's
// direction. The leaves it hits are intersected at once, near-first (in ray-octant order: a slot's
// bit sits at `slot ^ octant_flip`, and the conversion placed children by octant), each skipped
// when a hit closer than its box was found. The internal children it hits are sorted by entry
// distance (a sorting network over keys of entry bits and child offset; one needs no sort) and
// become a node group: child base, the offsets of the children in order (three bits each) with
// their count, and the entry distance of the second child. The traversal descends into the nearest
// child and pushes the rest of the group (one stack entry per wide level at most). A popped group
// whose next child lies beyond the closest hit is dropped. The paper visits the internal children in
// octant order too; sorted, rays test far fewer triangles (README, "Traversal"). The including
// kernel declares `wide_nodes` (as array<vec4<u32>>: a node is read as five 16-byte loads, not
// eleven, one per field) and `wide_triangles` (the references' triangles in order, each with its
// index: `WideTree::triangles`), and passes a zero from a uniform
// (`opaque_zero`) and its stack (see `TraversalStack`). CPU twin of the layout: `WideBvh`
// (src/bvh/wide/node.rs).
#include "wide_node.wgsl"
#include "ray_triangle.wgsl"
#include "ray_box.wgsl"

// The node at `index` of `wide_nodes` (five vec4 words per node). Lavapipe loads storage lane by
// lane at a cost per load besides its words: as five loads the wide trace ran 9-14 % faster there
// than as the struct's eleven.
fn load_wide_node(index: u32) -> WideNode {
    let w0 = wide_nodes[5u * index];
    let w1 = wide_nodes[5u * index + 1u];
    let w2 = wide_nodes[5u * index + 2u];
    let w3 = wide_nodes[5u * index + 3u];
    let w4 = wide_nodes[5u * index + 4u];
    return WideNode(bitcast<vec3<f32>>(w0.xyz), w0.w, w1.x, w1.y, w1.zw, w2.xy, w2.zw, w3.xy, w3.zw, w4.xy, w4.zw);
}

// Intersects the triangles of references first..end-1 (their copies in `wide_triangles`, each
// with its triangle's index after v1), keeping the closest hit in `best` and its material in
// `best_material`. Bound as words, so the
// index and material (denormal bit patterns as floats) come through no float handling.
fn intersect_wide_leaf(first: u32, end: u32, test: RayTriangleTest, t_min: f32, best: ptr<function, Hit>, best_material: ptr<function, u32>) {
    for (var i = first; i < end; i++) {
        let w0 = wide_triangles[3u * i];
        let w1 = wide_triangles[3u * i + 1u];
        let w2 = wide_triangles[3u * i + 2u];
        let tri = Triangle(bitcast<vec3<f32>>(w0.xyz), w0.w, bitcast<vec3<f32>>(w1.xyz), w1.w, bitcast<vec3<f32>>(w2.xyz), w2.w);
        let h = intersect_triangle(test, tri, t_min, (*best).t);
        if h.w != 0.0 {
            *best = Hit(h.x, tri.pad1, h.y, h.z);
            *best_material = tri.material;
        }
    }
}

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

// Sort keys of the internal children: the bits of the entry distance that a key keeps (no sign,
// not the three low bits, which hold the child's offset), and the key of a child not hit.
const KEY_ENTRY: u32 = 0x7ffffff8u;
const NO_KEY: u32 = 0xffffffffu;

// Eight keys in ascending order (Batcher's odd-even merge sort, 19 comparators): keys 0-3 in
// `low`, 4-7 in `high`, and the same for the result.
fn sort_keys(low: vec4<u32>, high: vec4<u32>) -> array<vec4<u32>, 2> {
    var l = low;
    var h = high;
    // (0,1) (2,3) (4,5) (6,7)
    var a4 = vec4<u32>(l.x, l.z, h.x, h.z);
    var b4 = vec4<u32>(l.y, l.w, h.y, h.w);
    var lo4 = min(a4, b4);
    var hi4 = max(a4, b4);
    l = vec4<u32>(lo4.x, hi4.x, lo4.y, hi4.y);
    h = vec4<u32>(lo4.z, hi4.z, lo4.w, hi4.w);
    // (0,2) (1,3) (4,6) (5,7)
    a4 = vec4<u32>(l.xy, h.xy);
    b4 = vec4<u32>(l.zw, h.zw);
    lo4 = min(a4, b4);
    hi4 = max(a4, b4);
    l = vec4<u32>(lo4.xy, hi4.xy);
    h = vec4<u32>(lo4.zw, hi4.zw);
    // (1,2) (5,6)
    let a2 = vec2<u32>(l.y, h.y);
    let b2 = vec2<u32>(l.z, h.z);
    var lo2 = min(a2, b2);
    var hi2 = max(a2, b2);
    l = vec4<u32>(l.x, lo2.x, hi2.x, l.w);
    h = vec4<u32>(h.x, lo2.y, hi2.y, h.w);
    // (0,4) (1,5) (2,6) (3,7)
    lo4 = min(l, h);
    hi4 = max(l, h);
    l = lo4;
    h = hi4;
    // (2,4) (3,5)
    lo2 = min(l.zw, h.xy);
    hi2 = max(l.zw, h.xy);
    l = vec4<u32>(l.xy, lo2);
    h = vec4<u32>(hi2, h.zw);
    // (1,2) (3,4) (5,6)
    let a3 = vec3<u32>(l.y, l.w, h.y);
    let b3 = vec3<u32>(l.z, h.x, h.z);
    let lo3 = min(a3, b3);
    let hi3 = max(a3, b3);
    return array<vec4<u32>, 2>(vec4<u32>(l.x, lo3.x, hi3.x, lo3.y), vec4<u32>(hi3.y, lo3.z, hi3.z, h.w));
}

// Four child boxes against the ray: their entry distances and a bit per box entered.
struct SlabHits {
    entry: vec4<f32>,
    entered: u32,
}

// `near` and `far`: per axis, the word of four quantized planes the ray crosses first and last;
// a plane's distance is its byte times `scale` plus the offset.
fn slab_test(near: vec3<u32>, far: vec3<u32>, scale: vec3<f32>, near_offset: vec3<f32>, far_offset: vec3<f32>, t_min: f32, t_max: f32) -> SlabHits {
    let enter = max(
        max(
            vec4<f32>(unpack4xU8(near.x)) * scale.x + near_offset.x,
            vec4<f32>(unpack4xU8(near.y)) * scale.y + near_offset.y,
        ),
        max(vec4<f32>(unpack4xU8(near.z)) * scale.z + near_offset.z, vec4<f32>(t_min)),
    );
    let exit = min(
        min(
            vec4<f32>(unpack4xU8(far.x)) * scale.x + far_offset.x,
            vec4<f32>(unpack4xU8(far.y)) * scale.y + far_offset.y,
        ),
        min(vec4<f32>(unpack4xU8(far.z)) * scale.z + far_offset.z, vec4<f32>(t_max)),
    ) * BOX_EXIT_SLACK;
    let bits = select(vec4<u32>(0u), vec4<u32>(1u, 2u, 4u, 8u), enter <= exit);
    return SlabHits(enter, bits.x | bits.y | bits.z | bits.w);
}

// The node groups still to visit. The caller declares it once per invocation and passes it to
// every `traverse`: WGSL zero-fills every variable, so a stack declared in `traverse` would be
// cleared on every call. A traversal pushes at most one group per wide level below the root, and
// the deepest wide trees of the shared scenes have 14 levels (conference, from a binary tree of
// 42; 7-12 elsewhere), so 32 groups (384 bytes of private memory, zero-filled at each
// invocation's start: on a GPU 24 16-byte stores to local memory, where 64 took 48) hold any
// wide tree of up to 33 levels; a deeper one overflows, which the tracer reports as an error.
const STACK_SIZE: u32 = 32u;
alias TraversalStack = array<vec3<u32>, STACK_SIZE>;

fn traverse(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, opaque_zero: u32, any_hit: bool, stack: ptr<function, TraversalStack>) -> TraceResult {
    var best = Hit(t_max, MISS, 0.0, 0.0);
    var best_material = 0u;
    let test = ray_triangle_test(origin, dir, opaque_zero);
    let boxes = box_ray(origin, dir);
    // Slots of children on the ray's negative side of an axis come first along it.
    let near_is_lo = boxes.inv_dir >= vec3<f32>(0.0);
    let octant_flip = 7u ^ (select(0u, 1u, dir.x < 0.0) | select(0u, 2u, dir.y < 0.0) | select(0u, 4u, dir.z < 0.0));
    var overflow = 0u;
    var steps = vec2<u32>(0u);
    var sp = 0u;
    var index = 0u;
    loop {
        let node = load_wide_node(index);
        steps.x++;
        let scale = vec3<f32>(
            exponent_scale(node.exponents & 0xffu),
            exponent_scale((node.exponents >> 8u) & 0xffu),
            exponent_scale((node.exponents >> 16u) & 0xffu),
        ) * boxes.inv_dir;
        let offset = (node.origin - boxes.origin) * boxes.inv_dir;
        // The padding of flat axes (see BoxRay) goes into the offsets of the near and far planes.
        let near_offset = offset - boxes.slab_pad;
        let far_offset = offset + boxes.slab_pad;
        let imask = internal_slots(node);
        // Which quantized planes are near and far along each axis for this ray.
        let near_x = select(node.hi_x, node.lo_x, near_is_lo.x);
        let near_y = select(node.hi_y, node.lo_y, near_is_lo.y);
        let near_z = select(node.hi_z, node.lo_z, near_is_lo.z);
        let far_x = select(node.lo_x, node.hi_x, near_is_lo.x);
        let far_y = select(node.lo_y, node.hi_y, near_is_lo.y);
        let far_z = select(node.lo_z, node.hi_z, near_is_lo.z);
        // Slots 0..3, then 4..7, four boxes at a time. The halves are values, not an array:
        // an array indexed by a slot would live in memory (a GPU's local memory).
        let low = slab_test(vec3<u32>(near_x.x, near_y.x, near_z.x), vec3<u32>(far_x.x, far_y.x, far_z.x), scale, near_offset, far_offset, t_min, best.t);
        let high = slab_test(vec3<u32>(near_x.y, near_y.y, near_z.y), vec3<u32>(far_x.y, far_y.y, far_z.y), scale, near_offset, far_offset, t_min, best.t);
        let occupied = imask | slot_mask(node.leaf_counts);
        let entered = (low.entered | (high.entered << 4u)) & occupied;
        // Leaves near-first (octant order), each skipped once a hit nearer than its box is found.
        var leaves = slots_in_octant_order(entered & ~imask, octant_flip);
        while leaves != 0u {
            let position = firstLeadingBit(leaves);
            leaves ^= 1u << position;
            let slot = position ^ octant_flip;
            if select(low.entry, high.entry, slot >= 4u)[slot & 3u] > best.t * BOX_EXIT_SLACK {
                continue;
            }
            let first = leaf_first(node, slot);
            let count = slot_byte(node.leaf_counts, slot);
            intersect_wide_leaf(first, first + count, test, t_min, &best, &best_material);
            steps.y += count;
            if any_hit && best.tri != MISS {
                return TraceResult(best, overflow, best_material, steps);
            }
        }
        // The internal children hit. One: descend into it, its offset from child_base being the
        // count of internal slots below it; no sort (on lavapipe, where a batch of 8 lanes skips
        // the sort only when none of them needs it, this made the wide trace 3-9 % faster).
        // More: nearest first, by sorted keys of a child's entry distance with its offset from
        // child_base in the low three bits. Entries are >= t_min >= 0, and non-negative floats
        // order as their bits once the sign bit of a -0.0 is cleared. A group: (child base,
        // offsets in order, three bits each, | count << 24, entry of the second).
        let hit_inner = entered & imask;
        let count = countOneBits(hit_inner);
        if count == 1u {
            index = node.child_base + countOneBits(imask & (hit_inner - 1u));
            continue;
        }
        var group = vec3<u32>(0u);
        if count == 0u {
            // The first group on the stack whose next child can still hold a closer hit (its
            // entry, rounded, may lie a little beyond one).
            var found = false;
            while sp > 0u {
                sp--;
                let popped = (*stack)[sp];
                if bitcast<f32>(popped.z) <= best.t * BOX_EXIT_SLACK {
                    group = popped;
                    found = true;
                    break;
                }
            }
            if !found {
                break;
            }
        } else {
            let inner_low = (vec4<u32>(hit_inner) & vec4<u32>(1u, 2u, 4u, 8u)) != vec4<u32>(0u);
            let inner_high = (vec4<u32>(hit_inner >> 4u) & vec4<u32>(1u, 2u, 4u, 8u)) != vec4<u32>(0u);
            let offsets_low = countOneBits(vec4<u32>(imask) & vec4<u32>(0u, 1u, 3u, 7u));
            let offsets_high = countOneBits(vec4<u32>(imask) & vec4<u32>(15u, 31u, 63u, 127u));
            let keys = sort_keys(
                select(vec4<u32>(NO_KEY), (bitcast<vec4<u32>>(low.entry) & vec4<u32>(KEY_ENTRY)) | offsets_low, inner_low),
                select(vec4<u32>(NO_KEY), (bitcast<vec4<u32>>(high.entry) & vec4<u32>(KEY_ENTRY)) | offsets_high, inner_high),
            );
            let order = (keys[0].x & 7u) | ((keys[0].y & 7u) << 3u) | ((keys[0].z & 7u) << 6u) | ((keys[0].w & 7u) << 9u)
                | ((keys[1].x & 7u) << 12u) | ((keys[1].y & 7u) << 15u) | ((keys[1].z & 7u) << 18u) | ((keys[1].w & 7u) << 21u);
            // The second child's key without its low bits: its entry distance, rounded down.
            group = vec3<u32>(node.child_base, order | (count << 24u), keys[0].y & KEY_ENTRY);
        }
        // Descend into the group's next child; the rest of the group goes on the stack.
        index = group.x + (group.y & 7u);
        let left = (group.y >> 24u) - 1u;
        if left != 0u {
            if sp < STACK_SIZE {
                (*stack)[sp] = vec3<u32>(group.x, ((group.y & 0xffffffu) >> 3u) | (left << 24u), group.z);
                sp++;
            } else {
                overflow = 1u;
            }
        }
    }
    return TraceResult(best, overflow, best_material, steps);
}
