//! Batched ray queries on the GPU (kernel `rays_intersect`): the closest hit of every ray, or
//! any hit in its interval, through a tree.

use bytemuck::{Pod, Zeroable};

use crate::device::{Geometry, Tree};
use crate::geometry::{Hit, Ray};
use crate::gpu::{
    kernel, read_buffer, storage_buffer, storage_buffer_zeroed, GpuContext, Kernel, ParamSlab,
    Recorder,
};
use crate::{Error, Result};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct QueryParams {
    ray_count: u32,
    row_pitch: u32,
    /// Always 0: keeps the triangle test's products unfused (`opaque` in ray_triangle.wgsl).
    opaque_zero: u32,
    /// 1: any hit in the interval (stops at the first), 0: the closest hit.
    any_hit: u32,
}

kernel!(pub RAYS_INTERSECT: QueryParams = "rays_intersect"::"main", [64, 1, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite]);

/// Closest hit of every ray through `tree`. Misses have `tri == Hit::MISS`.
pub fn closest_hits(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
) -> Result<Vec<Hit>> {
    query(ctx, geometry, tree, rays, false)
}

/// Some hit of every ray in its interval (the first the traversal finds, as for shadow rays).
/// Misses have `tri == Hit::MISS`.
pub fn any_hits(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
) -> Result<Vec<Hit>> {
    query(ctx, geometry, tree, rays, true)
}

fn query(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
    any_hit: bool,
) -> Result<Vec<Hit>> {
    if rays.is_empty() {
        return Ok(Vec::new());
    }
    let ray_count = u32::try_from(rays.len())
        .map_err(|_| Error::InvalidArgument(format!("{} rays in one batch", rays.len())))?;
    let kernel = Kernel::new(ctx, &RAYS_INTERSECT);
    let grid = kernel.grid(ctx, ray_count);
    let params = QueryParams {
        ray_count,
        row_pitch: grid.row_pitch,
        opaque_zero: 0,
        any_hit: u32::from(any_hit),
    };
    let ray_buffer = storage_buffer(ctx, "rays", rays)?;
    let hits = storage_buffer_zeroed(ctx, "hits", std::mem::size_of_val(rays) as u64 / 2)?;
    let counters = storage_buffer_zeroed(ctx, "query counters", 4)?;
    let mut slab = ParamSlab::new(ctx);
    let mut rec = Recorder::new(ctx, &mut slab, None);
    rec.pass("rays_intersect").dispatch(
        &kernel,
        grid,
        &params,
        &[
            &geometry.triangles,
            &tree.nodes,
            &tree.prim_indices,
            &ray_buffer,
            &hits,
            &counters,
        ],
    );
    rec.submit();
    let overflows: Vec<u32> = read_buffer(ctx, &counters, 1)?;
    if overflows[0] > 0 {
        return Err(Error::Gpu(format!(
            "{} rays overflowed the traversal stack (tree too deep)",
            overflows[0]
        )));
    }
    read_buffer(ctx, &hits, rays.len())
}
