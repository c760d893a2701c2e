// Gathers the primitives under a working-tree node depth-first (left first) into `gathered`,
// mapped to triangle ids through `ref_tris` with duplicates dropped when `params.has_refs` is
// set; returns their number. Output leaves hold at most MAX_GPU_LEAF_SIZE primitives (the
// collapse's max leaf size limit). The including kernel declares `nodes`, `prim_indices`, `ref_tris` and
// `params.has_refs`.

// The stack holds disjoint subtrees of the leaf's, each of at least one primitive.
const GATHER_STACK: u32 = MAX_GPU_LEAF_SIZE;

var<private> gathered: array<u32, MAX_GPU_LEAF_SIZE>;

fn gather_leaf(root: u32) -> u32 {
    var count = 0u;
    var stack: array<u32, GATHER_STACK>;
    var sp = 1u;
    stack[0] = root;
    while sp > 0u {
        sp--;
        let n = nodes[stack[sp]];
        if (n.right_or_count & LEAF_FLAG) != 0u {
            let end = n.left_or_first + (n.right_or_count & ~LEAF_FLAG);
            for (var k = n.left_or_first; k < end; k++) {
                var prim = prim_indices[k];
                var fresh = count < MAX_GPU_LEAF_SIZE;
                if params.has_refs != 0u {
                    prim = ref_tris[prim];
                    for (var j = 0u; j < count; j++) {
                        fresh = fresh && gathered[j] != prim;
                    }
                }
                if fresh {
                    gathered[count] = prim;
                    count++;
                }
            }
        } else if sp + 2u <= GATHER_STACK {
            // Right first on the stack, so the left subtree is gathered first.
            stack[sp] = n.right_or_count;
            stack[sp + 1u] = n.left_or_first;
            sp += 2u;
        }
    }
    return count;
}
