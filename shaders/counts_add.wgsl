// Add-back of the exclusive scan `sort::PrefixScan`: after counts_scan.wgsl scanned each
// SCAN_BLOCK of `data` locally and left each block's offset in `block_offsets`, every element of
// block b gets block_offsets[b] added, which makes the scan of `data` global (every column of
// `data` on its own: scan_blocks.wgsl).
#include "scan_blocks.wgsl"

@group(0) @binding(0) var<uniform> params: ScanParams;
@group(0) @binding(1) var<storage, read_write> data: array<u32>;
@group(0) @binding(2) var<storage, read> block_offsets: array<u32>;

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
    let add = block_offsets[b.id];
    let base = b.first + lid * (SCAN_BLOCK / 256u);
    for (var i = 0u; i < SCAN_BLOCK / 256u; i++) {
        if base + i < params.len {
            data[b.start + base + i] += add;
        }
    }
}
