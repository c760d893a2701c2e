// Morton keys of primitive box centroids normalized to the scene's centroid bounds (LBVH stage 2,
// Karras 2012 §4), and the identity permutation as sort values. Centroids are quantized on a grid
// of MORTON_GRID (2^21) cells per axis; the full key interleaves the high MORTON_AXIS_BITS (16) bits
// of each axis (48 bits: bit 3k+2 holds x's kept bit k, 3k+1 y's, 3k z's), and the kernel writes its
// high `params.key_bits` bits. The grid is cubic (cell size from the longest side), so thin axes do
// not waste top-level splits. Keys are vec2<u32>(low 32 bits, high 32 bits); they can carry the
// sort's value (the index) above their bits instead (`params.packed`).
#include "constants.wgsl"
#include "box_words.wgsl"

// Rust twin: `MortonParams` (src/bvh/lbvh/morton_compute.rs).
struct MortonParams {
    count: u32,
    row_pitch: u32,
    // 1..=48: the high bits of the full key that the key keeps.
    key_bits: u32,
    // 1: the index goes above the key's bits, not in `values` (`sort::packs_indices`, sorted by
    // `RadixSort::record` with `SortValues::AboveKeys`); 0: in `values`.
    packed: u32,
}

@group(0) @binding(0) var<uniform> params: MortonParams;
@group(0) @binding(1) var<storage, read> prim_boxes: array<Aabb>;
// The centroid bounds as box words (box_words.wgsl).
@group(0) @binding(2) var<storage, read> centroid_bounds: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read_write> keys: array<vec2<u32>>;
@group(0) @binding(4) var<storage, read_write> values: array<u32>;
// The item count's limit (`gpu::ItemCount`): the kernel works on min(params.count, count_limit[0]).
@group(0) @binding(5) var<storage, read> count_limit: array<u32>;

// Grid bits per axis below the kept ones.
const DROPPED_BITS: u32 = 21u - MORTON_AXIS_BITS;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= min(params.count, count_limit[0]) {
        return;
    }
    let c = (prim_boxes[i].min + prim_boxes[i].max) * 0.5;
    let bounds = box_of_words(centroid_bounds[0], centroid_bounds[1]);
    let e = bounds.max - bounds.min;
    let extent = max(e.x, max(e.y, e.z));
    let scale = select(0.0, MORTON_GRID / extent, extent > 0.0);
    let q = vec3<u32>(clamp((c - bounds.min) * scale, vec3<f32>(0.0), vec3<f32>(MORTON_GRID_MAX))) >> vec3<u32>(DROPPED_BITS);
    var key = vec2<u32>(0u);
    for (var bit = 0u; bit < MORTON_AXIS_BITS; bit++) {
        for (var axis = 0u; axis < 3u; axis++) {
            let position = 3u * bit + 2u - axis;
            let value = (q[axis] >> bit) & 1u;
            if position < 32u {
                key.x |= value << position;
            } else {
                key.y |= value << (position - 32u);
            }
        }
    }
    // Shift the 48-bit key right by 48 - key_bits.
    let drop = 3u * MORTON_AXIS_BITS - params.key_bits;
    if drop >= 32u {
        key = vec2<u32>(key.y >> (drop - 32u), 0u);
    } else if drop > 0u {
        key = vec2<u32>((key.x >> drop) | (key.y << (32u - drop)), key.y >> drop);
    }
    let bits = params.key_bits;
    if params.packed == 0u {
        values[i] = i;
    } else if bits >= 32u {
        key.y |= i << (bits - 32u);
    } else {
        key = vec2<u32>(key.x | (i << bits), i >> (32u - bits));
    }
    keys[i] = key;
}
