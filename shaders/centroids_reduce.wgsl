// Scene centroid bounds by parallel reduction (LBVH stage 1, Karras 2012 §3). Each workgroup
// reduces a tile of TILE elements to one box: `from_prims` reads the centroids of the primitive
// boxes, `from_boxes` reduces the previous level's boxes. Levels repeat until one box remains.
// min/max are exact, so the result is bit-identical to the CPU twin in any order.
#include "aabb.wgsl"

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
@group(0) @binding(2) var<storage, read_write> boxes_out: array<Aabb>;
// The item count's limit (`gpu::ItemCount`): both entries reduce min(params.count,
// count_limit[0]) items; tiles past them give the empty box.
@group(0) @binding(3) var<storage, read> count_limit: array<u32>;

var<workgroup> shared_min: array<vec3<f32>, WORKGROUP>;
var<workgroup> shared_max: array<vec3<f32>, WORKGROUP>;

fn reduce_and_store(lid: u32, tile: u32, lo: vec3<f32>, hi: vec3<f32>) {
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
    if lid == 0u {
        boxes_out[tile] = Aabb(shared_min[0], 0u, shared_max[0], 0u);
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
    reduce_and_store(lid, tile, lo, hi);
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
    reduce_and_store(lid, tile, lo, hi);
}
