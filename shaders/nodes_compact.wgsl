// Leaf collapse, step 2: compaction into the traversal layout. After exclusive scans of the kept
// flags (new node indices; the root stays 0) and of the output leaves' primitive counts (first
// entry of each leaf's range), one invocation per kept node writes its output node. An output
// leaf's range holds the primitives of its working subtree in depth-first order (left first), as
// unique triangle ids when they are pre-split references: each working leaf writes its own where
// nodes_mark.wgsl found (`leaf_slots`), no subtree is walked. Invocation 0 also writes the
// output's node and primitive counts.
#include "bvh_node.wgsl"

struct CompactParams {
    // Leaves of the working tree (at most; see count_limit): it has 2n - 1 nodes.
    leaf_count: u32,
    row_pitch: u32,
    has_refs: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: CompactParams;
@group(0) @binding(1) var<storage, read> nodes: array<BvhNode>;
@group(0) @binding(2) var<storage, read> prim_indices: array<u32>;
@group(0) @binding(3) var<storage, read> flags: array<u32>;
// Two columns of 2·leaf_count - 1, each scanned block by block (sort::PrefixScan's block-local
// scan): new node indices, then the first primitive of each output leaf; see `scanned`.
@group(0) @binding(4) var<storage, read> scans: array<u32>;
// The scanned block totals: column c's block b at c·blocks + b.
@group(0) @binding(5) var<storage, read> block_offsets: array<u32>;
@group(0) @binding(6) var<storage, read_write> out_nodes: array<BvhNode>;
@group(0) @binding(7) var<storage, read_write> out_prims: array<u32>;
// [0]: output nodes, [1]: output primitive references
@group(0) @binding(8) var<storage, read_write> tree_counts: array<u32>;
@group(0) @binding(9) var<storage, read> ref_tris: array<u32>;
// Totals of the two scans.
@group(0) @binding(10) var<storage, read> totals: array<u32>;
// The item count's limit (`gpu::ItemCount`): the tree has min(params.leaf_count, count_limit[0])
// leaves.
@group(0) @binding(11) var<storage, read> count_limit: array<u32>;
// Per working leaf, its output leaf and its position there (NO_SLOT: none; nodes_mark.wgsl).
@group(0) @binding(12) var<storage, read> leaf_slots: array<vec2<u32>>;

const KEPT: u32 = 0u;
const LEAF_PRIMS: u32 = 1u;

// Element i of the exclusive scan of `column`: its block-local value plus its block's offset.
fn scanned(column: u32, i: u32) -> u32 {
    let len = 2u * params.leaf_count - 1u;
    let blocks = (len + SCAN_BLOCK - 1u) / SCAN_BLOCK;
    return scans[column * len + i] + block_offsets[column * blocks + i / SCAN_BLOCK];
}

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * params.row_pitch;
    let node_count = 2u * min(params.leaf_count, count_limit[0]) - 1u;
    if i == 0u {
        tree_counts[0] = totals[KEPT];
        tree_counts[1] = totals[LEAF_PRIMS];
    }
    if i >= node_count {
        return;
    }
    let node = nodes[i];
    if (node.right_or_count & LEAF_FLAG) != 0u {
        let slot = leaf_slots[node.left_or_first];
        if slot.y != NO_SLOT {
            let at = scanned(LEAF_PRIMS, slot.x) + slot.y;
            for (var k = 0u; k < (node.right_or_count & ~LEAF_FLAG); k++) {
                var prim = prim_indices[node.left_or_first + k];
                if params.has_refs != 0u {
                    prim = ref_tris[prim];
                }
                out_prims[at + k] = prim;
            }
        }
    }
    let flag = flags[i];
    if (flag & 1u) == 0u {
        return;
    }
    let out = scanned(KEPT, i);
    if (flag & 2u) != 0u {
        let first = scanned(LEAF_PRIMS, i);
        // The next node's scanned entry (the total after the last node: the nodes past the tree
        // add nothing).
        let len = 2u * params.leaf_count - 1u;
        let next = select(totals[LEAF_PRIMS], scanned(LEAF_PRIMS, min(i + 1u, len - 1u)), i + 1u < len);
        out_nodes[out] = BvhNode(node.min, first, node.max, LEAF_FLAG | (next - first));
    } else {
        out_nodes[out] = BvhNode(node.min, scanned(KEPT, node.left_or_first), node.max, scanned(KEPT, node.right_or_count));
    }
}
