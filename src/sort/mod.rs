//! Sorting and scanning on the GPU: the portable LSD radix sort of (64-bit Morton key, u32 value)
//! pairs that is the sort stage of the LBVH builder (Karras 2012), reduce-then-scan per 4-bit digit
//! (histogram, then offsets summed per tile and a stable scatter; Satish et al. 2009 / Merrill &
//! Grimshaw 2010 without decoupled look-back), plus its CPU twin as the test oracle; and the
//! multi-level exclusive prefix scan that BVH compaction and pre-splitting use.

mod counts_add;
mod counts_scan;
mod keys_histogram;
mod keys_scatter;
mod prefix_scan;
mod radix_sort;

pub use counts_add::COUNTS_ADD;
pub use counts_scan::COUNTS_SCAN;
pub use keys_histogram::KEYS_HISTOGRAM;
pub use keys_scatter::KEYS_SCATTER;
pub use prefix_scan::{scan_blocks, PrefixScan};
pub use radix_sort::{
    check_tile_items, context_tile_items, packs_indices, sort_pairs_cpu, tile_items, RadixSort,
    SortValues, RADIX_BITS, SORT_TILE_ITEMS,
};
