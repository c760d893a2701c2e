// GPU twin of `WideNode` (src/bvh/wide/node.rs): an 8-wide node with quantized child boxes after
// Ylitie, Karras & Laine 2017 (80 bytes). Slot s of a node is a child when its bit of `imask` is
// set (internal: a wide node) or its byte of `leaf_counts` is not zero (a leaf of that many
// primitive references); other slots are empty. Child box of slot s, per axis a:
//     [origin.a + lo_a[s] · 2^(e_a − 127), origin.a + hi_a[s] · 2^(e_a − 127)]
// with the biased exponents e_a in the low three bytes of `exponents` (imask in the high byte).
// Internal children are consecutive wide nodes from `child_base` in slot order; the references of
// the leaf children are consecutive from `prim_base` in slot order.
struct WideNode {
    origin: vec3<f32>,
    exponents: u32,
    child_base: u32,
    prim_base: u32,
    leaf_counts: vec2<u32>,
    lo_x: vec2<u32>,
    lo_y: vec2<u32>,
    lo_z: vec2<u32>,
    hi_x: vec2<u32>,
    hi_y: vec2<u32>,
    hi_z: vec2<u32>,
}

// Bit s set where slot s holds an internal child (imask, the high byte of `exponents`).
fn internal_slots(node: WideNode) -> u32 {
    return node.exponents >> 24u;
}

// Byte `slot` of eight bytes packed little-endian into two words.
fn slot_byte(bytes: vec2<u32>, slot: u32) -> u32 {
    return (bytes[slot >> 2u] >> ((slot & 3u) * 8u)) & 0xffu;
}

// Bit s set where byte s of the eight bytes is not zero.
fn slot_mask(bytes: vec2<u32>) -> u32 {
    let low = select(vec4<u32>(0u), vec4<u32>(1u, 2u, 4u, 8u), unpack4xU8(bytes.x) != vec4<u32>(0u));
    let high = select(vec4<u32>(0u), vec4<u32>(16u, 32u, 64u, 128u), unpack4xU8(bytes.y) != vec4<u32>(0u));
    let both = low | high;
    return both.x | both.y | both.z | both.w;
}

fn byte_sum(word: u32) -> u32 {
    let pairs = (word & 0x00ff00ffu) + ((word >> 8u) & 0x00ff00ffu);
    return (pairs & 0xffffu) + (pairs >> 16u);
}

// First reference of the leaf in `slot`: prim_base plus the sizes of the leaves in lower slots.
fn leaf_first(node: WideNode, slot: u32) -> u32 {
    let low_mask = select((1u << (8u * (slot & 3u))) - 1u, 0xffffffffu, slot >= 4u);
    let high_mask = select(0u, (1u << (8u * (slot & 3u))) - 1u, slot >= 4u);
    return node.prim_base + byte_sum(node.leaf_counts.x & low_mask) + byte_sum(node.leaf_counts.y & high_mask);
}

// 2^(e − 127) for a biased exponent e in 1..=254.
fn exponent_scale(biased: u32) -> f32 {
    return bitcast<f32>(biased << 23u);
}
