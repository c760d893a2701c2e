// Shared by keys_histogram.wgsl and keys_scatter.wgsl (the LSD passes of `sort::RadixSort`): the
// tile geometry, the pass parameters (binding 0) and the pair count, the 4-bit digits of a key and
// the packed per-invocation digit counters. SortParams must match src/sort/radix_sort.rs.

const WORKGROUP: u32 = 256u;
// Keys per invocation (8, 16 or 32, set per pipeline by `sort::RadixSort`; at most 255, the
// byte-wide counters): a tile holds WORKGROUP * TILE_ITEMS keys, below 2^16 (16-bit counters).
override TILE_ITEMS: u32 = 32u;
#include "constants.wgsl"

// The pass's digit: `bits` bits from bit `shift`; the next pass's digit, whose counts the pass
// gathers: `next_bits` (0 after the last pass) bits from `next_shift`; where the values are
// (`pairs`: PAIRS_SEPARATE, PAIRS_PACKED or PAIRS_UNPACK, keys_scatter.wgsl) and the sorted bits
// (`key_bits`), above which packed values sit.
struct SortParams {
    n: u32,
    num_tiles: u32,
    shift: u32,
    bits: u32,
    next_shift: u32,
    next_bits: u32,
    pairs: u32,
    key_bits: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;

// Keys per tile.
fn tile_size() -> u32 {
    return WORKGROUP * TILE_ITEMS;
}

// Pairs to sort: n, or fewer when the count was computed on the GPU (the including kernel
// declares `count_limit`; see `gpu::ItemCount`). Tiles past them count and move nothing.
fn sort_count() -> u32 {
    return min(params.n, count_limit[0]);
}

// [w][invocation]: counts (keys_scatter: then exclusive prefixes within the segment) of digits
// 2w (low 16 bits) and 2w + 1 (high 16 bits).
var<workgroup> digit_counts: array<u32, 2048>;
// [w][segment]: sums (keys_scatter: then exclusive prefixes) over the 32 segments of 8
// invocations.
var<workgroup> segments: array<u32, 256>;

// The `bits` bits from bit `shift` of a 64-bit key (x = low word, y = high word); shifts are
// multiples of 4, so a digit never straddles the two words.
fn digit_at(key: vec2<u32>, shift: u32, bits: u32) -> u32 {
    let word = select(key.x, key.y, shift >= 32u);
    return (word >> (shift & 31u)) & ((1u << bits) - 1u);
}

// The pass's digit of a key.
fn digit_of(key: vec2<u32>) -> u32 {
    return digit_at(key, params.shift, params.bits);
}

// One in byte (d % 4) of component d / 4: adding it counts digit d in 16 byte-wide counters.
fn one_hot(d: u32) -> vec4<u32> {
    return select(vec4<u32>(0u), vec4<u32>(1u << ((d & 3u) * 8u)), vec4<u32>(d >> 2u) == vec4<u32>(0u, 1u, 2u, 3u));
}

// Bytes 0 and 1 of `f` to the two 16-bit halves.
fn widen(f: u32) -> u32 {
    return (f & 0xffu) | ((f & 0xff00u) << 8u);
}

// Stores invocation `lid`'s 16 byte-wide counters (from `one_hot` sums) as 16-bit halves in
// `digit_counts`.
fn store_digit_counts(count: vec4<u32>, lid: u32) {
    digit_counts[lid] = widen(count.x);
    digit_counts[WORKGROUP + lid] = widen(count.x >> 16u);
    digit_counts[2u * WORKGROUP + lid] = widen(count.y);
    digit_counts[3u * WORKGROUP + lid] = widen(count.y >> 16u);
    digit_counts[4u * WORKGROUP + lid] = widen(count.z);
    digit_counts[5u * WORKGROUP + lid] = widen(count.z >> 16u);
    digit_counts[6u * WORKGROUP + lid] = widen(count.w);
    digit_counts[7u * WORKGROUP + lid] = widen(count.w >> 16u);
}
