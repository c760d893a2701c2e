//! Convex polygons clipped by axis-aligned planes, one plane at a time: Sutherland & Hodgman,
//! "Reentrant Polygon Clipping" (CACM 1974), in f64. The SBVH clips its references with it.

use glam::DVec3;

/// The side of a plane a clip keeps (points on the plane belong to both).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HalfSpace {
    /// Coordinates ≤ the plane's.
    Below,
    /// Coordinates ≥ the plane's.
    Above,
}

/// A convex polygon of at most `N` vertices.
#[derive(Clone, Copy)]
pub struct Polygon<const N: usize> {
    vertices: [DVec3; N],
    len: usize,
    overflowed: bool,
}

impl<const N: usize> Polygon<N> {
    pub fn triangle(vertices: [DVec3; 3]) -> Self {
        let mut polygon = Self {
            vertices: [DVec3::ZERO; N],
            len: 0,
            overflowed: false,
        };
        for v in vertices {
            polygon.push(v);
        }
        polygon
    }

    pub fn vertices(&self) -> &[DVec3] {
        &self.vertices[..self.len]
    }

    /// Whether clipping ran out of vertex slots and dropped vertices (only conceivable for
    /// numerically degenerate input; a triangle clipped by 6 planes has at most 9 vertices).
    pub fn overflowed(&self) -> bool {
        self.overflowed
    }

    fn push(&mut self, v: DVec3) {
        if self.len == N {
            self.overflowed = true;
        } else {
            self.vertices[self.len] = v;
            self.len += 1;
        }
    }

    /// The part in `keep` of the plane where coordinate `axis` equals `plane`: each vertex inside
    /// is kept and each edge between inside and outside adds its crossing point, `a + (b − a)·t`
    /// with `t = (plane − a) / (b − a)` along the axis, clamped into the box of the edge's ends
    /// (rounding cannot move it off the edge's box) and with the axis coordinate set to the
    /// plane's.
    pub fn clip(&self, axis: usize, plane: f64, keep: HalfSpace) -> Self {
        let mut out = Self {
            vertices: [DVec3::ZERO; N],
            len: 0,
            overflowed: self.overflowed,
        };
        let inside = |v: DVec3| match keep {
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
                let mut p = (a + (b - a) * t).max(a.min(b)).min(a.max(b));
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
    fn right_triangle<const N: usize>() -> Polygon<N> {
        Polygon::triangle([
            DVec3::ZERO,
            DVec3::new(2.0, 0.0, 0.0),
            DVec3::new(0.0, 2.0, 0.0),
        ])
    }

    #[test]
    fn clipping_keeps_the_side_and_adds_the_crossings() {
        let triangle = right_triangle::<9>();
        let below = triangle.clip(0, 1.0, HalfSpace::Below);
        assert_eq!(
            below.vertices(),
            [
                DVec3::ZERO,
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0),
                DVec3::new(0.0, 2.0, 0.0)
            ]
        );
        let above = triangle.clip(0, 1.0, HalfSpace::Above);
        assert_eq!(
            above.vertices(),
            [
                DVec3::new(1.0, 0.0, 0.0),
                DVec3::new(2.0, 0.0, 0.0),
                DVec3::new(1.0, 1.0, 0.0)
            ]
        );
        // A plane the triangle only touches leaves the touching vertex (and the crossings of its
        // edges there); one it misses leaves nothing.
        let touching = triangle.clip(1, 2.0, HalfSpace::Above);
        assert_eq!(touching.vertices(), [DVec3::new(0.0, 2.0, 0.0); 3]);
        let missed = triangle.clip(2, 1.0, HalfSpace::Above);
        assert!(missed.vertices().is_empty() && !missed.overflowed());
    }

    #[test]
    fn vertices_beyond_the_capacity_are_dropped_and_flagged() {
        let clipped = right_triangle::<3>().clip(0, 1.0, HalfSpace::Below);
        assert_eq!(clipped.vertices().len(), 3);
        assert!(clipped.overflowed());
        // The flag survives further clipping.
        let again = clipped.clip(1, 5.0, HalfSpace::Below);
        assert!(again.overflowed());
    }
}
