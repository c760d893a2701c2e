//! Watertight ray/triangle intersection (Woop, Benthin & Wald 2013, "Watertight Ray/Triangle
//! Intersection", JCGT 2(1)). The WGSL twin is `shaders/include/ray_triangle.wgsl`; the brute-force
//! oracle, the CPU traversal and every GPU traversal use this one test.
//!
//! Per ray: the axis of the largest direction component becomes z (`kz`), the other two x and y;
//! the permuted direction is scaled by a power of two (exact) so that its largest component lies
//! in [1, 2). Per triangle: the vertices, relative to the origin, are sheared into the plane
//! orthogonal to the ray (each coordinate multiplied by `dz`, which needs no division), and the
//! three 2D edge functions U, V, W decide the hit by their signs alone.
//!
//! Why no ray escapes through a closed mesh: a vertex shared by neighbouring triangles is sheared
//! by the same correctly rounded operations in both, and the edge function of a shared edge is
//! `p.x·q.y − p.y·q.x` in one triangle and exactly its negation in the other (products commute,
//! `a − b = −(b − a)` in IEEE arithmetic). Zero counts as inside for both, so the neighbours leave
//! no crack. This holds only if no product is fused into a following add or subtract (FMA
//! contraction, which GPU compilers do and WGSL allows): the kernel passes every product through
//! `unfused` (unfused.wgsl), an XOR with a zero the compiler cannot see. With that, hit-or-miss
//! decisions use only correctly rounded multiplies and subtractions and are bit-identical on the
//! CPU and on any Vulkan device (up to denormals, which GPUs may flush); only the final division
//! for `t` is approximate on some GPUs (a few ulps).
//!
//! Both windings hit. A triangle seen exactly edge-on (U + V + W = 0) is missed; its neighbours
//! cover the ray.

use glam::Vec3;

use super::Ray;

/// Per-ray constants of the watertight test: compute once per ray, test many triangles.
#[derive(Clone, Copy, Debug)]
pub struct RayTriangleTest {
    origin: Vec3,
    /// The axis of the largest |direction| component (ties: x before y before z).
    kz: usize,
    /// The direction permuted to (kx, ky, kz) and scaled by a power of two.
    shear: Vec3,
    /// The unscaled direction component along `kz` (turns the scaled distance into `t`).
    dz: f32,
}

impl RayTriangleTest {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x >= a.y && a.x >= a.z {
            0
        } else if a.y >= a.z {
            1
        } else {
            2
        };
        let largest = a.x.max(a.y).max(a.z);
        let d = permute(dir, kz);
        Self {
            origin,
            kz,
            shear: d * power_of_two_scale(largest),
            dz: d.z,
        }
    }

    pub fn for_ray(ray: &Ray) -> Self {
        Self::new(Vec3::from(ray.origin), Vec3::from(ray.dir))
    }

    /// `(t, u, v)` when the ray hits the triangle with `t_min < t < t_max`: `u` and `v` are the
    /// barycentric weights of `v1` and `v2`. Edges and vertices are inclusive.
    pub fn intersect(
        &self,
        v0: Vec3,
        v1: Vec3,
        v2: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<(f32, f32, f32)> {
        let a = permute(v0 - self.origin, self.kz);
        let b = permute(v1 - self.origin, self.kz);
        let c = permute(v2 - self.origin, self.kz);
        let (a2, b2, c2) = (self.sheared(a), self.sheared(b), self.sheared(c));
        let u = edge_function(c2, b2);
        let v = edge_function(a2, c2);
        let w = edge_function(b2, a2);
        let inside = (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0);
        let det = u + v + w;
        if !inside || det == 0.0 {
            return None;
        }
        let scaled_t = u * a.z + v * b.z + w * c.z;
        let t = scaled_t / (det * self.dz);
        (t > t_min && t < t_max).then(|| (t, v / det, w / det))
    }

    /// A permuted point's 2D coordinates in the plane orthogonal to the ray, times the scaled dz.
    fn sheared(&self, p: Vec3) -> [f32; 2] {
        let s = self.shear;
        [s.z * p.x - s.x * p.z, s.z * p.y - s.y * p.z]
    }
}

/// `p.x·q.y − p.y·q.x`: twice the signed area of (origin, p, q); negated when p and q swap.
fn edge_function(p: [f32; 2], q: [f32; 2]) -> f32 {
    p[0] * q[1] - p[1] * q[0]
}

/// `v` reordered to (kx, ky, kz) with kx = kz + 1, ky = kz + 2 (mod 3).
fn permute(v: Vec3, kz: usize) -> Vec3 {
    match kz {
        0 => Vec3::new(v.y, v.z, v.x),
        1 => Vec3::new(v.z, v.x, v.y),
        _ => v,
    }
}

/// 2^(127 − e) for `largest` with biased exponent e (capped at 253): scales it into [1, 2)
/// exactly. Same bit arithmetic as `power_of_two_scale` in the WGSL twin.
fn power_of_two_scale(largest: f32) -> f32 {
    let biased = ((largest.to_bits() >> 23) & 0xff).min(253);
    f32::from_bits((254 - biased) << 23)
}

/// The watertight test of one ray against one triangle (`ray.t_min < t < ray.t_max`).
pub fn intersect_triangle(ray: &Ray, v0: Vec3, v1: Vec3, v2: Vec3) -> Option<(f32, f32, f32)> {
    RayTriangleTest::for_ray(ray).intersect(v0, v1, v2, ray.t_min, ray.t_max)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_report_distance_and_barycentrics() {
        let ray = Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z, 0.0, f32::MAX);
        let (t, u, v) = intersect_triangle(&ray, Vec3::ZERO, Vec3::X, Vec3::Y).unwrap();
        assert_eq!((t, u, v), (1.0, 0.25, 0.25));
        // The other winding hits too.
        let (t, u, v) = intersect_triangle(&ray, Vec3::ZERO, Vec3::Y, Vec3::X).unwrap();
        assert_eq!((t, u, v), (1.0, 0.25, 0.25));
        // An unnormalized direction scales t.
        let long = Ray::new(Vec3::new(0.25, 0.25, -1.0), Vec3::Z * 8.0, 0.0, f32::MAX);
        assert_eq!(
            intersect_triangle(&long, Vec3::ZERO, Vec3::X, Vec3::Y)
                .unwrap()
                .0,
            0.125
        );
    }

    #[test]
    fn interval_misses_and_degenerate_rays() {
        let tri = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let hit = |o: Vec3, d: Vec3, t0: f32, t1: f32| {
            intersect_triangle(&Ray::new(o, d, t0, t1), tri[0], tri[1], tri[2]).is_some()
        };
        let o = Vec3::new(0.25, 0.25, -1.0);
        assert!(!hit(o, Vec3::Z, 1.0, 2.0), "t == t_min is outside");
        assert!(!hit(o, Vec3::Z, 0.0, 1.0), "t == t_max is outside");
        assert!(!hit(o, -Vec3::Z, 0.0, f32::MAX), "behind the origin");
        assert!(!hit(Vec3::new(0.8, 0.8, -1.0), Vec3::Z, 0.0, f32::MAX));
        assert!(!hit(o, Vec3::ZERO, 0.0, f32::MAX), "zero direction");
        assert!(
            !hit(o, Vec3::splat(f32::NAN), 0.0, f32::MAX),
            "NaN direction"
        );
        assert!(
            !hit(Vec3::new(-1.0, 0.1, 0.0), Vec3::X, 0.0, f32::MAX),
            "edge-on"
        );
    }

    #[test]
    fn edges_and_vertices_are_inclusive() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        for target in [a, b, c, 0.5 * (a + b), 0.5 * (b + c), 0.5 * (c + a)] {
            let o = target - Vec3::new(0.1, 0.2, 1.0);
            let ray = Ray::new(o, target - o, 0.0, f32::MAX);
            assert!(intersect_triangle(&ray, a, b, c).is_some(), "{target}");
        }
    }

    /// Two triangles sharing an edge: every ray through points of the edge hits at least one,
    /// whatever its direction (Möller–Trumbore lets some of these through).
    #[test]
    fn a_shared_edge_leaves_no_crack() {
        let (p, q) = (Vec3::new(0.1, -3.3, 0.7), Vec3::new(2.9, 1.7, -0.3));
        let (l, r) = (Vec3::new(-1.3, 0.9, 0.2), Vec3::new(1.9, -2.1, 1.1));
        let mut state = 12345u32;
        let mut next = || {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            state as f32 / u32::MAX as f32
        };
        for _ in 0..20_000 {
            let s = next();
            let target = p + s * (q - p);
            let o = target + Vec3::new(next() - 0.5, next() - 0.5, next() + 0.5) * 7.0;
            let ray = Ray::new(o, target - o, 0.0, f32::MAX);
            let left = intersect_triangle(&ray, p, q, l).is_some();
            let right = intersect_triangle(&ray, q, p, r).is_some();
            assert!(
                left || right,
                "ray through {target} slipped between the triangles"
            );
        }
    }
}
