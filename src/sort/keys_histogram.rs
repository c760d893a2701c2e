//! Radix sort step 1 (kernel `keys_histogram`): per tile of `SORT_TILE` keys, the 16 counts of
//! the pass's 4-bit digit, stored digit-major (`counts[digit * tiles + tile]`).

use super::radix_sort::SortParams;
use crate::gpu::kernel;

kernel!(pub KEYS_HISTOGRAM: SortParams = "keys_histogram"::"main", [256, 1, 1], [Read, ReadWrite, Read]);
