// A workgroup's share of a box reduction (box_words.wgsl): a tile of REDUCE_TILE items, four per
// invocation; the workgroup's invocations reduce their boxes in workgroup memory, then
// invocation 0 adds the result to the box words with six atomicMax (an empty box adds nothing).
// The including kernel declares `box_words: array<atomic<u32>>` (read_write storage), includes
// box_words.wgsl, and runs with @workgroup_size(WORKGROUP). Call from uniform control flow.

#include "constants.wgsl"

const WORKGROUP: u32 = 256u;
const PER_INVOCATION: u32 = REDUCE_TILE / WORKGROUP;
// GROUPS² = WORKGROUP.
const GROUPS: u32 = 16u;

// The tile of a workgroup of a (possibly 2D) grid.
fn tile_index(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

var<workgroup> shared_min: array<vec3<f32>, WORKGROUP>;
var<workgroup> shared_max: array<vec3<f32>, WORKGROUP>;

fn add_to_box_words(lid: u32, lo: vec3<f32>, hi: vec3<f32>) {
    shared_min[lid] = lo;
    shared_max[lid] = hi;
    workgroupBarrier();
    // Two barriers, not one per halving step (a barrier is what a workgroup pays most for on a
    // CPU device): GROUPS invocations each reduce a group of GROUPS boxes, then invocation 0 the
    // groups' boxes. Min and max are exact: the order changes at most the sign of a zero.
    if lid < GROUPS {
        for (var k = 1u; k < GROUPS; k++) {
            shared_min[lid * GROUPS] = min(shared_min[lid * GROUPS], shared_min[lid * GROUPS + k]);
            shared_max[lid * GROUPS] = max(shared_max[lid * GROUPS], shared_max[lid * GROUPS + k]);
        }
    }
    workgroupBarrier();
    if lid == 0u {
        for (var g = 1u; g < GROUPS; g++) {
            shared_min[0] = min(shared_min[0], shared_min[g * GROUPS]);
            shared_max[0] = max(shared_max[0], shared_max[g * GROUPS]);
        }
        let lo = shared_min[0];
        let hi = shared_max[0];
        if lo.x > hi.x {
            return;
        }
        atomicMax(&box_words[0], order_bits(-lo.x));
        atomicMax(&box_words[1], order_bits(-lo.y));
        atomicMax(&box_words[2], order_bits(-lo.z));
        atomicMax(&box_words[4], order_bits(hi.x));
        atomicMax(&box_words[5], order_bits(hi.y));
        atomicMax(&box_words[6], order_bits(hi.z));
    }
}

