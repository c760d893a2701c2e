//! CPU brute-force closest hit over all triangles with the watertight test: the oracle for the
//! traversal tests.

use crate::geometry::{Hit, Ray, RayTriangleTest};
use crate::scene::Triangle;

/// The closest hit of `ray` among all `triangles` (ties keep the lower triangle id).
pub fn brute_force_closest_hit(triangles: &[Triangle], ray: &Ray) -> Hit {
    let test = RayTriangleTest::for_ray(ray);
    let mut best = Hit::miss();
    let mut t_max = ray.t_max;
    for (i, tri) in triangles.iter().enumerate() {
        let [v0, v1, v2] = tri.vertices();
        if let Some((t, u, v)) = test.intersect(v0, v1, v2, ray.t_min, t_max) {
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
