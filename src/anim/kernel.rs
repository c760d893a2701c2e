//! Runs one animation kernel (`shaders/<data>_animate.wgsl`) over the animated triangles of a
//! scene. The kernels share one binding convention: 0 = the frame's parameters (the animated
//! triangle count and grid row pitch first), 1 = the scene's triangles (written at indices
//! 0..count, the animated prefix), 2.. = read-only inputs (rest poses, per-body motion).

use bytemuck::Pod;

use crate::gpu::{GpuContext, Grid, Kernel, KernelDecl, Recorder};

pub(crate) struct AnimationKernel<P> {
    kernel: Kernel<P>,
    inputs: Vec<wgpu::Buffer>,
}

impl<P: Pod> AnimationKernel<P> {
    /// The kernel of `decl` with `inputs` bound from binding 2 on.
    pub fn new(ctx: &GpuContext, decl: &'static KernelDecl<P>, inputs: Vec<wgpu::Buffer>) -> Self {
        Self {
            kernel: Kernel::new(ctx, decl),
            inputs,
        }
    }

    /// Records the kernel over `count` animated triangles of `triangles` (pass "animate"), with
    /// the parameters `params` makes for the dispatch grid.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        count: u32,
        params: impl FnOnce(Grid) -> P,
        triangles: &wgpu::Buffer,
    ) {
        let grid = self.kernel.grid(rec.ctx, count);
        let mut buffers = vec![triangles];
        buffers.extend(self.inputs.iter());
        rec.pass("animate")
            .dispatch(&self.kernel, grid, &params(grid), &buffers);
    }
}
