// Scene centroid bounds by parallel reduction (LBVH stage 1, Karras 2012 §3), in one dispatch:
// each workgroup reduces a tile of TILE elements in workgroup memory and adds its box to the
// eight box words with six atomicMax (box_words.wgsl). `from_prims` reads the centroids of the
// primitive boxes, `from_boxes` the boxes themselves (the scene box). min/max are exact, so the
// result is bit-identical to the CPU twin in any order.
#include "box_words.wgsl"

const WORKGROUP: u32 = 256u;
const PER_INVOCATION: u32 = 4u;
const TILE: u32 = 1024u;

struct ReduceParams {
    count: u32,
    pad0: u32,
    pad1: u32,
    pad2: u32,
}

@group(0) @binding(0) var<uniform> params: ReduceParams;
@group(0) @binding(1) var<storage, read> boxes_in: array<Aabb>;
// The box words (box_words.wgsl), zeroed before the dispatch.
@group(0) @binding(2) var<storage, read_write> box_words: array<atomic<u32>>;
// The item count's limit (`gpu::ItemCount`): both entries reduce min(params.count,
// count_limit[0]) items; tiles past them add nothing.
@group(0) @binding(3) var<storage, read> count_limit: array<u32>;

var<workgroup> shared_min: array<vec3<f32>, WORKGROUP>;
var<workgroup> shared_max: array<vec3<f32>, WORKGROUP>;

fn reduce_and_store(lid: u32, lo: vec3<f32>, hi: vec3<f32>) {
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

fn tile_index(wid: vec3<u32>, groups: vec3<u32>) -> u32 {
    return wid.x + wid.y * groups.x;
}

@compute @workgroup_size(WORKGROUP)
fn from_prims(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tile = tile_index(wid, groups);
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(-F32_MAX);
    let count = min(params.count, count_limit[0]);
    for (var k = 0u; k < PER_INVOCATION; k++) {
        let i = tile * TILE + k * WORKGROUP + lid;
        if i < count {
            let c = (boxes_in[i].min + boxes_in[i].max) * 0.5;
            lo = min(lo, c);
            hi = max(hi, c);
        }
    }
    reduce_and_store(lid, lo, hi);
}

@compute @workgroup_size(WORKGROUP)
fn from_boxes(@builtin(workgroup_id) wid: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>, @builtin(local_invocation_index) lid: u32) {
    let tile = tile_index(wid, groups);
    var lo = vec3<f32>(F32_MAX);
    var hi = vec3<f32>(-F32_MAX);
    let count = min(params.count, count_limit[0]);
    for (var k = 0u; k < PER_INVOCATION; k++) {
        let i = tile * TILE + k * WORKGROUP + lid;
        if i < count {
            lo = min(lo, boxes_in[i].min);
            hi = max(hi, boxes_in[i].max);
        }
    }
    reduce_and_store(lid, lo, hi);
}
