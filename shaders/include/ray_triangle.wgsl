// Möller–Trumbore ray/triangle test, the same operation order as geometry::intersect_triangle.
// Returns vec4(t, u, v, 1) on a hit with t in (t_min, t_max), vec4(0) otherwise.
fn intersect_triangle(origin: vec3<f32>, dir: vec3<f32>, t_min: f32, t_max: f32, tri: Triangle) -> vec4<f32> {
    let e1 = tri.v1 - tri.v0;
    let e2 = tri.v2 - tri.v0;
    let p = cross(dir, e2);
    let det = dot(e1, p);
    if det == 0.0 {
        return vec4<f32>(0.0);
    }
    let inv_det = 1.0 / det;
    let s = origin - tri.v0;
    let u = dot(s, p) * inv_det;
    let q = cross(s, e1);
    let v = dot(dir, q) * inv_det;
    let t = dot(e2, q) * inv_det;
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t > t_min && t < t_max {
        return vec4<f32>(t, u, v, 1.0);
    }
    return vec4<f32>(0.0);
}
