// Radix-sort stable scatter (one LSD pass of `sort::RadixSort`, reduce-then-scan step 3): each
// workgroup ranks its tile of TILE (key, value) pairs by the 8-bit digit at `params.shift` (low
// `params.bits` bits) stably and writes each pair to offsets[digit * num_tiles + tile] + rank, where
// `offsets` is the exclusive scan of the keys_histogram.wgsl counts.
//
// Stable ranking without subgroup operations: "match"-style multisplit ranking (as in CUB's
// BlockRadixRankMatch and Onesweep, Adinets & Merrill 2022) with subgroup ballots emulated in
// workgroup memory. The 256 invocations form 8 virtual warps of 32 lanes; warp w owns the
// contiguous slice [w * 256, (w + 1) * 256) of the tile and walks it in 8 rounds of 32 pairs.
// In each round every lane moves its bit in peers[warp][digit] from last round's digit to this
// round's (atomicAnd/atomicOr), so after a barrier peers[warp][digit] is the set of lanes holding
// that digit; the lane's rank within its warp is the count of that digit in earlier rounds plus the
// lower peers, and the highest peer adds the round's count. After the last round the per-warp
// counts are turned into exclusive prefixes over warps. Order of ranks = (warp, round, lane) =
// element order, hence stable. Two barriers per round; 13 KiB of workgroup memory.
// Tiles are linear workgroup indices over a 1D or 2D grid: wid.x + wid.y * num_workgroups.x.
// TILE, SortParams and digit_of must match keys_histogram.wgsl and src/sort/radix_sort.rs.

const WORKGROUP: u32 = 256u;
const RADIX: u32 = 256u;
const LANES: u32 = 32u; // lanes of a virtual warp = bits of a peers mask
const ROUNDS: u32 = 8u;
const WARP_ITEMS: u32 = 256u; // LANES * ROUNDS pairs per virtual warp
const TILE: u32 = 2048u; // WORKGROUP * ROUNDS pairs per workgroup
const NONE: u32 = 0xffffffffu;

struct SortParams {
    n: u32,
    num_tiles: u32,
    shift: u32,
    bits: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;
@group(0) @binding(1) var<storage, read> keys_in: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> values_in: array<u32>;
@group(0) @binding(3) var<storage, read> offsets: array<u32>;
@group(0) @binding(4) var<storage, read_write> keys_out: array<vec2<u32>>;
@group(0) @binding(5) var<storage, read_write> values_out: array<u32>;

// [warp][digit]: bit l set when lane l of the warp holds that digit in the current round.
var<workgroup> peers: array<atomic<u32>, 2048>;
// [warp / 2][digit], warp parity selects the 16-bit half: pairs of that digit the warp has ranked;
// after the last round, the tile-local exclusive prefix over warps instead.
var<workgroup> warp_counts: array<atomic<u32>, 1024>;
// First output position of each digit for this tile.
var<workgroup> digit_base: array<u32, 256>;

fn digit_of(key: vec2<u32>) -> u32 {
    let word = select(key.x, key.y, params.shift >= 32u);
    return (word >> (params.shift & 31u)) & ((1u << params.bits) - 1u);
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
    for (var i = 0u; i < 8u; i++) {
        atomicStore(&peers[i * RADIX + lid], 0u);
    }
    for (var i = 0u; i < 4u; i++) {
        atomicStore(&warp_counts[i * RADIX + lid], 0u);
    }
    digit_base[lid] = offsets[lid * params.num_tiles + tile];
    workgroupBarrier();

    let warp = lid / LANES;
    let lane = lid % LANES;
    let lane_bit = 1u << lane;
    let peers_row = warp * RADIX;
    let count_row = (warp >> 1u) * RADIX;
    let count_shift = (warp & 1u) * 16u;
    let first = tile * TILE + warp * WARP_ITEMS + lane;
    var ranks: array<u32, ROUNDS>;
    var prev = NONE;
    for (var r = 0u; r < ROUNDS; r++) {
        let item = first + r * LANES;
        var digit = NONE;
        if item < params.n {
            digit = digit_of(keys_in[item]);
        }
        if digit != prev {
            if prev != NONE {
                atomicAnd(&peers[peers_row + prev], ~lane_bit);
            }
            if digit != NONE {
                atomicOr(&peers[peers_row + digit], lane_bit);
            }
        }
        workgroupBarrier();
        var mask = 0u;
        if digit != NONE {
            mask = atomicLoad(&peers[peers_row + digit]);
            let before = (atomicLoad(&warp_counts[count_row + digit]) >> count_shift) & 0xffffu;
            ranks[r] = before + countOneBits(mask & (lane_bit - 1u));
        }
        workgroupBarrier();
        // The highest peer of the round adds the round's count for the next rounds.
        if digit != NONE && (mask >> lane) == 1u {
            atomicAdd(&warp_counts[count_row + digit], countOneBits(mask) << count_shift);
        }
        prev = digit;
    }
    workgroupBarrier();

    // Invocation `lid` owns digit `lid`: per-warp counts -> exclusive prefix over warps (< TILE).
    var run = 0u;
    for (var i = 0u; i < 4u; i++) {
        let packed = atomicLoad(&warp_counts[i * RADIX + lid]);
        let even = packed & 0xffffu;
        atomicStore(&warp_counts[i * RADIX + lid], run | ((run + even) << 16u));
        run += even + (packed >> 16u);
    }
    workgroupBarrier();

    for (var r = 0u; r < ROUNDS; r++) {
        let item = first + r * LANES;
        if item < params.n {
            let key = keys_in[item];
            let digit = digit_of(key);
            let prefix = (atomicLoad(&warp_counts[count_row + digit]) >> count_shift) & 0xffffu;
            let dest = digit_base[digit] + prefix + ranks[r];
            keys_out[dest] = key;
            values_out[dest] = values_in[item];
        }
    }
}
