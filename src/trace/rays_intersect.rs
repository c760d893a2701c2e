//! Batched ray queries on the GPU (kernels `rays_intersect`, `rays_intersect_wide`): the closest
//! hit of every ray, or any hit in its interval, through a tree in the binary or the wide layout;
//! on request with each ray's traversal steps.

use bytemuck::{Pod, Zeroable};

use super::paths_trace::COUNT_STEPS_OVERRIDE;
use crate::bvh::wide::Layout;
use crate::bvh::TraversalSteps;
use crate::device::{Geometry, Tree};
use crate::geometry::{Hit, Ray};
use crate::gpu::{
    flag_override, kernel, read_buffer, storage_buffer, storage_buffer_zeroed, GpuContext, Kernel,
    ParamSlab, Recorder,
};
use crate::{Error, Result};

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct QueryParams {
    ray_count: u32,
    row_pitch: u32,
    /// Always 0: keeps the triangle test's products unfused (`unfused` in unfused.wgsl).
    opaque_zero: u32,
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<QueryParams>() == 16);

/// The pipeline-overridable constant that picks the query (`override ANY_HIT` in
/// ray_queries.wgsl): 1 for any hit in the interval (the traversal stops at the first), 0 for
/// the closest hit.
pub const ANY_HIT_OVERRIDE: &str = "ANY_HIT";

kernel!(pub RAYS_INTERSECT: QueryParams = "rays_intersect"::"main", [64, 1, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite]);

kernel!(pub RAYS_INTERSECT_WIDE: QueryParams = "rays_intersect_wide"::"main", [64, 1, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite]);

/// Closest hit of every ray through `tree`. Misses have `tri == Hit::MISS`.
pub fn closest_hits(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
) -> Result<Vec<Hit>> {
    Ok(query(ctx, geometry, tree, rays, false, Layout::Binary, false)?.0)
}

/// Some hit of every ray in its interval (the first the traversal finds, as for shadow rays).
/// Misses have `tri == Hit::MISS`.
pub fn any_hits(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
) -> Result<Vec<Hit>> {
    Ok(query(ctx, geometry, tree, rays, true, Layout::Binary, false)?.0)
}

/// [`closest_hits`] through the tree's wide layout (`tree.wide`, from a conversion).
pub fn closest_hits_wide(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
) -> Result<Vec<Hit>> {
    Ok(query(ctx, geometry, tree, rays, false, Layout::Wide, false)?.0)
}

/// [`any_hits`] through the tree's wide layout (`tree.wide`, from a conversion).
pub fn any_hits_wide(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
) -> Result<Vec<Hit>> {
    Ok(query(ctx, geometry, tree, rays, true, Layout::Wide, false)?.0)
}

/// [`closest_hits`] through `layout` with each ray's traversal steps: the internal nodes whose
/// children's boxes it tested and the triangles it tested (binary: as the CPU twin
/// `Bvh::closest_hit_steps` counts them).
pub fn closest_hits_with_steps(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
    layout: Layout,
) -> Result<(Vec<Hit>, Vec<TraversalSteps>)> {
    query(ctx, geometry, tree, rays, false, layout, true)
}

/// The hits of `rays`, and their steps when `count_steps` (else none).
fn query(
    ctx: &GpuContext,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
    any_hit: bool,
    layout: Layout,
    count_steps: bool,
) -> Result<(Vec<Hit>, Vec<TraversalSteps>)> {
    if rays.is_empty() {
        return Ok((Vec::new(), Vec::new()));
    }
    let ray_count = u32::try_from(rays.len())
        .map_err(|_| Error::InvalidArgument(format!("{} rays in one batch", rays.len())))?;
    if let Some((i, ray)) = rays
        .iter()
        .enumerate()
        .find(|(_, r)| !r.has_valid_interval())
    {
        return Err(Error::InvalidArgument(format!(
            "ray {i} has the interval [{}, {}]: a ray's t_min must be >= 0 and <= t_max",
            ray.t_min, ray.t_max
        )));
    }
    // What the leaves' references are tested through: the binary tree's indices into the
    // triangles, the wide tree's copies of its references' triangles.
    let overrides = [
        flag_override(ANY_HIT_OVERRIDE, any_hit),
        flag_override(COUNT_STEPS_OVERRIDE, count_steps),
    ];
    let (kernel, nodes, leaf_data) = match layout {
        Layout::Binary => (
            Kernel::with_overrides(ctx, &RAYS_INTERSECT, &overrides),
            &tree.nodes,
            &tree.prim_indices,
        ),
        Layout::Wide => {
            let wide = tree.wide.as_ref().ok_or_else(|| {
                Error::InvalidArgument("the tree has no wide layout (convert it first)".into())
            })?;
            (
                Kernel::with_overrides(ctx, &RAYS_INTERSECT_WIDE, &overrides),
                &wide.nodes,
                &wide.triangles,
            )
        }
    };
    let grid = kernel.grid(ctx, ray_count);
    let params = QueryParams {
        ray_count,
        row_pitch: grid.row_pitch,
        opaque_zero: 0,
        _pad: 0,
    };
    let ray_buffer = storage_buffer(ctx, "rays", rays)?;
    let hits = storage_buffer_zeroed(ctx, "hits", std::mem::size_of_val(rays) as u64 / 2)?;
    // The overflow count, then two words of steps per ray where counted.
    let counter_words = if count_steps { 1 + 2 * rays.len() } else { 1 };
    let counters = storage_buffer_zeroed(ctx, "query counters", 4 * counter_words as u64)?;
    let mut slab = ParamSlab::new(ctx);
    let mut rec = Recorder::new(ctx, &mut slab, None);
    rec.pass("rays_intersect").dispatch(
        &kernel,
        grid,
        &params,
        &[
            &geometry.triangles,
            nodes,
            leaf_data,
            &ray_buffer,
            &hits,
            &counters,
        ],
    );
    rec.submit();
    let words: Vec<u32> = read_buffer(ctx, &counters, counter_words)?;
    if words[0] > 0 {
        return Err(Error::Gpu(format!(
            "{} rays overflowed the traversal stack (tree too deep)",
            words[0]
        )));
    }
    let steps = words[1..]
        .chunks_exact(2)
        .map(|w| TraversalSteps {
            nodes: u64::from(w[0]),
            triangles: u64::from(w[1]),
        })
        .collect();
    Ok((read_buffer(ctx, &hits, rays.len())?, steps))
}
