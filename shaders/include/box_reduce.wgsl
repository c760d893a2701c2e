// A workgroup's share of a box reduction (box_words.wgsl): a tile of REDUCE_TILE items, four per
// invocation; the workgroup's invocations reduce their boxes in workgroup memory, then
// invocation 0 adds the result to the box words with six atomicMax (an empty box adds nothing).
// The including kernel declares `box_words: array<atomic<u32>>` (read_write storage), includes
// box_words.wgsl, and runs with @workgroup_size(WORKGROUP). Call from uniform control flow.

#include "constants.wgsl"

const WORKGROUP: u32 = 256u;
const PER_INVOCATION: u32 = REDUCE_TILE / WORKGROUP;

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
    for (var stride = WORKGROUP / 2u; stride > 0u; stride >>= 1u) {
        if lid < stride {
            shared_min[lid] = min(shared_min[lid], shared_min[lid + stride]);
            shared_max[lid] = max(shared_max[lid], shared_max[lid + stride]);
        }
        workgroupBarrier();
    }
    if lid == 0u && shared_min[0].x <= shared_max[0].x {
        let lo = shared_min[0];
        let hi = shared_max[0];
        atomicMax(&box_words[0], order_bits(-lo.x));
        atomicMax(&box_words[1], order_bits(-lo.y));
        atomicMax(&box_words[2], order_bits(-lo.z));
        atomicMax(&box_words[4], order_bits(hi.x));
        atomicMax(&box_words[5], order_bits(hi.y));
        atomicMax(&box_words[6], order_bits(hi.z));
    }
}

