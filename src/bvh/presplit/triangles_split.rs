//! Pre-splitting step 3 (kernel `triangles_split`; Karras & Aila 2013, §5): each triangle
//! becomes its s_t + 1 reference boxes, written at its scanned offset; a triangle of more than
//! `SPLIT_INLINE_PIECES` references lists them for step 4. CPU twin: `split_triangle`.

use crate::gpu::{kernel, Items};

kernel!(pub TRIANGLES_SPLIT: Items = "triangles_split"::"main", [64, 1, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite, Read, ReadWrite, ReadWrite]);
