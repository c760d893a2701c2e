//! LBVH stage 2: Morton keys of triangle AABB centroids in the scene's centroid bounds (kernel
//! `morton_compute`), and the CPU twin with the same float steps. Centroids are quantized on a
//! 2^21-cell grid per axis; the full key interleaves the high `MORTON_AXIS_BITS` (16) bits of each
//! axis (48 bits), and a build keeps its high `key_bits` of them: fewer radix-sort passes (4 bits
//! each), and an order consistent with the full key's (ties go to the primitive index).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::geometry::Aabb;
use crate::gpu::constants::{MORTON_AXIS_BITS, MORTON_GRID};
use crate::gpu::{kernel, ItemCount, Kernel, Pass};
use crate::sort::packs_indices;

/// Bits of the full key: `MORTON_AXIS_BITS` per axis.
pub const MORTON_BITS: u32 = 3 * MORTON_AXIS_BITS;
/// Key bits of the `lbvh` builder: 44 of 48 (11 sort passes), so that a dense object in a large,
/// empty scene still spreads over many cells: the trees' SAH is that of 48 bits to 0.001 % on the
/// shared scenes and an object in a 500× larger box, where 36 bits cost 20 % (README, "Build
/// floor").
pub const LBVH_KEY_BITS: u32 = 44;
/// Key bits of the treelet builders (`trbvh`, `trbvh-split`): 32 (8 sort passes). Keys that
/// coarse change the LBVH of a dense object in a large scene, but the treelet rounds repair it:
/// the optimized trees' SAH moves by at most 0.1 % on the scenes measured (README, "Build floor").
pub const TRBVH_KEY_BITS: u32 = 32;

/// Parameters of `morton_compute.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct MortonParams {
    count: u32,
    row_pitch: u32,
    key_bits: u32,
    /// 1: the index goes above the key's bits (`sort::packs_indices`), not in the values.
    packed: u32,
}
const _: () = assert!(std::mem::size_of::<MortonParams>() == 16);

kernel!(pub MORTON_COMPUTE: MortonParams = "morton_compute"::"main", [64, 1, 1], [Read, Read, ReadWrite, ReadWrite, Read]);

/// Spreads the low `MORTON_AXIS_BITS` bits of x so that bit k lands on bit 3k.
fn spread_bits(x: u32) -> u64 {
    (0..MORTON_AXIS_BITS).fold(0u64, |acc, k| acc | (u64::from((x >> k) & 1) << (3 * k)))
}

/// CPU twin: the Morton key of one primitive box's centroid within `bounds`, its high `key_bits`
/// (1..=48) bits. The grid is cubic: its cell size follows the bounds' longest side on every axis,
/// so flat scenes do not spend key bits (and top-level splits) on their thin axis.
pub fn morton_key(b: &Aabb, bounds: &Aabb, key_bits: u32) -> u64 {
    let c = (b.min + b.max) * 0.5;
    let extent = (bounds.max - bounds.min).max_element();
    let grid = MORTON_GRID as f32;
    let scale = if extent > 0.0 { grid / extent } else { 0.0 };
    let q = ((c - bounds.min) * scale).clamp(Vec3::ZERO, Vec3::splat(grid - 1.0));
    let kept = |x: f32| spread_bits(x as u32 >> (MORTON_GRID.ilog2() - MORTON_AXIS_BITS));
    ((kept(q.x) << 2) | (kept(q.y) << 1) | kept(q.z)) >> (MORTON_BITS - key_bits)
}

/// CPU twin of the whole stage.
pub fn morton_keys_cpu(prim_boxes: &[Aabb], bounds: &Aabb, key_bits: u32) -> Vec<u64> {
    prim_boxes
        .iter()
        .map(|b| morton_key(b, bounds, key_bits))
        .collect()
}

/// The kernel `morton_compute`, and the width of the keys it writes.
pub(crate) struct MortonCompute {
    kernel: Kernel<MortonParams>,
    /// The high bits of the full key that the keys keep (1..=48).
    pub key_bits: u32,
}

impl MortonCompute {
    pub fn new(ctx: &crate::gpu::GpuContext, key_bits: u32) -> Self {
        Self {
            kernel: Kernel::new(ctx, &MORTON_COMPUTE),
            key_bits,
        }
    }

    /// Whether the keys of `capacity` primitives carry their indices (`sort::packs_indices`):
    /// where the values fit above the key bits, the sort moves each pair as one word.
    pub fn packs_indices(&self, capacity: u32) -> bool {
        packs_indices(self.key_bits, capacity)
    }

    /// Records key computation over `count` primitive boxes: `keys[i]` (as `[lo, hi]`, the high
    /// `key_bits` of the full key) and `values[i] = i` (the permutation the sort reorders), or,
    /// where they pack the indices (`packs_indices` of the capacity), `keys[i]` = key | i <<
    /// key_bits (the sort's `record_packed` form).
    pub fn record(
        &self,
        pass: &mut Pass<'_>,
        prim_boxes: &wgpu::Buffer,
        count: ItemCount<'_>,
        centroid_bounds: &wgpu::Buffer,
        keys: &wgpu::Buffer,
        values: &wgpu::Buffer,
    ) {
        let grid = self.kernel.grid(pass.ctx(), count.capacity());
        let params = MortonParams {
            count: count.capacity(),
            row_pitch: grid.row_pitch,
            key_bits: self.key_bits,
            packed: u32::from(self.packs_indices(count.capacity())),
        };
        pass.dispatch(
            &self.kernel,
            grid,
            &params,
            &[
                prim_boxes,
                centroid_bounds,
                keys,
                values,
                count.limit(pass.ctx()),
            ],
        );
    }
}
