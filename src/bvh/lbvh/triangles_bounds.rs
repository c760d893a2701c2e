//! LBVH stages 0-1 for triangles: one primitive box per triangle and, in the same dispatch, the
//! bounds of their centroids (Karras 2012 §4: the Morton grid spans them) or of the boxes
//! themselves (pre-splitting's scene box), reduced into box words (kernel `triangles_bounds`);
//! and the CPU twin of the boxes. The build runs over primitive boxes so that pre-split
//! references (several clipped boxes per triangle) go through the same stages.

use bytemuck::{Pod, Zeroable};

use crate::geometry::Aabb;
use crate::gpu::{kernel, Grid, Kernel, Pass};
use crate::scene::Triangle;

/// Triangles one workgroup takes (WORKGROUP × PER_INVOCATION in the kernel).
const TILE: u32 = 1024;

/// Parameters of `triangles_bounds` (WGSL twin in the kernel).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct TriangleBoundsParams {
    count: u32,
    centroids: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<TriangleBoundsParams>() == 16);

kernel!(pub TRIANGLES_BOUNDS: TriangleBoundsParams = "triangles_bounds"::"main", [256, 1, 1],
    [Read, ReadWrite, ReadWrite]);

/// CPU twin: the triangles' boxes.
pub fn prim_boxes_cpu(triangles: &[Triangle]) -> Vec<Aabb> {
    triangles.iter().map(Triangle::bounds).collect()
}

/// What the triangles' boxes are reduced to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BoundsOf {
    /// The boxes' centroids (the LBVH's Morton grid).
    Centroids,
    /// The boxes (the scene box).
    Boxes,
}

/// The kernel `triangles_bounds`.
pub struct TrianglesBounds {
    kernel: Kernel<TriangleBoundsParams>,
}

impl TrianglesBounds {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        Self {
            kernel: Kernel::new(ctx, &TRIANGLES_BOUNDS),
        }
    }

    /// Records `prim_boxes[i] = bounds(triangles[i])` for `count` triangles and the reduction of
    /// `of` into `box_words` (zeroed beforehand; `lbvh::box_of_words` reads them).
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        triangles: &wgpu::Buffer,
        count: u32,
        prim_boxes: &wgpu::Buffer,
        box_words: &wgpu::Buffer,
        of: BoundsOf,
    ) {
        let ctx = pass.ctx();
        let params = TriangleBoundsParams {
            count,
            centroids: u32::from(of == BoundsOf::Centroids),
            _pad: [0; 2],
        };
        pass.dispatch(
            &self.kernel,
            Grid::items(ctx, count.div_ceil(TILE).max(1), 1),
            &params,
            &[triangles, prim_boxes, box_words],
        );
    }
}
