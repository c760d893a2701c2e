//! Pre-splitting step 4 (kernel `references_split`; Karras & Aila 2013, §5): the box of each
//! reference of a triangle of more than `SPLIT_INLINE_PIECES` references, one invocation per
//! reference, found from the triangle's piece down. CPU twin: `split_triangle`.

use crate::gpu::{kernel, Items};

kernel!(pub REFERENCES_SPLIT: Items = "references_split"::"main", [64, 1, 1],
    [Read, Read, Read, Read, ReadWrite, Read, Read, Read, Read]);
