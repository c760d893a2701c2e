// Bottom-up bounds (Karras 2012 §4): one invocation per leaf writes its leaf node, then climbs
// parent links; a per-node atomic counter lets only the second arrival merge both children and go
// on. WGSL atomics are relaxed, so the ordering is made explicit: node boxes are written and read
// with atomics (`node_words`: 8 words per BvhNode), a storageBarrier (device-scope acquire/release
// on storage memory) separates the box stores from the counter increment (release) and the
// increment from the sibling's box loads (acquire). Barriers need uniform control flow, so every
// invocation of a workgroup steps the climb loop together until all of them are done.
// Input: primitive boxes, prim_indices (sorted values), children from lbvh_hierarchy. Counters
// must start at zero.
#include "bvh_node.wgsl"
#include "aabb.wgsl"

const WORKGROUP: u32 = 64u;

struct RefitParams {
    count: u32,
    row_pitch: u32,
    pad0: u32,
    pad1: u32,
}

@group(0) @binding(0) var<uniform> params: RefitParams;
@group(0) @binding(1) var<storage, read> prim_boxes: array<Aabb>;
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(3) var<storage, read> parents: array<u32>;
@group(0) @binding(4) var<storage, read_write> node_words: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> arrivals: array<atomic<u32>>;

var<workgroup> climbing: atomic<u32>;
var<workgroup> any_climbing: u32;

#include "node_words.wgsl"

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = gid.x + gid.y * params.row_pitch;
    let n = params.count;
    var node = n - 1u + j;
    var is_climbing = false;
    if lid == 0u {
        atomicStore(&climbing, 0u);
    }
    workgroupBarrier();
    if j < n {
        let b = prim_boxes[prim_indices[j]];
        store_box(node, b.min, b.max);
        atomicStore(&node_words[node * 8u + 3u], j);
        atomicStore(&node_words[node * 8u + 7u], LEAF_FLAG | 1u);
        is_climbing = node != 0u;
        if is_climbing {
            atomicAdd(&climbing, 1u);
        }
    }
    loop {
        // Release: this node's box is stored before the parent's counter is incremented.
        storageBarrier();
        var parent = 0u;
        if is_climbing {
            parent = parents[node];
            if atomicAdd(&arrivals[parent], 1u) == 0u {
                // First arrival: the sibling's invocation will finish the parent.
                is_climbing = false;
                atomicSub(&climbing, 1u);
            }
        }
        // Acquire: the sibling's box, stored before its increment, is visible now.
        storageBarrier();
        if is_climbing {
            let w = parent * 8u;
            let left = atomicLoad(&node_words[w + 3u]);
            let right = atomicLoad(&node_words[w + 7u]);
            store_box(parent, min(load_min(left), load_min(right)), max(load_max(left), load_max(right)));
            node = parent;
            if node == 0u {
                is_climbing = false;
                atomicSub(&climbing, 1u);
            }
        }
        workgroupBarrier();
        if lid == 0u {
            any_climbing = atomicLoad(&climbing);
        }
        if workgroupUniformLoad(&any_climbing) == 0u {
            break;
        }
    }
}
