// Radix-sort histogram of the first LSD pass of `sort::RadixSort` (reduce-then-scan): each
// workgroup counts the 4-bit digits at `params.shift` (only the low `params.bits` of them) of its
// tile of tile_size() keys and writes the 16 counts digit-major, counts[digit * num_tiles + tile], from
// which keys_scatter.wgsl sums every (digit, tile)'s first output position. Later passes take their
// counts from the scatter before them, which adds them into `next_counts`: this kernel zeroes the
// tile's 16 words there for the first scatter.
// Counting without atomics: each invocation counts its keys (strided, coalesced loads) into 16
// byte-wide counters packed in a vec4 (a one-hot add per key, all vector ALU), widens them to
// 16-bit halves in workgroup memory, and a raking reduction sums the 256 invocations (2 barriers).
// Tiles are linear workgroup indices over a 1D or 2D grid: wid.x + wid.y * num_workgroups.x.
// Tile geometry, parameters and digit counting are shared with keys_scatter.wgsl
// (radix_digits.wgsl).

@group(0) @binding(1) var<storage, read> keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> counts: array<u32>;
@group(0) @binding(3) var<storage, read_write> next_counts: array<u32>;
// The item count's limit (`gpu::ItemCount`): the sort orders the first `sort_count()` pairs.
@group(0) @binding(4) var<storage, read> count_limit: array<u32>;

#include "radix_digits.wgsl"

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
    let n = sort_count();
    var count = vec4<u32>(0u);
    for (var i = 0u; i < TILE_ITEMS; i++) {
        let item = tile * tile_size() + i * WORKGROUP + lid;
        if item < n {
            count += one_hot(digit_of(keys[item]));
        }
    }
    store_digit_counts(count, lid);
    workgroupBarrier();
    // Invocation lid sums invocations [8s, 8s + 8) of word w.
    let w = lid / 32u;
    let s = lid % 32u;
    var sum = 0u;
    for (var j = 0u; j < 8u; j++) {
        sum += digit_counts[w * WORKGROUP + s * 8u + j];
    }
    segments[lid] = sum;
    workgroupBarrier();
    if lid < 16u {
        var total = 0u;
        for (var j = 0u; j < 32u; j++) {
            total += segments[(lid >> 1u) * 32u + j];
        }
        counts[lid * params.num_tiles + tile] = (total >> ((lid & 1u) * 16u)) & 0xffffu;
        next_counts[lid * params.num_tiles + tile] = 0u;
    }
}
