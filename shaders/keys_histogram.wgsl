// Radix-sort histogram, step 1 of each LSD pass of `sort::RadixSort` (reduce-then-scan): each
// workgroup counts the 4-bit digits at `params.shift` (only the low `params.bits` of them) of its
// tile of TILE keys and writes the 16 counts digit-major, counts[digit * num_tiles + tile], so that
// one exclusive scan of `counts` gives every (digit, tile) its first output position.
// Counting without atomics: each invocation counts its keys (strided, coalesced loads) into 16
// byte-wide counters packed in a vec4 (a one-hot add per key, all vector ALU), widens them to
// 16-bit halves in workgroup memory, and a raking reduction sums the 256 invocations (2 barriers).
// Tiles are linear workgroup indices over a 1D or 2D grid: wid.x + wid.y * num_workgroups.x.
// ITEMS, TILE, SortParams and digit_of must match keys_scatter.wgsl and src/sort/radix_sort.rs.

const WORKGROUP: u32 = 256u;
const ITEMS: u32 = 32u; // keys per invocation, at most 255 (byte-wide counters)
const TILE: u32 = 8192u; // WORKGROUP * ITEMS keys per workgroup, below 2^16 (16-bit counters)

struct SortParams {
    n: u32,
    num_tiles: u32,
    shift: u32,
    bits: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;
@group(0) @binding(1) var<storage, read> keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> counts: array<u32>;

// [w][invocation]: counts of digits 2w (low 16 bits) and 2w + 1 (high 16 bits).
var<workgroup> partial: array<u32, 2048>;
// [w][segment]: sums over the 32 segments of 8 invocations.
var<workgroup> segments: array<u32, 256>;

// The digit of a 64-bit key (x = low word, y = high word); shifts are multiples of 4, so a digit
// never straddles the two words.
fn digit_of(key: vec2<u32>) -> u32 {
    let word = select(key.x, key.y, params.shift >= 32u);
    return (word >> (params.shift & 31u)) & ((1u << params.bits) - 1u);
}

// One in byte (d % 4) of component d / 4: adding it counts digit d in 16 byte-wide counters.
fn one_hot(d: u32) -> vec4<u32> {
    return select(vec4<u32>(0u), vec4<u32>(1u << ((d & 3u) * 8u)), vec4<u32>(d >> 2u) == vec4<u32>(0u, 1u, 2u, 3u));
}

// Bytes 0 and 1 of `f` to the two 16-bit halves.
fn widen(f: u32) -> u32 {
    return (f & 0xffu) | ((f & 0xff00u) << 8u);
}

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let tile = wid.x + wid.y * nwg.x;
    if tile >= params.num_tiles {
        return;
    }
    var count = vec4<u32>(0u);
    for (var i = 0u; i < ITEMS; i++) {
        let item = tile * TILE + i * WORKGROUP + lid;
        if item < params.n {
            count += one_hot(digit_of(keys[item]));
        }
    }
    partial[lid] = widen(count.x);
    partial[WORKGROUP + lid] = widen(count.x >> 16u);
    partial[2u * WORKGROUP + lid] = widen(count.y);
    partial[3u * WORKGROUP + lid] = widen(count.y >> 16u);
    partial[4u * WORKGROUP + lid] = widen(count.z);
    partial[5u * WORKGROUP + lid] = widen(count.z >> 16u);
    partial[6u * WORKGROUP + lid] = widen(count.w);
    partial[7u * WORKGROUP + lid] = widen(count.w >> 16u);
    workgroupBarrier();
    // Invocation lid sums invocations [8s, 8s + 8) of word w.
    let w = lid / 32u;
    let s = lid % 32u;
    var sum = 0u;
    for (var j = 0u; j < 8u; j++) {
        sum += partial[w * WORKGROUP + s * 8u + j];
    }
    segments[lid] = sum;
    workgroupBarrier();
    if lid < 16u {
        var total = 0u;
        for (var j = 0u; j < 32u; j++) {
            total += segments[(lid >> 1u) * 32u + j];
        }
        counts[lid * params.num_tiles + tile] = (total >> ((lid & 1u) * 16u)) & 0xffffu;
    }
}
