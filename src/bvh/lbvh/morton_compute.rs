//! LBVH stage 2: Morton keys of triangle AABB centroids in the scene's centroid bounds (kernel
//! `morton_compute`), and the CPU twin with the same float steps. Centroids are quantized on a
//! 2^21-cell grid per axis; the full key interleaves the high `MORTON_AXIS_BITS` (16) bits of each
//! axis (48 bits), and a build keeps its high `key_bits` of them: fewer radix-sort passes (4 bits
//! each), and an order consistent with the full key's (ties go to the primitive index). How many
//! it keeps may depend on the primitive count (`KeyWidth`): `lbvh` narrows its keys past 2^20
//! primitives so that the indices still fit above them.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use crate::geometry::Aabb;
use crate::gpu::constants::{MORTON_AXIS_BITS, MORTON_GRID};
use crate::gpu::{kernel, ItemCount, Kernel, Pass};
use crate::sort::packs_indices;

/// Bits of the full key: `MORTON_AXIS_BITS` per axis.
pub const MORTON_BITS: u32 = 3 * MORTON_AXIS_BITS;
/// Key bits of the `lbvh` builder up to 2^20 primitives (`KeyWidth::LBVH`): 44 of 48 (11 sort
/// passes), so that a dense object in a large,
/// empty scene still spreads over many cells: the trees' SAH is that of 48 bits to 0.001 % on the
/// shared scenes and an object in a 500× larger box, where 36 bits cost 20 % (README, "Build
/// floor").
pub const LBVH_KEY_BITS: u32 = 44;
/// The fewest key bits `lbvh` narrows its keys to where the primitives' indices do not fit above
/// 44 bits (past 2^20 primitives), so that its sort still moves each index with its key: 40
/// bits hold 2^24 primitives in 10 sort passes. The trees' SAH at 40 bits is that of 44 to 4
/// decimals on the shared scenes and 0.003 % above it on the stadium (README, "Build floor").
pub const LBVH_PACKED_KEY_BITS: u32 = 40;
/// Key bits of the treelet builders (`trbvh`, `trbvh-split`): 32 (8 sort passes). Keys that
/// coarse change the LBVH of a dense object in a large scene, but the treelet rounds repair it:
/// the optimized trees' SAH moves by at most 0.1 % on the scenes measured (README, "Build floor").
pub const TRBVH_KEY_BITS: u32 = 32;

/// How many of the full key's high bits a builder's keys keep, by primitive count: `most`, or,
/// where the indices of that many primitives do not fit above `most` bits, the most bits that
/// leave room for them, down to `least` (the sort then moves each pair as one word,
/// `sort::packs_indices`); below `least`, `most` again with the indices apart.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct KeyWidth {
    pub most: u32,
    pub least: u32,
}

impl KeyWidth {
    /// The `lbvh` builder's width: 44 bits, narrowed to 40 as the count grows to 2^24.
    pub const LBVH: KeyWidth = KeyWidth {
        most: LBVH_KEY_BITS,
        least: LBVH_PACKED_KEY_BITS,
    };

    /// Always `bits` bits.
    pub const fn fixed(bits: u32) -> KeyWidth {
        KeyWidth {
            most: bits,
            least: bits,
        }
    }

    /// The key bits of a build over `count` primitives.
    pub fn bits(self, count: u32) -> u32 {
        let index_bits = u32::BITS - count.saturating_sub(1).leading_zeros();
        let room = 64 - index_bits;
        if room < self.most && room >= self.least {
            room
        } else {
            self.most
        }
    }
}

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
    /// How many high bits of the full key the keys keep (1..=48), by primitive count.
    pub width: KeyWidth,
}

impl MortonCompute {
    pub fn new(ctx: &crate::gpu::GpuContext, width: KeyWidth) -> Self {
        Self {
            kernel: Kernel::new(ctx, &MORTON_COMPUTE),
            width,
        }
    }

    /// The key bits of a build over up to `capacity` primitives.
    pub fn key_bits(&self, capacity: u32) -> u32 {
        self.width.bits(capacity)
    }

    /// Whether the keys of `capacity` primitives carry their indices (`sort::packs_indices`):
    /// where the values fit above the key bits, the sort moves each pair as one word.
    pub fn packs_indices(&self, capacity: u32) -> bool {
        packs_indices(self.key_bits(capacity), capacity)
    }

    /// Records key computation over `count` primitive boxes: `keys[i]` (as `[lo, hi]`, the high
    /// `key_bits` of the full key) and `values[i] = i` (the permutation the sort reorders), or,
    /// where they pack the indices (`packs_indices` of the capacity), `keys[i]` = key | i <<
    /// key_bits (the sort's `SortValues::AboveKeys` form).
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
            key_bits: self.key_bits(count.capacity()),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lbvh_keys_narrow_only_where_the_indices_need_the_room() {
        let bits = |count| KeyWidth::LBVH.bits(count);
        assert_eq!(bits(0), 44);
        assert_eq!(bits(1), 44);
        assert_eq!(bits(1 << 20), 44);
        assert_eq!(bits((1 << 20) + 1), 43);
        assert_eq!(bits(1 << 21), 43);
        assert_eq!(bits((1 << 23) + 1), 40);
        assert_eq!(bits(1 << 24), 40);
        assert_eq!(bits((1 << 24) + 1), 44);
        assert_eq!(bits(u32::MAX), 44);
        for count in [1, 1 << 20, (1 << 20) + 1, 8_720_000, 1 << 24] {
            assert!(packs_indices(bits(count), count), "{count}");
        }
        assert!(!packs_indices(bits((1 << 24) + 1), (1 << 24) + 1));
        assert_eq!(KeyWidth::fixed(32).bits(u32::MAX), 32);
        assert_eq!(KeyWidth::fixed(48).bits(1 << 16), 48);
    }
}
