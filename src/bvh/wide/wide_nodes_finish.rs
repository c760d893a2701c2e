//! The levels of the GPU binary-to-wide conversion below the level dispatches (kernel
//! `wide_nodes_finish`): an indirect dispatch, one invocation per wide node of the next level,
//! each emitting its node's subtree depth-first.

use super::wide_nodes_emit::WideParams;
use crate::gpu::kernel;

kernel!(pub WIDE_NODES_FINISH: WideParams = "wide_nodes_finish"::"main", [64, 1, 1],
    [Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, ReadWrite, Read]);
