//! LBVH stage 0: one primitive box per triangle (kernel `triangles_bounds`) and its CPU twin.
//! The build runs over primitive boxes so that pre-split references (several clipped boxes per
//! triangle) go through the same stages.

use crate::geometry::Aabb;
use crate::gpu::{kernel, Items, Kernel, Pass};
use crate::scene::Triangle;

kernel!(pub TRIANGLES_BOUNDS: Items = "triangles_bounds"::"main", [64, 1, 1], [Read, ReadWrite]);

/// CPU twin: the triangles' boxes.
pub fn prim_boxes_cpu(triangles: &[Triangle]) -> Vec<Aabb> {
    triangles.iter().map(Triangle::bounds).collect()
}

/// The kernel `triangles_bounds`.
pub struct TrianglesBounds {
    kernel: Kernel<Items>,
}

impl TrianglesBounds {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        Self {
            kernel: Kernel::new(ctx, &TRIANGLES_BOUNDS),
        }
    }

    /// Records `prim_boxes[i] = bounds(triangles[i])` for `count` triangles.
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        triangles: &wgpu::Buffer,
        count: u32,
        prim_boxes: &wgpu::Buffer,
    ) {
        pass.dispatch_items(&self.kernel, count, &[triangles, prim_boxes]);
    }
}
