//! LBVH stage 1: the scene's centroid bounds by parallel reduction (kernel `centroids_reduce`),
//! and its CPU twin. The Morton grid spans these bounds (Karras 2012 §4).

use bytemuck::{Pod, Zeroable};

use glam::Vec3;

use crate::geometry::Aabb;
use crate::gpu::constants::REDUCE_TILE;
use crate::gpu::{kernel, storage_buffer_zeroed, GpuContext, Grid, ItemCount, Kernel, Pass};
use crate::Result;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct ReduceParams {
    count: u32,
    _pad: [u32; 3],
}

kernel!(pub CENTROIDS_REDUCE: ReduceParams = "centroids_reduce"::"main", [256, 1, 1], [Read, ReadWrite, Read]);

/// CPU twin: bounds of the primitive boxes' centroids.
pub fn centroid_bounds_cpu(prim_boxes: &[Aabb]) -> Aabb {
    prim_boxes
        .iter()
        .fold(Aabb::EMPTY, |b, p| b.grow(p.centroid()))
}

/// The kernel `centroids_reduce`: the bounds of primitive boxes' centroids in one dispatch (for
/// boxes that are not the triangles': `TrianglesBounds` reduces the triangles' as it computes
/// them).
pub struct CentroidsReduce {
    kernel: Kernel<ReduceParams>,
}

impl CentroidsReduce {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            kernel: Kernel::new(ctx, &CENTROIDS_REDUCE),
        }
    }

    /// The eight box words a reduction adds into (`box_words.wgsl`; zero them before each).
    pub fn box_buffer(ctx: &GpuContext) -> Result<wgpu::Buffer> {
        storage_buffer_zeroed(ctx, "box words", 32)
    }

    /// Records the reduction of the boxes' centroids into `box_words`, zeroed beforehand.
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        prim_boxes: &wgpu::Buffer,
        count: ItemCount<'_>,
        box_words: &wgpu::Buffer,
    ) {
        let ctx = pass.ctx();
        let params = ReduceParams {
            count: count.capacity(),
            _pad: [0; 3],
        };
        let limit = count.limit(ctx);
        pass.dispatch(
            &self.kernel,
            reduce_grid(ctx, count.capacity()),
            &params,
            &[prim_boxes, box_words, limit],
        );
    }
}

/// The grid of a box reduction over `count` items: a workgroup per tile (box_reduce.wgsl).
pub(crate) fn reduce_grid(ctx: &GpuContext, count: u32) -> Grid {
    Grid::items(ctx, count.div_ceil(REDUCE_TILE).max(1), 1)
}

/// CPU twin of `box_words.wgsl`'s `box_of_words`: the box the eight words of a reduction hold.
pub fn box_of_words(words: &[u32]) -> Aabb {
    let from_order_bits = |u: u32| {
        f32::from_bits(if u & 0x8000_0000 != 0 {
            u & 0x7fff_ffff
        } else {
            !u
        })
    };
    let axes = |first: usize| {
        Vec3::new(
            from_order_bits(words[first]),
            from_order_bits(words[first + 1]),
            from_order_bits(words[first + 2]),
        )
    };
    Aabb::new(-axes(0), axes(4))
}
