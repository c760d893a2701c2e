//! Sorting on the GPU: the portable LSD radix sort of (64-bit Morton key, u32 value) pairs that is
//! the sort stage of the LBVH builder (Karras 2012), reduce-then-scan per 4-bit digit (histogram,
//! multi-level exclusive scan, stable scatter; Satish et al. 2009 / Merrill & Grimshaw 2010 without
//! decoupled look-back), plus its CPU twin as the test oracle.

mod prefix_scan;
mod radix_sort;

pub use prefix_scan::{PrefixScan, ScanPlan, SCAN_BLOCK};
pub use radix_sort::{sort_pairs, sort_pairs_cpu, RadixSort, RADIX_BITS, TILE_SIZE};
