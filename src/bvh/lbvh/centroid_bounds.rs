//! LBVH stage 1: the scene's centroid bounds by parallel reduction (`shaders/centroids_reduce.wgsl`),
//! and its CPU twin. The Morton grid spans these bounds (Karras 2012 §4).

use bytemuck::{Pod, Zeroable};

use crate::geometry::Aabb;
use crate::gpu::{
    bind_entry, compute_pipeline, dispatch_grid, storage_buffer_zeroed, uniform_buffer, GpuContext,
};
use crate::Result;

/// Elements one workgroup reduces (WORKGROUP × PER_INVOCATION in the kernel).
const TILE: u32 = 1024;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct ReduceParams {
    count: u32,
    _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<ReduceParams>() == 16);

/// CPU twin: bounds of the primitive boxes' centroids.
pub fn centroid_bounds_cpu(prim_boxes: &[Aabb]) -> Aabb {
    prim_boxes
        .iter()
        .fold(Aabb::EMPTY, |b, p| b.grow(p.centroid()))
}

pub struct CentroidBounds {
    from_prims: wgpu::ComputePipeline,
    from_boxes: wgpu::ComputePipeline,
}

impl CentroidBounds {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            from_prims: compute_pipeline(ctx, "centroids_reduce.wgsl", "from_prims"),
            from_boxes: compute_pipeline(ctx, "centroids_reduce.wgsl", "from_boxes"),
        }
    }

    /// Boxes written by each reduction level for `count` elements (the last level writes one).
    fn level_sizes(count: u32) -> Vec<u32> {
        let mut sizes = vec![count.div_ceil(TILE).max(1)];
        while let Some(&last) = sizes.last().filter(|&&s| s > 1) {
            sizes.push(last.div_ceil(TILE));
        }
        sizes
    }

    /// Number of reduction levels for `count` elements.
    pub fn level_count(count: u32) -> usize {
        Self::level_sizes(count).len()
    }

    /// Scratch buffers for reducing up to `count` primitives: one per level.
    pub fn level_buffers(ctx: &GpuContext, count: u32) -> Result<Vec<wgpu::Buffer>> {
        Self::level_sizes(count)
            .into_iter()
            .map(|boxes| storage_buffer_zeroed(ctx, "centroid bounds level", u64::from(boxes) * 32))
            .collect()
    }

    /// Records the reduction of the boxes' centroids (or of the boxes themselves, when
    /// `of_centroids` is false); the bounds end up in box 0 of `levels.last()`.
    pub fn record(
        &self,
        ctx: &GpuContext,
        pass: &mut wgpu::ComputePass<'_>,
        prim_boxes: &wgpu::Buffer,
        count: u32,
        levels: &[wgpu::Buffer],
        of_centroids: bool,
    ) {
        let mut remaining = count;
        for (level, output) in levels.iter().enumerate() {
            let params = uniform_buffer(
                ctx,
                "reduce params",
                &ReduceParams {
                    count: remaining,
                    _pad: [0; 3],
                },
            );
            let (pipeline, input) = if level == 0 {
                let first = if of_centroids {
                    &self.from_prims
                } else {
                    &self.from_boxes
                };
                (first, prim_boxes)
            } else {
                (&self.from_boxes, &levels[level - 1])
            };
            let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("centroids_reduce"),
                layout: &pipeline.get_bind_group_layout(0),
                entries: &[
                    bind_entry(0, &params),
                    bind_entry(1, input),
                    bind_entry(2, output),
                ],
            });
            let (gx, gy) = dispatch_grid(ctx, remaining.div_ceil(TILE).max(1), 1);
            pass.set_pipeline(pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups(gx, gy, 1);
            remaining = remaining.div_ceil(TILE).max(1);
        }
    }
}
