// A 128-bit fingerprint of a buffer's words (src/bvh/fingerprint.rs; CPU twin `words_hash_cpu`):
// each word w at index i adds mix_k(key, w) to four 32-bit sums (k = 0..3, different seeds), the
// key being i (`positional`: the words' order counts) or i mod `stride` (the buffer as a multiset
// of records of `stride` words, e.g. wide nodes, whose numbering the conversion's atomics choose).
// Words whose position in their record is set in `skipped` (stride <= 32) are left out. Sums
// wrap, so the result does not depend on the order in which workgroups add: equal to the CPU's
// exactly on every device. A workgroup hashes a tile of 256 * ITEMS words, each invocation every
// 256th (neighbouring invocations load neighbouring words), adds its sums to the workgroup's in
// workgroup memory, and the workgroup adds its four to `hash` (zeroed before the dispatch).
#include "random.wgsl"

struct HashParams {
    count: u32,
    row_pitch: u32,
    words: u32,
    stride: u32,
    skipped: u32,
    positional: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: HashParams;
@group(0) @binding(1) var<storage, read> words: array<u32>;
@group(0) @binding(2) var<storage, read_write> hash: array<atomic<u32>, 4>;

var<workgroup> sums: array<atomic<u32>, 4>;

// Word w's term of sum k (seeded by `seed`) at `key`: two rounds of a bijective hash, so that
// the terms of two different (word, key) pairs are unrelated.
fn mix(w: u32, seed: u32, key: u32) -> u32 {
    return pcg_hash(pcg_hash(w ^ seed) + key * 0x9e3779b9u);
}

// Words per invocation (`fingerprint::HASH_ITEMS`).
const ITEMS: u32 = 16u;

// `params.count` is the number of invocations (words / ITEMS, rounded up).
@compute @workgroup_size(256)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let invocation = gid.x + gid.y * params.row_pitch;
    let first = (invocation - lid) * ITEMS + lid;
    var local = vec4<u32>(0u);
    for (var k = 0u; k < ITEMS; k++) {
        let i = first + k * 256u;
        let position = i % params.stride;
        if i < params.words && ((params.skipped >> position) & 1u) == 0u {
            let key = select(position, i, params.positional != 0u);
            let w = words[i];
            local += vec4<u32>(mix(w, 0x243f6a88u, key), mix(w, 0x85a308d3u, key), mix(w, 0x13198a2eu, key), mix(w, 0x03707344u, key));
        }
    }
    atomicAdd(&sums[0], local.x);
    atomicAdd(&sums[1], local.y);
    atomicAdd(&sums[2], local.z);
    atomicAdd(&sums[3], local.w);
    workgroupBarrier();
    if lid < 4u {
        atomicAdd(&hash[lid], atomicLoad(&sums[lid]));
    }
}
