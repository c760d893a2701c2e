//! The deep levels of the GPU binary-to-wide conversion (kernel `wide_nodes_finish`): one
//! workgroup emits level after level until no node allocates children.

use super::wide_nodes_emit::WideParams;
use crate::gpu::kernel;

kernel!(pub WIDE_NODES_FINISH: WideParams = "wide_nodes_finish"::"main", [256, 1, 1],
    [Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, ReadWrite, Read]);
