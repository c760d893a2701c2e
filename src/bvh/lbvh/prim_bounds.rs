//! LBVH stage 0: one primitive box per triangle (`shaders/triangles_bounds.wgsl`) and its CPU twin.
//! The build runs over primitive boxes so that pre-split references (several clipped boxes per
//! triangle) go through the same stages.

use bytemuck::{Pod, Zeroable};

use crate::geometry::Aabb;
use crate::gpu::{bind_entry, compute_pipeline, dispatch_grid, uniform_buffer, GpuContext};
use crate::scene::Triangle;

const WORKGROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BoundsParams {
    count: u32,
    row_pitch: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<BoundsParams>() == 16);

/// A box as the GPU stages exchange it (32 bytes, like a `BvhNode`'s bounds).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct GpuAabb {
    pub min: [f32; 3],
    pub _pad0: u32,
    pub max: [f32; 3],
    pub _pad1: u32,
}
const _: () = assert!(std::mem::size_of::<GpuAabb>() == 32);

impl From<Aabb> for GpuAabb {
    fn from(b: Aabb) -> Self {
        Self {
            min: b.min.to_array(),
            _pad0: 0,
            max: b.max.to_array(),
            _pad1: 0,
        }
    }
}

impl From<GpuAabb> for Aabb {
    fn from(b: GpuAabb) -> Self {
        Aabb::new(b.min.into(), b.max.into())
    }
}

/// CPU twin: the triangles' boxes.
pub fn prim_boxes_cpu(triangles: &[Triangle]) -> Vec<Aabb> {
    triangles.iter().map(Triangle::bounds).collect()
}

pub struct TriangleBounds {
    pipeline: wgpu::ComputePipeline,
}

impl TriangleBounds {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            pipeline: compute_pipeline(ctx, "triangles_bounds.wgsl", "main"),
        }
    }

    /// Records `prim_boxes[i] = bounds(triangles[i])` for `count` triangles.
    pub fn record(
        &self,
        ctx: &GpuContext,
        pass: &mut wgpu::ComputePass<'_>,
        triangles: &wgpu::Buffer,
        count: u32,
        prim_boxes: &wgpu::Buffer,
    ) {
        let (gx, gy) = dispatch_grid(ctx, count, WORKGROUP);
        let params = uniform_buffer(
            ctx,
            "triangle bounds params",
            &BoundsParams {
                count,
                row_pitch: gx * WORKGROUP,
                _pad: [0; 2],
            },
        );
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("triangles_bounds"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &params),
                bind_entry(1, triangles),
                bind_entry(2, prim_boxes),
            ],
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
}
