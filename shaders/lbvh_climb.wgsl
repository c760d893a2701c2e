// LBVH stages 4-5 in one bottom-up climb: the hierarchy (Karras 2012's binary radix tree and node
// layout, found bottom-up as in Apetrei 2014: radix_climb.wgsl) and the bounds (Karras 2012 §4).
// One invocation per leaf writes its leaf node and climbs; the second arrival at each parent
// writes the parent's children, their parent links and the parent's box (radix_climb.wgsl's
// `climb`, which also orders the node data around the arrivals). Internal nodes are 0..n-2 (root
// 0), leaf j is node n-1+j. Arrivals must be zero, and are again after.
#include "bvh_node.wgsl"
#include "aabb.wgsl"
#include "items.wgsl"

// Invocations per workgroup: 64, or the device's climb width (`Kernel::climb`; 8 on CPU devices).
override WORKGROUP_WIDTH: u32 = 64u;

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

// Nothing beyond the children, parent links and box that emit_parent stores.
fn finish_parent(p: EmittedParent) {}

@compute @workgroup_size(WORKGROUP_WIDTH)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = gid.x + gid.y * params.row_pitch;
    leaf_count = min(params.count, count_limit[0]);
    var leaf = RangeNode(0u, 0u, 0u, 0u, 0u, false);
    var leaf_box: Aabb;
    if j < leaf_count {
        leaf_box = prim_boxes[prim_indices[j]];
        leaf = emit_leaf(j, leaf_box);
    }
    climb(leaf, leaf_box, j < leaf_count, lid);
}
