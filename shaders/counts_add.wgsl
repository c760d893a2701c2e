// Add-back of the multi-level exclusive scan `sort::PrefixScan`: after counts_scan.wgsl scanned
// each SCAN_BLOCK of `data` locally and the next level scanned the block totals `sums`, every element
// of block b gets sums[b] added, which makes the scan of `data` global; the same for every one of
// `columns` arrays of `len` stored back to back (workgroup c * num_blocks + b: block b of column c).
// Workgroups are linear indices over a 1D or 2D grid: wid.x + wid.y * num_workgroups.x.
#include "constants.wgsl"

struct ScanParams {
    // Elements and blocks per column.
    len: u32,
    num_blocks: u32,
    columns: u32,
    pad: u32,
}

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read> sums: array<u32>;

@compute @workgroup_size(256)
fn main(
    @builtin(local_invocation_index) lid: u32,
    @builtin(workgroup_id) wid: vec3<u32>,
    @builtin(num_workgroups) nwg: vec3<u32>,
) {
    let id = wid.x + wid.y * nwg.x;
    if id >= params.num_blocks * params.columns {
        return;
    }
    let column = id / params.num_blocks;
    let block = id - column * params.num_blocks;
    let add = sums[id];
    let start = column * params.len;
    let base = block * SCAN_BLOCK + lid * (SCAN_BLOCK / 256u);
    for (var i = 0u; i < SCAN_BLOCK / 256u; i++) {
        if base + i < params.len {
            data[start + base + i] += add;
        }
    }
}
