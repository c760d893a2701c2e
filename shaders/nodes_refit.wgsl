// Refit of a fixed tree (src/bvh/nodes_refit.rs): the topology (child links, leaf ranges, prim_indices)
// stays that of the tree built at the first frame; only the boxes follow the moved triangles. Any
// tree in the node layout works (LBVH, or a TRBVH tree after collapse and compaction, leaves of
// several primitives) given its parent links and the list of its leaves.
//
// One invocation per leaf stores the leaf's box (union of its triangles) and climbs parent links
// with `climb` (bottom_up_climb.wgsl: atomics and storageBarriers order the box stores and
// counter increments, as in lbvh_climb.wgsl). Child and leaf words are only read. Counters must start
// at zero.
#include "bvh_node.wgsl"
#include "items.wgsl"

// Invocations per workgroup: 64, or the device's climb width (`Kernel::climb`; 8 on CPU devices).
override WORKGROUP_WIDTH: u32 = 64u;

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> triangles: array<Triangle>;
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(3) var<storage, read> leaves: array<u32>;
@group(0) @binding(4) var<storage, read> parents: array<u32>;
@group(0) @binding(5) var<storage, read_write> node_words: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> arrivals: array<atomic<u32>>;

#include "node_words.wgsl"
#include "bottom_up_climb.wgsl"

// The parent's box: the union of its children's.
fn finish_parent(parent: u32) {
    let w = parent * 8u;
    let left = atomicLoad(&node_words[w + 3u]);
    let right = atomicLoad(&node_words[w + 7u]);
    store_box(parent, min(load_min(left), load_min(right)), max(load_max(left), load_max(right)));
}

@compute @workgroup_size(WORKGROUP_WIDTH)
fn main(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let j = gid.x + gid.y * params.row_pitch;
    var node = 0u;
    if j < params.count {
        node = leaves[j];
        let first = atomicLoad(&node_words[node * 8u + 3u]);
        let count = atomicLoad(&node_words[node * 8u + 7u]) & ~LEAF_FLAG;
        var lo = vec3<f32>(3.40282347e38);
        var hi = vec3<f32>(-3.40282347e38);
        for (var c = 0u; c < count; c++) {
            let t = triangles[prim_indices[first + c]];
            lo = min(lo, min(t.v0, min(t.v1, t.v2)));
            hi = max(hi, max(t.v0, max(t.v1, t.v2)));
        }
        store_box(node, lo, hi);
    }
    climb(node, j < params.count, lid);
}
