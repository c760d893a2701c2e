//! Batched ray queries on the GPU (`shaders/rays_intersect.wgsl`): closest hit, or any hit.

use bytemuck::{Pod, Zeroable};

use super::GpuScene;
use crate::geometry::{Hit, Ray};
use crate::gpu::{
    bind_entry, compute_pipeline, dispatch_grid, read_buffer, storage_buffer,
    storage_buffer_zeroed, uniform_buffer, GpuContext,
};
use crate::{Error, Result};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct QueryParams {
    ray_count: u32,
    row_pitch: u32,
    /// Always 0: keeps the triangle test's products unfused (`opaque` in ray_triangle.wgsl).
    opaque_zero: u32,
    /// 1: any hit in the interval (stops at the first), 0: the closest hit.
    any_hit: u32,
}
const _: () = assert!(std::mem::size_of::<QueryParams>() == 16);

const WORKGROUP: u32 = 64;

/// Closest hit of every ray through the scene's BVH. Misses have `tri == Hit::MISS`.
pub fn closest_hits(ctx: &GpuContext, scene: &GpuScene, rays: &[Ray]) -> Result<Vec<Hit>> {
    query(ctx, scene, rays, false)
}

/// Some hit of every ray in its interval (the first the traversal finds, as for shadow rays).
/// Misses have `tri == Hit::MISS`.
pub fn any_hits(ctx: &GpuContext, scene: &GpuScene, rays: &[Ray]) -> Result<Vec<Hit>> {
    query(ctx, scene, rays, true)
}

fn query(ctx: &GpuContext, scene: &GpuScene, rays: &[Ray], any_hit: bool) -> Result<Vec<Hit>> {
    if rays.is_empty() {
        return Ok(Vec::new());
    }
    let ray_count = u32::try_from(rays.len())
        .map_err(|_| Error::InvalidArgument(format!("{} rays in one batch", rays.len())))?;
    let pipeline = compute_pipeline(ctx, "rays_intersect.wgsl", "main");
    let (gx, gy) = dispatch_grid(ctx, ray_count, WORKGROUP);
    let params = uniform_buffer(
        ctx,
        "query params",
        &QueryParams {
            ray_count,
            row_pitch: gx * WORKGROUP,
            opaque_zero: 0,
            any_hit: u32::from(any_hit),
        },
    );
    let ray_buffer = storage_buffer(ctx, "rays", rays)?;
    let hits = storage_buffer_zeroed(ctx, "hits", std::mem::size_of_val(rays) as u64 / 2)?;
    let counters = storage_buffer_zeroed(ctx, "query counters", 4)?;
    let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("rays_intersect"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            bind_entry(0, &params),
            bind_entry(1, &scene.triangles),
            bind_entry(2, &scene.nodes),
            bind_entry(3, &scene.prim_indices),
            bind_entry(4, &ray_buffer),
            bind_entry(5, &hits),
            bind_entry(6, &counters),
        ],
    });
    let mut encoder = ctx
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("ray query"),
        });
    {
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("rays_intersect"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
    ctx.queue.submit([encoder.finish()]);
    let overflows: Vec<u32> = read_buffer(ctx, &counters, 1)?;
    if overflows[0] > 0 {
        return Err(Error::Gpu(format!(
            "{} rays overflowed the traversal stack (tree too deep)",
            overflows[0]
        )));
    }
    read_buffer(ctx, &hits, rays.len())
}
