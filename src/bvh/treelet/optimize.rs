//! GPU treelet restructuring, one dispatch per round (`shaders/treelet_optimize.wgsl`; Karras &
//! Aila 2013, §3-4): a bottom-up climb that updates primitive counts and SAH costs and lets each
//! workgroup optimize the treelets its climbing invocations reach, cooperatively.

use bytemuck::{Pod, Zeroable};

use super::dp::CostModel;
use crate::gpu::{bind_entry, compute_pipeline, dispatch_grid, uniform_buffer, GpuContext};
use crate::trace::GpuScene;

const WORKGROUP: u32 = 32;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct TreeletParams {
    count: u32,
    row_pitch: u32,
    gamma: u32,
    treelet_size: u32,
    max_leaf_size: u32,
    ci: f32,
    ct: f32,
    /// Always 0: keeps the kernel's products unfused (see `unfused` in the shader).
    zero: u32,
}
const _: () = assert!(std::mem::size_of::<TreeletParams>() == 32);

/// Per-node state the rounds and the collapse share (sized for 2n-1 nodes).
pub(crate) struct TreeletState<'a> {
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

pub(crate) struct TreeletOptimizer {
    pipeline: wgpu::ComputePipeline,
}

impl TreeletOptimizer {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            pipeline: compute_pipeline(ctx, "treelet_optimize.wgsl", "main"),
        }
    }

    /// Records one round over the working tree in `scene` (LBVH layout). `gamma = u32::MAX` only
    /// updates counts and costs.
    pub fn record(
        &self,
        ctx: &GpuContext,
        pass: &mut wgpu::ComputePass<'_>,
        scene: &GpuScene,
        state: &TreeletState<'_>,
        round: &Round,
    ) {
        let count = scene.prim_count;
        let (gx, gy) = dispatch_grid(ctx, count, WORKGROUP);
        let params = uniform_buffer(
            ctx,
            "treelet params",
            &TreeletParams {
                count,
                row_pitch: gx * WORKGROUP,
                gamma: round.gamma,
                treelet_size: round.treelet_size,
                max_leaf_size: round.model.max_leaf_size,
                ci: round.model.ci,
                ct: round.model.ct,
                zero: 0,
            },
        );
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("treelet_optimize"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &params),
                bind_entry(1, &scene.nodes),
                bind_entry(2, state.parents),
                bind_entry(3, state.prim_counts),
                bind_entry(4, state.costs),
                bind_entry(5, state.arrivals),
            ],
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
}
