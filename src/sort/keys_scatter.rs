//! Radix sort pass (kernel `keys_scatter`): the tile's first output slot per digit, summed from
//! the digit counts of all tiles, stable ranking within the tile by per-invocation counting
//! (Zagha & Blelloch 1991, one "processor" per invocation), the scatter of each (key, value)
//! pair to `offset[digit, tile] + rank`, and the next pass's digit counts per output tile.

use super::radix_sort::SortParams;
use crate::gpu::kernel;

kernel!(pub KEYS_SCATTER: SortParams = "keys_scatter"::"main", [256, 1, 1],
    [Read, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read]);
