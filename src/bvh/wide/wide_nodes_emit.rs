//! One level of the GPU binary-to-wide conversion (kernel `wide_nodes_emit`): the root, or the
//! wide nodes of one level with the next level's indirect dispatch sized on the GPU.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

/// Parameters of the conversion kernels (`WideParams` in wide_collapse.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct WideParams {
    /// The level a `wide_nodes_emit` dispatch emits (0: the root).
    pub level: u32,
    /// Indirect level dispatches after the root's.
    pub level_dispatches: u32,
    /// Wide nodes the output holds.
    pub capacity: u32,
    /// Always 0: keeps the area products unfused.
    pub zero: u32,
    /// 0: greedy, 1: optimal (`WideCollapse`).
    pub collapse: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<WideParams>() == 32);

kernel!(pub WIDE_NODES_EMIT: WideParams = "wide_nodes_emit"::"main", [64, 1, 1],
    [Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, ReadWrite, Read]);
