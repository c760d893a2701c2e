//! Axis-aligned bounding boxes and their surface area (the SAH's probability measure).

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: Vec3,
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box: the identity of `union`.
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    pub fn from_points(points: &[Vec3]) -> Self {
        points.iter().fold(Self::EMPTY, |b, &p| b.grow(p))
    }

    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    pub fn extent(&self) -> Vec3 {
        (self.max - self.min).max(Vec3::ZERO)
    }

    pub fn centroid(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Surface area; 0 for empty or flat-in-all-but-one boxes.
    pub fn surface_area(&self) -> f32 {
        if self.is_empty() {
            return 0.0;
        }
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Whether `inner` lies inside `self`, allowing `tolerance` (absolute) on every face.
    pub fn contains(&self, inner: &Aabb, tolerance: f32) -> bool {
        inner.is_empty()
            || (inner.min.cmpge(self.min - Vec3::splat(tolerance)).all()
                && inner.max.cmple(self.max + Vec3::splat(tolerance)).all())
    }

    /// Index of the longest axis (0 = x, 1 = y, 2 = z).
    pub fn largest_axis(&self) -> usize {
        let e = self.extent();
        if e.x >= e.y && e.x >= e.z {
            0
        } else if e.y >= e.z {
            1
        } else {
            2
        }
    }
}

/// A box as the GPU stages exchange it (32 bytes, like a `BvhNode`'s bounds; WGSL twin `Aabb` in
/// `shaders/include/aabb.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable, PartialEq)]
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
