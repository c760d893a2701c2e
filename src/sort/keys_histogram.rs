//! Radix sort's first step (kernel `keys_histogram`): per tile of keys, the 16 counts
//! of the first pass's 4-bit digit, stored digit-major (`counts[digit * tiles + tile]`); it zeroes
//! the tile's words of the counts the first scatter gathers for the second pass.

use super::radix_sort::SortParams;
use crate::gpu::kernel;

kernel!(pub KEYS_HISTOGRAM: SortParams = "keys_histogram"::"main", [256, 1, 1], [Read, ReadWrite, ReadWrite, Read]);
