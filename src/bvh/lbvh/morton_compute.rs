//! LBVH stage 2: 48-bit Morton keys of triangle AABB centroids in the scene's centroid bounds
//! (kernel `morton_compute`): the high `MORTON_AXIS_BITS` (16) bits per axis of a 2^21-cell grid;
//! and the CPU twin with the same float steps.

use glam::Vec3;

use crate::geometry::Aabb;
use crate::gpu::constants::{MORTON_AXIS_BITS, MORTON_GRID};
use crate::gpu::{kernel, ItemCount, Items, Kernel, Pass};

/// Key bits: `MORTON_AXIS_BITS` per axis.
pub const MORTON_BITS: u32 = 3 * MORTON_AXIS_BITS;

kernel!(pub MORTON_COMPUTE: Items = "morton_compute"::"main", [64, 1, 1], [Read, Read, ReadWrite, ReadWrite, Read]);

/// Spreads the low `MORTON_AXIS_BITS` bits of x so that bit k lands on bit 3k.
fn spread_bits(x: u32) -> u64 {
    (0..MORTON_AXIS_BITS).fold(0u64, |acc, k| acc | (u64::from((x >> k) & 1) << (3 * k)))
}

/// CPU twin: the Morton key of one primitive box's centroid within `bounds`. The grid is cubic:
/// its cell size follows the bounds' longest side on every axis, so flat scenes do not spend key
/// bits (and top-level splits) on their thin axis.
pub fn morton_key(b: &Aabb, bounds: &Aabb) -> u64 {
    let c = (b.min + b.max) * 0.5;
    let extent = (bounds.max - bounds.min).max_element();
    let grid = MORTON_GRID as f32;
    let scale = if extent > 0.0 { grid / extent } else { 0.0 };
    let q = ((c - bounds.min) * scale).clamp(Vec3::ZERO, Vec3::splat(grid - 1.0));
    let kept = |x: f32| spread_bits(x as u32 >> (MORTON_GRID.ilog2() - MORTON_AXIS_BITS));
    (kept(q.x) << 2) | (kept(q.y) << 1) | kept(q.z)
}

/// CPU twin of the whole stage.
pub fn morton_keys_cpu(prim_boxes: &[Aabb], bounds: &Aabb) -> Vec<u64> {
    prim_boxes.iter().map(|b| morton_key(b, bounds)).collect()
}

/// The kernel `morton_compute`.
pub(crate) struct MortonCompute {
    kernel: Kernel<Items>,
}

impl MortonCompute {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Self {
        Self {
            kernel: Kernel::new(ctx, &MORTON_COMPUTE),
        }
    }

    /// Records key computation over `count` primitive boxes: `keys[i]` (as `[lo, hi]`) and
    /// `values[i] = i` (the permutation the sort reorders).
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        prim_boxes: &wgpu::Buffer,
        count: ItemCount<'_>,
        centroid_bounds: &wgpu::Buffer,
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
    ) {
        pass.dispatch_counted(
            &self.kernel,
            count,
            &[prim_boxes, centroid_bounds, keys, values],
        );
    }
}
