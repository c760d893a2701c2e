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
//
// Staged writes (the override STAGED_PAIRS = 2048, `SortWrites::Staged`; 1: direct writes, the
// default): the tile is ranked in rounds of 2048 pairs (TILE_ITEMS / 8 of them), each by all 256
// invocations, 8 pairs each, as above, with the tile's digit offsets carried from round to round
// (`round_offsets`). A round's keys are first read into workgroup memory by neighbouring
// invocations (coalesced loads; each invocation then takes its run of 8 from there), its ranked
// pairs go to workgroup memory in digit order, and after a barrier invocation j writes staged pair
// j to its slot, so neighbouring invocations write neighbouring slots of each digit's run:
// coalesced stores where the direct scatter has each invocation write a run of its own (one memory
// sector per pair and invocation, which a GPU's cache merges only while the output fits in it). The
// values stage in `digit_counts`, free once the round's ranks are known.
// 11 KiB of workgroup memory, 27 KiB staged (`STAGED_WORKGROUP_BYTES`); no subgroup operations.
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

// Component i of v, with selects (dynamic indexing is slow on some drivers).
fn pick(v: vec4<u32>, i: u32) -> u32 {
    return select(select(v.x, v.y, i == 1u), select(v.z, v.w, i == 3u), i >= 2u);
}

// First output position of each digit's pairs of this tile (`tile_offsets`).
var<workgroup> tile_offsets: array<u32, 16>;
// [digit d][the first or second output tile of d's pairs][next digit]: pairs of this tile
// (zero-initialized, as all workgroup memory).
var<workgroup> next_digit_counts: array<atomic<u32>, 512>;

// Pairs staged per round: 2048 (staged writes) or 1 (direct scatter). Set per pipeline by
// `sort::RadixSort`.
override STAGED_PAIRS: u32 = 1u;
// Pairs per invocation and round: a staged round is 2048 pairs, 8 per invocation; the direct
// scatter ranks its whole tile in one round.
override RUN_ITEMS: u32 = select(TILE_ITEMS, 8u, STAGED_PAIRS > 1u);
// Rounds per tile.
override ROUNDS: u32 = TILE_ITEMS / RUN_ITEMS;
// The keys of a round, in digit order (the values go to `digit_counts`).
var<workgroup> staged_keys: array<vec2<u32>, STAGED_PAIRS>;
// Per digit: the output slot of the round's first pair of that digit (the tile's offset plus the
// pairs of that digit in earlier rounds), and where the round's pairs of the digit start among
// its staged pairs.
var<workgroup> round_offsets: array<u32, 16>;
var<workgroup> staged_starts: array<u32, 16>;
// The round's counts of digits 2w (low half) and 2w + 1 (high half).
var<workgroup> round_counts: array<u32, 8>;

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

// First output position of digit d for invocation lid's pairs of this round.
fn first_slot(d: u32, lid: u32) -> u32 {
    let w = d >> 1u;
    let local = digit_counts[w * WORKGROUP + lid] + segments[w * 32u + lid / 8u];
    return round_offsets[d] + ((local >> ((d & 1u) * 16u)) & 0xffffu);
}

// The round's count of digit d.
fn round_count(d: u32) -> u32 {
    return (round_counts[d >> 1u] >> ((d & 1u) * 16u)) & 0xffffu;
}

// Key `i` of the invocation's run: staged, from `run_keys` (read there from workgroup memory);
// direct, from `keys_in` at `item`.
fn run_key(run_keys: ptr<function, array<vec2<u32>, 8>>, i: u32, item: u32) -> vec2<u32> {
    if STAGED_PAIRS > 1u {
        return (*run_keys)[i];
    }
    return keys_in[item];
}

// Ranks the round's pairs [first_item, first_item + 256 * RUN_ITEMS): the per-invocation digit
// counts, their exclusive scan over invocations, then each pair's output slot (see the header);
// the direct scatter writes each pair there, the staged one at its position in digit order in
// `staged_keys` and `digit_counts`. Counts the next pass's digits on the way.
fn rank_round(lid: u32, first_item: u32, n: u32, gather_next: bool) {
    let first = first_item + lid * RUN_ITEMS;
    // Staged: the round's keys are read into workgroup memory by neighbouring invocations
    // (coalesced loads), then each invocation takes its own run of 8 from there.
    var run_keys: array<vec2<u32>, 8>;
    if STAGED_PAIRS > 1u {
        for (var i = 0u; i < 8u; i++) {
            let item = first_item + i * WORKGROUP + lid;
            if item < n {
                staged_keys[i * WORKGROUP + lid] = keys_in[item];
            }
        }
        workgroupBarrier();
        for (var i = 0u; i < 8u; i++) {
            run_keys[i] = staged_keys[lid * 8u + i];
        }
    }
    var count = vec4<u32>(0u);
    for (var i = 0u; i < RUN_ITEMS; i++) {
        let item = first + i;
        if item < n {
            count += one_hot(digit_of(run_key(&run_keys, i, item)));
        }
    }
    store_digit_counts(count, lid);
    workgroupBarrier();
    // Invocation lid scans invocations [8s, 8s + 8) of word w (two digits at once: the halves
    // never carry, round counts stay below 2^16).
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
        round_counts[lid] = total;
    }
    workgroupBarrier();
    let slots0 = vec4<u32>(first_slot(0u, lid), first_slot(1u, lid), first_slot(2u, lid), first_slot(3u, lid));
    let slots1 = vec4<u32>(first_slot(4u, lid), first_slot(5u, lid), first_slot(6u, lid), first_slot(7u, lid));
    let slots2 = vec4<u32>(first_slot(8u, lid), first_slot(9u, lid), first_slot(10u, lid), first_slot(11u, lid));
    let slots3 = vec4<u32>(first_slot(12u, lid), first_slot(13u, lid), first_slot(14u, lid), first_slot(15u, lid));
    if STAGED_PAIRS > 1u {
        if lid < 16u {
            var start = 0u;
            for (var e = 0u; e < lid; e++) {
                start += round_count(e);
            }
            staged_starts[lid] = start;
        }
        // The slots are read: `digit_counts` may take the staged values.
        workgroupBarrier();
    }
    let size = tile_size();
    var seen = vec4<u32>(0u);
    for (var i = 0u; i < RUN_ITEMS; i++) {
        let item = first + i;
        if item < n {
            let key = run_key(&run_keys, i, item);
            let d = digit_of(key);
            let q = d >> 2u;
            let slots = select(select(slots0, slots1, q == 1u), select(slots2, slots3, q == 3u), q >= 2u);
            let dest = pick(slots, d & 3u) + ((pick(seen, q) >> ((d & 3u) * 8u)) & 0xffu);
            seen += one_hot(d);
            if STAGED_PAIRS > 1u {
                let local = staged_starts[d] + dest - round_offsets[d];
                staged_keys[local] = key;
                digit_counts[local] = values_in[item];
            } else {
                keys_out[dest] = key;
                values_out[dest] = values_in[item];
            }
            if gather_next {
                let second_tile = dest / size - tile_offsets[d] / size;
                let next = digit_at(key, params.next_shift, params.next_bits);
                atomicAdd(&next_digit_counts[(d * 2u + second_tile) * 16u + next], 1u);
            }
        }
    }
}

// Writes the round's staged pairs (`count` of them) to their output slots, neighbouring
// invocations to neighbouring slots, and moves `round_offsets` past them; ends with a barrier.
fn write_round(lid: u32, count: u32) {
    workgroupBarrier();
    for (var j = lid; j < count; j += WORKGROUP) {
        let key = staged_keys[j];
        let d = digit_of(key);
        let dest = round_offsets[d] + j - staged_starts[d];
        keys_out[dest] = key;
        values_out[dest] = digit_counts[j];
    }
    workgroupBarrier();
    if lid < 16u {
        round_offsets[lid] += round_count(lid);
    }
    workgroupBarrier();
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
    if lid < 16u {
        round_offsets[lid] = tile_offsets[lid];
    }
    let n = sort_count();
    // One round (direct), or the tile's rounds of 2048 pairs one after another (staged). The
    // direct scatter's round is outside the loop: lavapipe runs barriers in a loop, even one
    // that runs once, at a cost (its sort took 1.7x as long).
    rank_round(lid, tile * tile_size(), n, gather_next);
    if STAGED_PAIRS > 1u {
        for (var round = 0u; round < ROUNDS; round++) {
            let first = tile * tile_size() + round * STAGED_PAIRS;
            if round > 0u {
                rank_round(lid, first, n, gather_next);
            }
            write_round(lid, min(select(0u, n - first, n > first), STAGED_PAIRS));
        }
    }
    if gather_next {
        workgroupBarrier();
        for (var i = lid; i < 512u; i += WORKGROUP) {
            let count = atomicLoad(&next_digit_counts[i]);
            if count != 0u {
                let output_tile = tile_offsets[i >> 5u] / tile_size() + ((i >> 4u) & 1u);
                atomicAdd(&next_counts[(i & 15u) * params.num_tiles + output_tile], count);
            }
        }
    }
}
