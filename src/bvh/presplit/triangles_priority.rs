//! Pre-splitting step 1 (kernel `triangles_priority`; Karras & Aila 2013, §5): each triangle's
//! split priority q = p³, and the largest q for the budget search. CPU twin: `split_priority`.

use crate::gpu::{kernel, Items};

kernel!(pub TRIANGLES_PRIORITY: Items = "triangles_priority"::"main", [64, 1, 1],
    [Read, ReadWrite, ReadWrite, Read]);
