//! The SAH-optimal wide collapse, step 1 (kernel `nodes_link`): parent links of the binary tree
//! and zeroed arrival counters for the bottom-up costs (`costs_climb`).

use crate::gpu::{kernel, Items};

kernel!(pub NODES_LINK: Items = "nodes_link"::"main", [64, 1, 1],
    [Read, ReadWrite, ReadWrite, Read]);
