// Exclusive prefix sum, one level of the multi-level scan `sort::PrefixScan`: each workgroup scans
// its block of SCAN_BLOCK = 4096 u32s of `data` in place (16 consecutive per invocation, then a
// Hillis-Steele scan of the 256 invocation totals in workgroup memory) and writes the block's total
// to sums[block]. The caller scans `sums` the same way (the next level, its own dispatch) and adds
// it back with counts_add.wgsl; a length of at most SCAN_BLOCK needs this one dispatch only.
// Every column of `data` is scanned on its own (scan_blocks.wgsl).
#include "scan_blocks.wgsl"

const WORKGROUP: u32 = 256u;
const ITEMS: u32 = SCAN_BLOCK / WORKGROUP;

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read_write> sums: array<u32>;

var<workgroup> partial: array<u32, 256>;

// Element i of the column starting at `start`.
fn load(start: u32, i: u32) -> u32 {
    if i < params.len {
        return data[start + i];
    }
    return 0u;
}

fn store(start: u32, i: u32, x: u32) {
    if i < params.len {
        data[start + i] = x;
    }
}

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let b = scan_block(wid, nwg);
    if !b.exists {
        return;
    }
    let base = b.first + lid * ITEMS;
    var total = 0u;
    for (var i = 0u; i < ITEMS; i++) {
        total += load(b.start, base + i);
    }
    partial[lid] = total;
    workgroupBarrier();
    for (var offset = 1u; offset < WORKGROUP; offset <<= 1u) {
        var t = partial[lid];
        if lid >= offset {
            t += partial[lid - offset];
        }
        workgroupBarrier();
        partial[lid] = t;
        workgroupBarrier();
    }
    var before = partial[lid] - total;
    for (var i = 0u; i < ITEMS; i++) {
        let x = load(b.start, base + i);
        store(b.start, base + i, before);
        before += x;
    }
    if lid == WORKGROUP - 1u {
        sums[b.id] = partial[lid];
    }
}
