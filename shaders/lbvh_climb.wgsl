// LBVH stages 4-5 in one bottom-up climb: the hierarchy (Karras 2012's binary radix tree and node
// layout, found bottom-up as in Apetrei 2014: radix_climb.wgsl) and the bounds (Karras 2012 §4).
// One invocation per leaf writes its leaf node and climbs; the second arrival at each parent
// writes the parent's children, their parent links and the parent's box. Internal nodes are
// 0..n-2 (root 0), leaf j is node n-1+j. Node data is shared across workgroups, so it goes
// through atomics (node_words.wgsl), ordered around the arrivals by storageBarriers (release
// before, acquire after, as in bottom_up_climb.wgsl). Arrivals must be zero, and are again after.
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "items.wgsl"

const WORKGROUP: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Items;
// The sorted keys (low word first) and the primitive of each leaf.
@group(0) @binding(1) var<storage, read> keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> prim_boxes: array<Aabb>;
@group(0) @binding(3) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(4) var<storage, read_write> node_words: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> parents: array<u32>;
// Per split: 0, or the far end + 1 of the first child to arrive (radix_climb.wgsl).
@group(0) @binding(6) var<storage, read_write> arrivals: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): the kernel works on min(params.count, count_limit[0]).
@group(0) @binding(7) var<storage, read> count_limit: array<u32>;

#include "node_words.wgsl"
#include "radix_climb.wgsl"

var<workgroup> climbing: atomic<u32>;
var<workgroup> any_climbing: u32;

@compute @workgroup_size(WORKGROUP)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = gid.x + gid.y * params.row_pitch;
    leaf_count = min(params.count, count_limit[0]);
    if lid == 0u {
        atomicStore(&climbing, 0u);
    }
    workgroupBarrier();
    var r = RangeNode(0u, 0u, 0u, 0u, 0u, false);
    var is_climbing = false;
    if j < leaf_count {
        r = emit_leaf(j, prim_boxes[prim_indices[j]]);
        is_climbing = r.node != 0u;
        if is_climbing {
            atomicAdd(&climbing, 1u);
        }
    }
    loop {
        // Release: this node's data is stored before the arrival.
        storageBarrier();
        var sibling = 0u;
        if is_climbing {
            sibling = arrive(r);
            if sibling == 0u {
                // First arrival: the sibling's invocation will finish the parent.
                is_climbing = false;
                atomicSub(&climbing, 1u);
            }
        }
        // Acquire: the sibling's data, stored before its arrival, is visible now.
        storageBarrier();
        if is_climbing {
            r = emit_parent(r, sibling).range;
            if r.node == 0u {
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
