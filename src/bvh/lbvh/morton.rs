//! LBVH stage 2: 63-bit Morton keys (21 bits per axis) of triangle AABB centroids in the scene's
//! centroid bounds (`shaders/morton_compute.wgsl`), and the CPU twin with the same float steps.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::Prims;
use crate::geometry::Aabb;
use crate::gpu::{bind_entry, compute_pipeline, dispatch_grid, uniform_buffer, GpuContext};
use crate::trace::GpuScene;

/// Key bits: 21 per axis.
pub const MORTON_BITS: u32 = 63;
const GRID: f32 = 2_097_152.0;
const WORKGROUP: u32 = 64;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct MortonParams {
    count: u32,
    row_pitch: u32,
    _pad: [u32; 2],
}
const _: () = assert!(std::mem::size_of::<MortonParams>() == 16);

/// Spreads the low 21 bits of x so that bit k lands on bit 3k.
fn spread_bits(x: u32) -> u64 {
    (0..21).fold(0u64, |acc, k| acc | (u64::from((x >> k) & 1) << (3 * k)))
}

/// CPU twin: the Morton key of one primitive box's centroid within `bounds`. The grid is cubic:
/// its cell size follows the bounds' longest side on every axis, so flat scenes do not spend key
/// bits (and top-level splits) on their thin axis.
pub fn morton_key(b: &Aabb, bounds: &Aabb) -> u64 {
    let c = (b.min + b.max) * 0.5;
    let extent = (bounds.max - bounds.min).max_element();
    let scale = if extent > 0.0 { GRID / extent } else { 0.0 };
    let q = ((c - bounds.min) * scale).clamp(Vec3::ZERO, Vec3::splat(GRID - 1.0));
    (spread_bits(q.x as u32) << 2) | (spread_bits(q.y as u32) << 1) | spread_bits(q.z as u32)
}

/// CPU twin of the whole stage.
pub fn morton_keys_cpu(prim_boxes: &[Aabb], bounds: &Aabb) -> Vec<u64> {
    prim_boxes.iter().map(|b| morton_key(b, bounds)).collect()
}

pub(crate) struct MortonKeys {
    pipeline: wgpu::ComputePipeline,
}

impl MortonKeys {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            pipeline: compute_pipeline(ctx, "morton_compute.wgsl", "main"),
        }
    }

    /// Records key computation over the primitives: `keys[i]` (as `[lo, hi]`) and
    /// `scene.prim_indices[i] = i` (the values the sort permutes).
    pub fn record(
        &self,
        ctx: &GpuContext,
        pass: &mut wgpu::ComputePass<'_>,
        prims: &Prims<'_>,
        scene: &GpuScene,
        centroid_bounds: &wgpu::Buffer,
        keys: &wgpu::Buffer,
    ) {
        let count = prims.count;
        let (gx, gy) = dispatch_grid(ctx, count, WORKGROUP);
        let params = uniform_buffer(
            ctx,
            "morton params",
            &MortonParams {
                count,
                row_pitch: gx * WORKGROUP,
                _pad: [0; 2],
            },
        );
        let bind_group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("morton_compute"),
            layout: &self.pipeline.get_bind_group_layout(0),
            entries: &[
                bind_entry(0, &params),
                bind_entry(1, prims.boxes),
                bind_entry(2, centroid_bounds),
                bind_entry(3, keys),
                bind_entry(4, &scene.prim_indices),
            ],
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups(gx, gy, 1);
    }
}
