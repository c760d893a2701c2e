//! Prefix scan add-back (kernel `counts_add`): every element of block b gets the block's offset,
//! which makes the blockwise scans of `counts_scan` global.

use super::prefix_scan::ScanParams;
use crate::gpu::kernel;

kernel!(pub COUNTS_ADD: ScanParams = "counts_add"::"main", [256, 1, 1], [ReadWrite, Read]);
