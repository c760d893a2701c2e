//! Prefix scan step (kernel `counts_scan`): each workgroup scans its block of `SCAN_BLOCK` u32s in
//! place and writes the block's total to the next level.

use super::prefix_scan::ScanParams;
use crate::gpu::kernel;

kernel!(pub COUNTS_SCAN: ScanParams = "counts_scan"::"main", [256, 1, 1], [ReadWrite, ReadWrite]);
