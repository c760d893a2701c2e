// Bottom-up bounds (Karras 2012 §4): one invocation per leaf writes its leaf node, then climbs
// parent links, the second arrival at each node merging both children (`climb`,
// bottom_up_climb.wgsl, which also documents the memory ordering).
// Input: primitive boxes, prim_indices (sorted values), children from lbvh_hierarchy. Counters
// must start at zero.
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "items.wgsl"

const WORKGROUP: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> prim_boxes: array<Aabb>;
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(3) var<storage, read> parents: array<u32>;
@group(0) @binding(4) var<storage, read_write> node_words: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> arrivals: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): the kernel works on min(params.count, count_limit[0]).
@group(0) @binding(6) var<storage, read> count_limit: array<u32>;

#include "node_words.wgsl"
#include "bottom_up_climb.wgsl"

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = gid.x + gid.y * params.row_pitch;
    let n = min(params.count, count_limit[0]);
    let node = n - 1u + j;
    if j < n {
        let b = prim_boxes[prim_indices[j]];
        store_box(node, b.min, b.max);
        atomicStore(&node_words[node * 8u + 3u], j);
        atomicStore(&node_words[node * 8u + 7u], LEAF_FLAG | 1u);
    }
    climb(node, j < n, lid);
}
