//! Runs one animation kernel (`shaders/<data>_animate.wgsl`) over the animated triangles of a
//! scene. The kernels share one binding convention: 0 = dispatch size (`DispatchParams`), 1 = the
//! animation's parameters for this frame (a uniform), 2 = the scene's triangles (written at
//! indices 0..count, the animated prefix), 3.. = read-only inputs (rest poses, per-body motion).

use bytemuck::{Pod, Zeroable};

use crate::gpu::{
    bind_entry, compute_pipeline, dispatch_grid, uniform_buffer, GpuContext, GpuTimer, StageTime,
};
use crate::Result;

/// Invocations per workgroup of every animation kernel.
const WORKGROUP: u32 = 64;

/// Binding 0 of every animation kernel: one invocation per animated triangle, in a 2D grid.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct DispatchParams {
    count: u32,
    row_pitch: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<DispatchParams>() == 16);

pub(crate) struct AnimationKernel {
    label: &'static str,
    pipeline: wgpu::ComputePipeline,
    dispatch: wgpu::Buffer,
    grid: (u32, u32),
    params: wgpu::Buffer,
    inputs: Vec<wgpu::Buffer>,
}

impl AnimationKernel {
    /// The kernel `file` for `count` animated triangles, with `params` as the first frame's
    /// parameters and `inputs` bound from binding 3 on.
    pub fn new<P: Pod>(
        ctx: &GpuContext,
        file: &'static str,
        count: u32,
        params: &P,
        inputs: Vec<wgpu::Buffer>,
    ) -> Self {
        let grid = dispatch_grid(ctx, count, WORKGROUP);
        let dispatch = DispatchParams {
            count,
            row_pitch: grid.0 * WORKGROUP,
            _pad: [0; 2],
        };
        Self {
            label: file,
            pipeline: compute_pipeline(ctx, file, "main"),
            dispatch: uniform_buffer(ctx, "animate dispatch", &dispatch),
            grid,
            params: uniform_buffer(ctx, "animate params", params),
            inputs,
        }
    }

    /// Writes this frame's `params` and runs the kernel into `triangles`; blocks until done and
    /// returns its GPU time (label "animate").
    pub fn run<P: Pod>(
        &self,
        ctx: &GpuContext,
        params: &P,
        triangles: &wgpu::Buffer,
    ) -> Result<StageTime> {
        ctx.queue
            .write_buffer(&self.params, 0, bytemuck::bytes_of(params));
        let mut entries = vec![
            bind_entry(0, &self.dispatch),
            bind_entry(1, &self.params),
            bind_entry(2, triangles),
        ];
        entries.extend(
            self.inputs
                .iter()
                .enumerate()
                .map(|(i, buffer)| bind_entry(3 + i as u32, buffer)),
        );
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.label),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &entries,
        });
        let mut timer = GpuTimer::new(ctx, 1);
        let mut encoder = ctx.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(self.label),
                timestamp_writes: timer.pass("animate"),
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(self.grid.0, self.grid.1, 1);
        }
        timer.resolve(&mut encoder);
        ctx.queue.submit([encoder.finish()]);
        let mut stages = timer.read(ctx)?;
        Ok(stages.pop().unwrap_or(StageTime {
            label: "animate".into(),
            ms: None,
        }))
    }
}
