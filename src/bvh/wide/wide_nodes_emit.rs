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
}
const _: () = assert!(std::mem::size_of::<WideParams>() == 16);

/// The pipeline-overridable constant that fixes the collapse of `wide_nodes_emit` and
/// `wide_nodes_finish` (`override WIDE_COLLAPSE` in wide_collapse.wgsl;
/// `WideCollapse::override_value`).
pub const WIDE_COLLAPSE_OVERRIDE: &str = "WIDE_COLLAPSE";

kernel!(pub WIDE_NODES_EMIT: WideParams = "wide_nodes_emit"::"main", [64, 1, 1],
    [Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, ReadWrite, Read]);
