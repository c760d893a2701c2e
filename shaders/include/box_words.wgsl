// A box reduced across workgroups by atomics, in one dispatch (the scene's centroid bounds of the
// LBVH keys, Karras 2012 §4; the scene box of pre-splitting): eight words, zeroed before the
// reduction. Words 0-2 hold the order bits of -min per axis, words 4-6 those of max: an unsigned
// order that agrees with the float order, so both ends reduce by atomicMax, and min and max are
// exact (the box is the CPU twin's, in any order). Rust twin: `lbvh::box_of_words`.

#include "aabb.wgsl"

// The unsigned integer of a (non-NaN) float that orders as the float does.
fn order_bits(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_order_bits(u: u32) -> f32 {
    return bitcast<f32>(select(~u, u & 0x7fffffffu, (u & 0x80000000u) != 0u));
}

// The box of the eight words, read as two vec4 (words 0-3, 4-7).
fn box_of_words(low: vec4<u32>, high: vec4<u32>) -> Aabb {
    let lo = -vec3<f32>(from_order_bits(low.x), from_order_bits(low.y), from_order_bits(low.z));
    let hi = vec3<f32>(from_order_bits(high.x), from_order_bits(high.y), from_order_bits(high.z));
    return Aabb(lo, 0u, hi, 0u);
}
