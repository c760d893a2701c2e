// The levels of the binary-to-wide conversion below the last level dispatch: an indirect dispatch
// sized by the record that dispatch wrote, whose workgroups take that record's level's wide nodes
// (the roots of disjoint subtrees) 64 at a time and emit their subtrees (wide_collapse.wgsl).
// Each step every busy invocation emits one node (a wave: one device atomic per counter
// allocates its children and references), until none is busy. An invocation walks its subtree
// depth-first without a stack: a node with internal children keeps its parent and the end of its
// siblings in its `wide_sources` entry (its source is no longer needed; one load gives a
// step up both, where the parent's link and then the parent's node took two round trips to
// memory), and siblings are consecutive. To
// keep the invocations busy it gives a node's children but the last to a pool of subtree roots in
// workgroup memory, which idle invocations take from (the walk then goes on with the children the
// pool had no room for); a deep, lopsided tail costs about its nodes / 64 + its depth in steps per
// workgroup instead of a dispatch per level.
#include "wide_collapse.wgsl"

// Subtree roots the workgroup's pool holds at most (Rust twin: `FINISH_POOL` in
// src/bvh/wide/converter.rs; tests set less, so that the pool fills).
override POOL: u32 = 1024u;

var<workgroup> pool: array<u32, POOL>;
// Roots in the pool (may pass POOL while invocations reserve room: what lies past it was kept by
// its giver), and the roots idle invocations take this step.
var<workgroup> pool_top: atomic<u32>;
var<workgroup> pool_takes: atomic<u32>;
// Invocations of the workgroup with a node to emit (counted afresh each step).
var<workgroup> walkers: atomic<u32>;
var<workgroup> walking: u32;

@compute @workgroup_size(64)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let range = record_range(params.level);
    let first = range.x;
    let end = range.y;
    // The workgroups stride over the level's nodes a wave at a time.
    let stride = groups.x * EMIT_WORKGROUP;
    for (var wave = first + wid.x * EMIT_WORKGROUP; wave < end; wave += stride) {
        // The subtree being walked: its root, the node to emit next, that node's parent (below
        // the root) and the end of its siblings.
        var root = wave + lid;
        var walks = root < end;
        var node = root;
        var parent = root;
        var siblings_end = root + 1u;
        loop {
            // The previous step's gifts are in the pool (workgroup memory), and their sources,
            // which other invocations wrote, are stored (storage memory).
            workgroupBarrier();
            storageBarrier();
            if !walks {
                let top = min(atomicLoad(&pool_top), POOL);
                let take = atomicAdd(&pool_takes, 1u);
                if take < top {
                    root = pool[top - 1u - take];
                    walks = true;
                    node = root;
                    parent = root;
                    siblings_end = root + 1u;
                }
            }
            if walks {
                atomicAdd(&walkers, 1u);
            }
            workgroupBarrier();
            if lid == 0u {
                let top = min(atomicLoad(&pool_top), POOL);
                atomicStore(&pool_top, top - min(atomicExchange(&pool_takes, 0u), top));
                walking = atomicExchange(&walkers, 0u);
            }
            // None busy: the pool is empty too (an idle invocation would have taken a root).
            if workgroupUniformLoad(&walking) == 0u {
                break;
            }
            let children = emit_wave_node(node, walks, lid);
            if walks && children.y > 0u {
                // The first children but the last go to the pool, as far as it has room; the
                // walk goes on with the others.
                var given = 0u;
                if children.y > 1u {
                    let at = atomicAdd(&pool_top, children.y - 1u);
                    given = min(children.y - 1u, POOL - min(at, POOL));
                    for (var k = 0u; k < given; k++) {
                        pool[at + k] = children.x + k;
                    }
                }
                wide_sources[node] = vec2<u32>(parent, siblings_end);
                parent = node;
                node = children.x + given;
                siblings_end = children.x + children.y;
            } else if walks {
                // The next sibling of the node or of its nearest ancestor below the root with one.
                loop {
                    if node == root {
                        walks = false;
                        break;
                    }
                    if node + 1u < siblings_end {
                        node++;
                        break;
                    }
                    node = parent;
                    if node != root {
                        let link = wide_sources[node];
                        parent = link.x;
                        siblings_end = link.y;
                    }
                }
            }
        }
    }
}
