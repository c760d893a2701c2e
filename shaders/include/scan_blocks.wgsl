// Shared by counts_scan.wgsl and counts_add.wgsl (`sort::PrefixScan`): the parameters (ScanParams
// must match src/sort/prefix_scan.rs) and which block a workgroup works on. `columns` arrays of
// `len` elements are stored back to back and scanned independently: workgroup c · num_blocks + b
// takes block b (SCAN_BLOCK elements) of column c, whose total and then offset is word
// c · num_blocks + b of the block sums. Workgroups are linear indices over a 1D or
// 2D grid: wid.x + wid.y · num_workgroups.x. The including kernel declares `params`.
#include "constants.wgsl"

struct ScanParams {
    // Elements and blocks per column.
    len: u32,
    num_blocks: u32,
    columns: u32,
    pad: u32,
}

struct ScanBlock {
    // The workgroup's linear index: its block's word in `sums`.
    id: u32,
    // Whether the grid's workgroup has a block (grids may hold more workgroups than blocks).
    exists: bool,
    // The block's first element within its column, and the column's first element in `data`.
    first: u32,
    start: u32,
}

fn scan_block(wid: vec3<u32>, nwg: vec3<u32>) -> ScanBlock {
    let id = wid.x + wid.y * nwg.x;
    let column = id / params.num_blocks;
    let block = id - column * params.num_blocks;
    return ScanBlock(id, id < params.num_blocks * params.columns, block * SCAN_BLOCK, column * params.len);
}
