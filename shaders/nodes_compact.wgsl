// Leaf collapse, step 2: compaction into the traversal layout. After exclusive scans of the kept
// flags (new node indices; the root stays 0) and of the output leaves' primitive counts (first
// entry of each leaf's range), one invocation per kept node writes its output node; an output
// leaf gathers the primitives of its working subtree in depth-first order (left first) into its
// range. Invocation 0 also writes the output's node and primitive counts.
#include "bvh_node.wgsl"

const STACK_SIZE: u32 = 64u;

struct CompactParams {
    node_count: u32,
    row_pitch: u32,
    prim_count: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: CompactParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(3) var<storage, read> prim_counts: array<u32>;
@group(0) @binding(4) var<storage, read> flags: array<u32>;
@group(0) @binding(5) var<storage, read> kept_scan: array<u32>;
@group(0) @binding(6) var<storage, read> leaf_prim_scan: array<u32>;
@group(0) @binding(7) var<storage, read_write> out_nodes: array<BvhNode>;
@group(0) @binding(8) var<storage, read_write> out_prims: array<u32>;
// [0]: output nodes, [1]: output primitive references
@group(0) @binding(9) var<storage, read_write> tree_counts: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    if i == 0u {
        let last = params.node_count - 1u;
        tree_counts[0] = kept_scan[last] + (flags[last] & 1u);
        tree_counts[1] = params.prim_count;
    }
    if i >= params.node_count || (flags[i] & 1u) == 0u {
        return;
    }
    let node = nodes[i];
    let out = kept_scan[i];
    if (flags[i] & 2u) != 0u {
        let first = leaf_prim_scan[i];
        var written = 0u;
        var stack: array<u32, STACK_SIZE>;
        var sp = 1u;
        stack[0] = i;
        while sp > 0u {
            sp--;
            let n = nodes[stack[sp]];
            if (n.right_or_count & LEAF_FLAG) != 0u {
                let end = n.left_or_first + (n.right_or_count & ~LEAF_FLAG);
                for (var k = n.left_or_first; k < end; k++) {
                    out_prims[first + written] = prim_indices[k];
                    written++;
                }
            } else {
                // Right first on the stack, so the left subtree is gathered first.
                stack[sp] = n.right_or_count;
                stack[sp + 1u] = n.left_or_first;
                sp += 2u;
            }
        }
        out_nodes[out] = BvhNode(node.min, first, node.max, LEAF_FLAG | prim_counts[i]);
    } else {
        out_nodes[out] = BvhNode(node.min, kept_scan[node.left_or_first], node.max, kept_scan[node.right_or_count]);
    }
}
