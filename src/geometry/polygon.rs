//! Convex polygons clipped by axis-aligned planes, one plane at a time: Sutherland & Hodgman,
//! "Reentrant Polygon Clipping" (CACM 1974), in f32 or f64. Triangle pre-splitting clips in f32
//! with the operations of the GPU kernel `triangles_split.wgsl`; the SBVH clips references in f64.

use std::ops::{Add, Div, Index, IndexMut, Mul, Sub};

use glam::{DVec3, Vec3};

/// A point of either precision, with the operations clipping needs.
pub trait ClipPoint:
    Copy
    + Default
    + Index<usize, Output = Self::Scalar>
    + IndexMut<usize>
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Self::Scalar, Output = Self>
{
    type Scalar: Copy + PartialOrd + Sub<Output = Self::Scalar> + Div<Output = Self::Scalar>;

    /// Per-component minimum.
    fn min(self, other: Self) -> Self;
    /// Per-component maximum.
    fn max(self, other: Self) -> Self;
}

/// Implements [`ClipPoint`] for a glam vector type with its own `min` and `max`.
macro_rules! impl_clip_point {
    ($vector:ty, $scalar:ty) => {
        impl ClipPoint for $vector {
            type Scalar = $scalar;

            fn min(self, other: Self) -> Self {
                <$vector>::min(self, other)
            }

            fn max(self, other: Self) -> Self {
                <$vector>::max(self, other)
            }
        }
    };
}

impl_clip_point!(Vec3, f32);
impl_clip_point!(DVec3, f64);

/// The side of a plane a clip keeps (points on the plane belong to both).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HalfSpace {
    /// Coordinates ≤ the plane's.
    Below,
    /// Coordinates ≥ the plane's.
    Above,
}

/// Where the point at which an edge crosses the clip plane lands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crossing {
    /// `a + (b − a)·t` as rounded, `t = (plane − a) / (b − a)` along the axis, with the axis
    /// coordinate set to the plane's.
    Interpolated,
    /// The interpolated point clamped into the box of the edge's ends (rounding cannot move it off
    /// the edge's box), with the axis coordinate set to the plane's.
    WithinEdgeBox,
}

/// A convex polygon of at most `N` vertices.
#[derive(Clone, Copy)]
pub struct Polygon<P, const N: usize> {
    vertices: [P; N],
    len: usize,
    overflowed: bool,
}

impl<P: ClipPoint, const N: usize> Polygon<P, N> {
    pub fn triangle(vertices: [P; 3]) -> Self {
        let mut polygon = Self {
            vertices: [P::default(); N],
            len: 0,
            overflowed: false,
        };
        for v in vertices {
            polygon.push(v);
        }
        polygon
    }

    pub fn vertices(&self) -> &[P] {
        &self.vertices[..self.len]
    }

    /// Whether clipping ran out of vertex slots and dropped vertices (only conceivable for
    /// numerically degenerate input; a triangle clipped by 6 planes has at most 9 vertices).
    pub fn overflowed(&self) -> bool {
        self.overflowed
    }

    fn push(&mut self, v: P) {
        if self.len == N {
            self.overflowed = true;
        } else {
            self.vertices[self.len] = v;
            self.len += 1;
        }
    }

    /// The part in `keep` of the plane where coordinate `axis` equals `plane`: each vertex inside
    /// is kept and each edge between inside and outside adds its crossing point.
    pub fn clip(&self, axis: usize, plane: P::Scalar, keep: HalfSpace, crossing: Crossing) -> Self {
        let mut out = Self {
            vertices: [P::default(); N],
            len: 0,
            overflowed: self.overflowed,
        };
        let inside = |v: P| match keep {
            HalfSpace::Below => v[axis] <= plane,
            HalfSpace::Above => v[axis] >= plane,
        };
        let n = self.len;
        for i in 0..n {
            let a = self.vertices[i];
            let b = self.vertices[(i + 1) % n];
            let a_inside = inside(a);
            if a_inside {
                out.push(a);
            }
            if a_inside != inside(b) {
                // One end is strictly beyond the plane, so the denominator is not zero.
                let t = (plane - a[axis]) / (b[axis] - a[axis]);
                let mut p = a + (b - a) * t;
                if crossing == Crossing::WithinEdgeBox {
                    p = p.max(a.min(b)).min(a.max(b));
                }
                p[axis] = plane;
                out.push(p);
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The right triangle (0,0,0), (2,0,0), (0,2,0).
    fn right_triangle<const N: usize>() -> Polygon<Vec3, N> {
        Polygon::triangle([
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 2.0, 0.0),
        ])
    }

    #[test]
    fn clipping_keeps_the_side_and_adds_the_crossings() {
        let triangle = right_triangle::<9>();
        let below = triangle.clip(0, 1.0, HalfSpace::Below, Crossing::Interpolated);
        assert_eq!(
            below.vertices(),
            [
                Vec3::ZERO,
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 2.0, 0.0)
            ]
        );
        let above = triangle.clip(0, 1.0, HalfSpace::Above, Crossing::WithinEdgeBox);
        assert_eq!(
            above.vertices(),
            [
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0)
            ]
        );
        // A plane the triangle only touches leaves the touching vertex (and the crossings of its
        // edges there); one it misses leaves nothing.
        let touching = triangle.clip(1, 2.0, HalfSpace::Above, Crossing::Interpolated);
        assert_eq!(touching.vertices(), [Vec3::new(0.0, 2.0, 0.0); 3]);
        let missed = triangle.clip(2, 1.0, HalfSpace::Above, Crossing::Interpolated);
        assert!(missed.vertices().is_empty() && !missed.overflowed());
    }

    #[test]
    fn vertices_beyond_the_capacity_are_dropped_and_flagged() {
        let clipped = right_triangle::<3>().clip(0, 1.0, HalfSpace::Below, Crossing::Interpolated);
        assert_eq!(clipped.vertices().len(), 3);
        assert!(clipped.overflowed());
        // The flag survives further clipping.
        let again = clipped.clip(1, 5.0, HalfSpace::Below, Crossing::Interpolated);
        assert!(again.overflowed());
    }
}
