//! GPU treelet restructuring, one dispatch per round (kernel `treelet_optimize`; Karras &
//! Aila 2013, §3-4): a bottom-up climb that updates primitive counts and SAH costs and lets each
//! workgroup optimize the treelets its climbing invocations reach, cooperatively.

use bytemuck::{Pod, Zeroable};

use super::dp::CostModel;
use crate::gpu::{kernel, ItemCount, Kernel, Pass};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct TreeletParams {
    count: u32,
    row_pitch: u32,
    gamma: u32,
    treelet_size: u32,
    max_leaf_size: u32,
    ci: f32,
    ct: f32,
    /// Always 0: keeps the kernel's area products unfused (see `unfused` in the shader).
    zero: u32,
}

kernel!(pub TREELET_OPTIMIZE: TreeletParams = "treelet_optimize"::"main", [32, 1, 1],
    [ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read]);

/// Per-node state the rounds and the collapse share (sized for 2n-1 nodes).
pub(crate) struct TreeletState<'a> {
    pub nodes: &'a wgpu::Buffer,
    pub parents: &'a wgpu::Buffer,
    pub prim_counts: &'a wgpu::Buffer,
    pub costs: &'a wgpu::Buffer,
    /// Arrival counters, zeroed before each round.
    pub arrivals: &'a wgpu::Buffer,
}

/// What one round does: the cost model, the treelet size and γ (the smallest treelet root).
pub(crate) struct Round {
    pub model: CostModel,
    pub treelet_size: u32,
    pub gamma: u32,
}

/// The kernel `treelet_optimize`.
pub(crate) struct TreeletOptimize {
    kernel: Kernel<TreeletParams>,
}

impl TreeletOptimize {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        Self {
            kernel: Kernel::new(ctx, &TREELET_OPTIMIZE),
        }
    }

    /// Records one round over a working tree of `count` leaves (LBVH layout). `gamma = u32::MAX`
    /// only updates counts and costs.
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        count: ItemCount<'_>,
        state: &TreeletState<'_>,
        round: &Round,
    ) {
        let ctx = pass.ctx();
        let grid = self.kernel.grid(ctx, count.capacity());
        let params = TreeletParams {
            count: count.capacity(),
            row_pitch: grid.row_pitch,
            gamma: round.gamma,
            treelet_size: round.treelet_size,
            max_leaf_size: round.model.max_leaf_size,
            ci: round.model.ci,
            ct: round.model.ct,
            zero: 0,
        };
        pass.dispatch(
            &self.kernel,
            grid,
            &params,
            &[
                state.nodes,
                state.parents,
                state.prim_counts,
                state.costs,
                state.arrivals,
                count.limit(ctx),
            ],
        );
    }
}
