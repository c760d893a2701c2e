// Radix-sort histogram (one LSD pass of `sort::RadixSort`, reduce-then-scan step 1): each workgroup
// counts the 8-bit digits at `params.shift` (only the low `params.bits` of them) of its tile of
// TILE keys with workgroup atomics and writes the counts digit-major, counts[digit * num_tiles + tile],
// so that one exclusive scan of `counts` gives every (digit, tile) its first output position.
// Tiles are linear workgroup indices over a 1D or 2D grid: wid.x + wid.y * num_workgroups.x.
// TILE, SortParams and digit_of must match keys_scatter.wgsl and src/sort/radix_sort.rs.

const WORKGROUP: u32 = 256u;
const ROUNDS: u32 = 8u;
const TILE: u32 = 2048u; // WORKGROUP * ROUNDS keys per workgroup

struct SortParams {
    n: u32,
    num_tiles: u32,
    shift: u32,
    bits: u32,
}

@group(0) @binding(0) var<uniform> params: SortParams;
@group(0) @binding(1) var<storage, read> keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read_write> counts: array<u32>;

var<workgroup> bins: array<atomic<u32>, 256>;

// The digit of a 64-bit key (x = low word, y = high word); shifts are multiples of 8, so a digit
// never straddles the two words.
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
    atomicStore(&bins[lid], 0u);
    workgroupBarrier();
    let first = tile * TILE + lid;
    for (var r = 0u; r < ROUNDS; r++) {
        let item = first + r * WORKGROUP;
        if item < params.n {
            atomicAdd(&bins[digit_of(keys[item])], 1u);
        }
    }
    workgroupBarrier();
    counts[lid * params.num_tiles + tile] = atomicLoad(&bins[lid]);
}
