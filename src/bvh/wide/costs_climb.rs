//! The SAH-optimal wide collapse, step 2 (kernel `costs_climb`; Ylitie, Karras & Laine 2017
//! §3.1): the dynamic program's costs and choices, bottom-up over the binary tree (CPU twin:
//! `OptimalCollapse`).

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

/// Parameters of `costs_climb` (`CostParams` in costs_climb.wgsl).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct CostParams {
    /// Node slots dispatched (the tree's node count is read on the GPU).
    pub count: u32,
    pub row_pitch: u32,
    pub ci: f32,
    pub ct: f32,
    /// Always 0: keeps the products unfused.
    pub zero: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<CostParams>() == 32);

kernel!(pub COSTS_CLIMB: CostParams = "costs_climb"::"main", [64, 1, 1],
    [Read, Read, ReadWrite, ReadWrite, ReadWrite, Read]);
