//! LBVH stage 1: the scene's centroid bounds by parallel reduction (kernel `centroids_reduce`),
//! and its CPU twin. The Morton grid spans these bounds (Karras 2012 §4).

use bytemuck::{Pod, Zeroable};

use crate::geometry::Aabb;
use crate::gpu::{kernel, storage_buffer_zeroed, GpuContext, Grid, ItemCount, Kernel, Pass};
use crate::Result;

/// Elements one workgroup reduces (WORKGROUP × PER_INVOCATION in the kernel).
const TILE: u32 = 1024;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ReduceParams {
    count: u32,
    _pad: [u32; 3],
}

kernel!(
    /// First level: the centroids of primitive boxes.
    pub CENTROIDS_FROM_PRIMS: ReduceParams = "centroids_reduce"::"from_prims", [256, 1, 1], [Read, ReadWrite, Read]
);
kernel!(
    /// Further levels (and the scene box from primitive boxes): boxes.
    pub CENTROIDS_FROM_BOXES: ReduceParams = "centroids_reduce"::"from_boxes", [256, 1, 1], [Read, ReadWrite, Read]
);

/// CPU twin: bounds of the primitive boxes' centroids.
pub fn centroid_bounds_cpu(prim_boxes: &[Aabb]) -> Aabb {
    prim_boxes
        .iter()
        .fold(Aabb::EMPTY, |b, p| b.grow(p.centroid()))
}

/// The kernel `centroids_reduce`: a reduction of boxes (or their centroids) to one box.
pub struct CentroidsReduce {
    from_prims: Kernel<ReduceParams>,
    from_boxes: Kernel<ReduceParams>,
}

impl CentroidsReduce {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            from_prims: Kernel::new(ctx, &CENTROIDS_FROM_PRIMS),
            from_boxes: Kernel::new(ctx, &CENTROIDS_FROM_BOXES),
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
        pass: &mut Pass<'_>,
        prim_boxes: &wgpu::Buffer,
        count: ItemCount<'_>,
        levels: &[wgpu::Buffer],
        of_centroids: bool,
    ) {
        let ctx = pass.ctx();
        let mut remaining = count.capacity();
        for (level, output) in levels.iter().enumerate() {
            let (kernel, input) = match level {
                0 if of_centroids => (&self.from_prims, prim_boxes),
                0 => (&self.from_boxes, prim_boxes),
                _ => (&self.from_boxes, &levels[level - 1]),
            };
            let tiles = remaining.div_ceil(TILE).max(1);
            let grid = Grid::items(ctx, tiles, 1);
            let params = ReduceParams {
                count: remaining,
                _pad: [0; 3],
            };
            // Only the first level's item count can be on the GPU.
            let limit = if level == 0 {
                count.limit(ctx)
            } else {
                &ctx.no_count_limit
            };
            pass.dispatch(kernel, grid, &params, &[input, output, limit]);
            remaining = tiles;
        }
    }
}
