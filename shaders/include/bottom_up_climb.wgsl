// The bottom-up climb of nodes_refit and costs_climb (Karras 2012 §4): each invocation whose
// leaf is done climbs parent links; a per-node atomic counter lets only the second arrival
// finish the parent from both children (`finish_parent`, which the including kernel defines:
// nodes_refit merges the children's boxes, costs_climb computes the collapse costs) and go on.
// WGSL atomics are relaxed, so what a child passes up goes through atomics, and storageBarriers
// order those stores before the counter increment (release) and the increment before the
// sibling's loads (acquire). Barriers need uniform control flow, so every invocation of a
// workgroup steps the loop together until all are done: call `climb` from uniform control flow.
// The including kernel declares `parents: array<u32>` and `arrivals: array<atomic<u32>>`
// (counters starting at zero) and `fn finish_parent(parent: u32)`.

var<workgroup> climbing: atomic<u32>;
var<workgroup> any_climbing: u32;

// Climbs from `leaf` (whose result is stored) when `has_leaf`; `lid` is the local invocation index.
fn climb(leaf: u32, has_leaf: bool, lid: u32) {
    if lid == 0u {
        atomicStore(&climbing, 0u);
    }
    workgroupBarrier();
    var node = leaf;
    var is_climbing = has_leaf && node != 0u;
    if is_climbing {
        atomicAdd(&climbing, 1u);
    }
    loop {
        // Release: this node's result is stored before the parent's counter is incremented.
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
        // Acquire: the sibling's result, stored before its increment, is visible now.
        storageBarrier();
        if is_climbing {
            finish_parent(parent);
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
