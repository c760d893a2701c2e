//! CPU brute-force closest hit over all triangles: the oracle for GPU traversal tests.

use crate::geometry::{intersect_triangle, Hit, Ray};
use crate::scene::Triangle;

/// The closest hit of `ray` among all `triangles` (ties keep the lower triangle id).
pub fn brute_force_closest_hit(triangles: &[Triangle], ray: &Ray) -> Hit {
    let mut best = Hit::miss();
    let mut t_max = ray.t_max;
    for (i, tri) in triangles.iter().enumerate() {
        let [v0, v1, v2] = tri.vertices();
        let probe = Ray { t_max, ..*ray };
        if let Some((t, u, v)) = intersect_triangle(&probe, v0, v1, v2) {
            t_max = t;
            best = Hit {
                t,
                tri: i as u32,
                u,
                v,
            };
        }
    }
    best
}
