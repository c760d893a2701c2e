//! LBVH stages 0-1 for triangles: one primitive box per triangle and, in the same dispatch, the
//! bounds of their centroids (Karras 2012 §4: the Morton grid spans them), reduced into box words
//! (kernel `triangles_bounds`); or only the scene box (pre-splitting's grid spans it); and the CPU
//! twin of the boxes. The build runs over primitive boxes so that pre-split
//! references (several clipped boxes per triangle) go through the same stages.

use bytemuck::{Pod, Zeroable};

use super::centroids_reduce::reduce_grid;
use crate::geometry::Aabb;
use crate::gpu::{kernel, Kernel, Pass};
use crate::scene::Triangle;

/// Parameters of `triangles_bounds` (WGSL twin in the kernel).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct TriangleBoundsParams {
    count: u32,
    lbvh_input: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<TriangleBoundsParams>() == 16);

kernel!(pub TRIANGLES_BOUNDS: TriangleBoundsParams = "triangles_bounds"::"main", [256, 1, 1],
    [Read, ReadWrite, ReadWrite]);

/// CPU twin: the triangles' boxes.
pub fn prim_boxes_cpu(triangles: &[Triangle]) -> Vec<Aabb> {
    triangles.iter().map(Triangle::bounds).collect()
}

/// What `TrianglesBounds` computes.
#[derive(Clone, Copy)]
pub enum TriangleBoundsOutput<'a> {
    /// The LBVH's input: every triangle's box into the buffer, and the bounds of their centroids.
    LbvhInput(&'a wgpu::Buffer),
    /// Only the box of all triangles (the scene box); the buffer (any storage buffer) is bound
    /// in the boxes' place and never written.
    SceneBox(&'a wgpu::Buffer),
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

    /// Records `output` for `count` triangles, the reduced box into `box_words` (zeroed
    /// beforehand; `lbvh::box_of_words` reads them).
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        triangles: &wgpu::Buffer,
        count: u32,
        output: TriangleBoundsOutput<'_>,
        box_words: &wgpu::Buffer,
    ) {
        let ctx = pass.ctx();
        let (prim_boxes, lbvh_input) = match output {
            TriangleBoundsOutput::LbvhInput(boxes) => (boxes, 1),
            TriangleBoundsOutput::SceneBox(placeholder) => (placeholder, 0),
        };
        let params = TriangleBoundsParams {
            count,
            lbvh_input,
            _pad: [0; 2],
        };
        pass.dispatch(
            &self.kernel,
            reduce_grid(ctx, count),
            &params,
            &[triangles, prim_boxes, box_words],
        );
    }
}
