// Radix-sort stable scatter, one dispatch per LSD pass of `sort::RadixSort` (reduce-then-scan): each
// workgroup ranks its tile of tile_size() (key, value) pairs stably by the 4-bit digit at `params.shift`
// (low `params.bits` bits) and writes each pair to offset(digit, tile) + rank. On the way it counts
// the next pass's digits per tile of its output, so that no pass but the first needs a histogram
// dispatch.
//
// The offsets without a scan pass: offset(d, t) = Σ_{d' < d} total(d') + Σ_{t' < t} count(d', t')
// over the pass's digit counts `counts` (keys_histogram.wgsl for the first pass, the scatter before
// for the others). Each workgroup sums the 16 × num_tiles counts itself (invocation lid adds digit
// lid / 16's counts of every 16th tile from lid % 16; then 16 sums per digit, then the 16 digit
// totals): 16 · num_tiles reads per workgroup, a few kilobytes that stay in cache, in place of a
// scan dispatch (or three) per pass.
//
// Stable ranking by per-invocation counting (the radix sort of Zagha & Blelloch 1991 for vector
// multiprocessors, one "processor" per invocation): invocation i owns the contiguous pairs
// [i * TILE_ITEMS, (i + 1) * TILE_ITEMS) of the tile. (1) It counts its digits in 16 byte-wide
// counters packed in a vec4 (one-hot adds, all vector ALU, no atomics); (2) the 16 x 256 counts,
// widened to 16-bit halves in workgroup memory, get an exclusive scan over invocations per digit
// (raking: segments of 8 invocations, then the 32 segment sums; 3 barriers in all); (3) it walks
// its pairs again and writes each to offset(digit, tile) + prefix(digit, invocation) + the count
// of that digit earlier in its own run. Ranks follow (invocation, position) = element order, hence stable.
//
// The next pass's counts (when `params.next_bits` > 0): the pairs of digit d go to the consecutive
// slots from offset(d, tile), at most a tile's worth of them, so into at most two output tiles. The
// workgroup counts each pair's next digit per (d, which of the two tiles) in workgroup memory, then
// adds the non-zero counts to `next_counts[next digit * num_tiles + output tile]` (device atomics:
// at most 512 per workgroup). The buffers rotate over three passes: the scatter reads `counts`,
// adds into `next_counts`, which the dispatch before zeroed, and zeroes its tile's words of
// `cleared_counts`, into which the scatter after it adds.
// Values (`params.pairs`): in `values_in`, moved to `values_out` beside the keys
// (PAIRS_SEPARATE); or above the low `params.key_bits` bits of the keys, which the sort never
// reads as digits (`SortValues::AboveKeys`): each pair then moves as one 8-byte store
// (PAIRS_PACKED), and the last pass writes the key with the bits above cleared and the value to
// `values_out` (PAIRS_UNPACK), so the sorted buffers are those of the separate form.
// 11 KiB of workgroup memory; no subgroup operations.
// Tiles are linear workgroup indices over a 1D or 2D grid: wid.x + wid.y * num_workgroups.x.
// Tile geometry, parameters and digit counting are shared with keys_histogram.wgsl
// (radix_digits.wgsl).

@group(0) @binding(1) var<storage, read> keys_in: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> values_in: array<u32>;
@group(0) @binding(3) var<storage, read> counts: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys_out: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> values_out: array<u32>;
@group(0) @binding(6) var<storage, read_write> next_counts: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> cleared_counts: array<u32>;
// The item count's limit (`gpu::ItemCount`): the sort orders the first `sort_count()` pairs.
@group(0) @binding(8) var<storage, read> count_limit: array<u32>;

#include "radix_digits.wgsl"

// Values of `params.pairs` (Rust twin: `Pairs` in src/sort/radix_sort.rs).
const PAIRS_SEPARATE: u32 = 0u;
const PAIRS_PACKED: u32 = 1u;
const PAIRS_UNPACK: u32 = 2u;

// A packed key's sorted bits (the bits above cleared) and its value (the 32 bits above them).
struct Unpacked {
    key: vec2<u32>,
    value: u32,
}

fn unpack(key: vec2<u32>) -> Unpacked {
    let bits = params.key_bits;
    if bits >= 32u {
        let high = bits - 32u;
        return Unpacked(vec2<u32>(key.x, key.y & ((1u << high) - 1u)), key.y >> high);
    }
    return Unpacked(vec2<u32>(key.x & ((1u << bits) - 1u), 0u), (key.x >> bits) | (key.y << (32u - bits)));
}

// Component i of v, with selects (dynamic indexing is slow on some drivers).
fn pick(v: vec4<u32>, i: u32) -> u32 {
    return select(select(v.x, v.y, i == 1u), select(v.z, v.w, i == 3u), i >= 2u);
}

// First output position of each digit's pairs of this tile (`tile_offsets`).
var<workgroup> tile_offsets: array<u32, 16>;
// [digit d][the first or second output tile of d's pairs][next digit]: pairs of this tile
// (zero-initialized, as all workgroup memory).
var<workgroup> next_digit_counts: array<atomic<u32>, 512>;

// Fills `tile_offsets`: offset(d, tile) from the counts of all tiles (see the header). Uses
// `digit_counts` as scratch; ends with a barrier.
fn compute_tile_offsets(lid: u32, tile: u32) {
    let d = lid >> 4u;
    var before = 0u;
    var total = 0u;
    for (var t = lid & 15u; t < params.num_tiles; t += 16u) {
        let c = counts[d * params.num_tiles + t];
        total += c;
        before += select(0u, c, t < tile);
    }
    digit_counts[lid] = before;
    digit_counts[WORKGROUP + lid] = total;
    workgroupBarrier();
    // Invocation d < 16: digit d's sums over the 16 stripes, then the totals of the digits below.
    if lid < 16u {
        var digit_before = 0u;
        var digit_total = 0u;
        for (var s = 0u; s < 16u; s++) {
            digit_before += digit_counts[lid * 16u + s];
            digit_total += digit_counts[WORKGROUP + lid * 16u + s];
        }
        digit_counts[2u * WORKGROUP + lid] = digit_total;
        tile_offsets[lid] = digit_before;
    }
    workgroupBarrier();
    if lid < 16u {
        var base = 0u;
        for (var d = 0u; d < lid; d++) {
            base += digit_counts[2u * WORKGROUP + d];
        }
        tile_offsets[lid] += base;
    }
    workgroupBarrier();
}

// First output position of digit d for invocation lid's pairs.
fn first_slot(d: u32, lid: u32) -> u32 {
    let w = d >> 1u;
    let local = digit_counts[w * WORKGROUP + lid] + segments[w * 32u + lid / 8u];
    return tile_offsets[d] + ((local >> ((d & 1u) * 16u)) & 0xffffu);
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
    let gather_next = params.next_bits != 0u;
    if gather_next && lid < 16u {
        cleared_counts[lid * params.num_tiles + tile] = 0u;
    }
    compute_tile_offsets(lid, tile);
    let size = tile_size();
    let first = tile * size + lid * TILE_ITEMS;
    let n = sort_count();
    var count = vec4<u32>(0u);
    for (var i = 0u; i < TILE_ITEMS; i++) {
        let item = first + i;
        if item < n {
            count += one_hot(digit_of(keys_in[item]));
        }
    }
    store_digit_counts(count, lid);
    workgroupBarrier();
    // Invocation lid scans invocations [8s, 8s + 8) of word w (two digits at once: the halves
    // never carry, tile counts stay below 2^16).
    let w = lid / 32u;
    let s = lid % 32u;
    var run = 0u;
    for (var j = 0u; j < 8u; j++) {
        let at = w * WORKGROUP + s * 8u + j;
        let c = digit_counts[at];
        digit_counts[at] = run;
        run += c;
    }
    segments[lid] = run;
    workgroupBarrier();
    if lid < 8u {
        var total = 0u;
        for (var j = 0u; j < 32u; j++) {
            let c = segments[lid * 32u + j];
            segments[lid * 32u + j] = total;
            total += c;
        }
    }
    workgroupBarrier();
    let slots0 = vec4<u32>(first_slot(0u, lid), first_slot(1u, lid), first_slot(2u, lid), first_slot(3u, lid));
    let slots1 = vec4<u32>(first_slot(4u, lid), first_slot(5u, lid), first_slot(6u, lid), first_slot(7u, lid));
    let slots2 = vec4<u32>(first_slot(8u, lid), first_slot(9u, lid), first_slot(10u, lid), first_slot(11u, lid));
    let slots3 = vec4<u32>(first_slot(12u, lid), first_slot(13u, lid), first_slot(14u, lid), first_slot(15u, lid));
    var seen = vec4<u32>(0u);
    for (var i = 0u; i < TILE_ITEMS; i++) {
        let item = first + i;
        if item < n {
            let key = keys_in[item];
            let d = digit_of(key);
            let q = d >> 2u;
            let slots = select(select(slots0, slots1, q == 1u), select(slots2, slots3, q == 3u), q >= 2u);
            let dest = pick(slots, d & 3u) + ((pick(seen, q) >> ((d & 3u) * 8u)) & 0xffu);
            seen += one_hot(d);
            if params.pairs == PAIRS_SEPARATE {
                keys_out[dest] = key;
                values_out[dest] = values_in[item];
            } else if params.pairs == PAIRS_PACKED {
                keys_out[dest] = key;
            } else {
                let pair = unpack(key);
                keys_out[dest] = pair.key;
                values_out[dest] = pair.value;
            }
            if gather_next {
                let second_tile = dest / size - tile_offsets[d] / size;
                let next = digit_at(key, params.next_shift, params.next_bits);
                atomicAdd(&next_digit_counts[(d * 2u + second_tile) * 16u + next], 1u);
            }
        }
    }
    if gather_next {
        workgroupBarrier();
        for (var i = lid; i < 512u; i += WORKGROUP) {
            let count = atomicLoad(&next_digit_counts[i]);
            if count != 0u {
                let output_tile = tile_offsets[i >> 5u] / size + ((i >> 4u) & 1u);
                atomicAdd(&next_counts[(i & 15u) * params.num_tiles + output_tile], count);
            }
        }
    }
}
