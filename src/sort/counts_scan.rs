//! Prefix scan (kernel `counts_scan`): each workgroup scans its block of `SCAN_BLOCK` u32s in
//! place and stores the block's total; the last workgroup to finish scans the totals into block
//! offsets and the grand total.

use super::prefix_scan::ScanParams;
use crate::gpu::kernel;

kernel!(pub COUNTS_SCAN: ScanParams = "counts_scan"::"main", [256, 1, 1], [ReadWrite, ReadWrite, ReadWrite, ReadWrite]);
