// SAH-optimal wide collapse, step 1 (src/bvh/wide/converter.rs): every internal node of the
// binary tree links its two children to itself (`parents`) and zeroes its arrival counter for
// the bottom-up climb of costs_climb.wgsl. One invocation per node of the tree, whose node count
// the GPU holds (`count_limit`, the tree's counts).
#include "bvh_node.wgsl"
#include "items.wgsl"

@group(0) @binding(0) var<uniform> params: Items;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read_write> parents: array<u32>;
@group(0) @binding(3) var<storage, read_write> arrivals: array<u32>;
@group(0) @binding(4) var<storage, read> count_limit: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i >= min(params.count, count_limit[0]) {
        return;
    }
    arrivals[i] = 0u;
    let node = nodes[i];
    if (node.right_or_count & LEAF_FLAG) == 0u {
        parents[node.left_or_first] = i;
        parents[node.right_or_count] = i;
    }
}
