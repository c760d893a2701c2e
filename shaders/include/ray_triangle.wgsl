// Watertight ray/triangle intersection (Woop, Benthin & Wald 2013, JCGT 2(1)), the twin of
// src/geometry/ray_triangle.rs operation for operation (see there for why no ray escapes through
// a closed mesh). Every product goes through `unfused` so that the compiler cannot fuse it into the
// following add or subtract: hit-or-miss decisions then use only correctly rounded multiplies and
// subtractions and equal the CPU's bit for bit; only the division for t may differ by a few ulps.
// Needs `Triangle` (bvh_node.wgsl) and the including kernel's `triangles`, bound as array<vec4<f32>>
// (`load_triangle`).
#include "unfused.wgsl"

// Triangle `index` of the including kernel's `triangles`, bound as array<vec4<f32>> (three
// 16-byte words per triangle): three loads, not one per field.
fn load_triangle(index: u32) -> Triangle {
    let w0 = triangles[3u * index];
    let w1 = triangles[3u * index + 1u];
    let w2 = triangles[3u * index + 2u];
    return Triangle(w0.xyz, bitcast<u32>(w0.w), w1.xyz, bitcast<u32>(w1.w), w2.xyz, bitcast<u32>(w2.w));
}

struct RayTriangleTest {
    origin: vec3<f32>,
    // Axis of the largest |direction| component (ties: x before y before z).
    kz: u32,
    // The direction permuted to (kx, ky, kz) and scaled by a power of two.
    shear: vec3<f32>,
    // The unscaled direction component along kz.
    dz: f32,
    // Always 0, read from a uniform by the kernel: the compiler cannot see through it.
    opaque_zero: u32,
}

// v reordered to (kx, ky, kz) with kx = kz + 1, ky = kz + 2 (mod 3).
fn permute(v: vec3<f32>, kz: u32) -> vec3<f32> {
    return select(select(v, v.zxy, kz == 1u), v.yzx, kz == 0u);
}

// 2^(127 - e) for the biased exponent e of `largest` (capped at 253): scales it into [1, 2).
fn power_of_two_scale(largest: f32) -> f32 {
    let biased = min((bitcast<u32>(largest) >> 23u) & 0xffu, 253u);
    return bitcast<f32>((254u - biased) << 23u);
}

fn ray_triangle_test(origin: vec3<f32>, dir: vec3<f32>, opaque_zero: u32) -> RayTriangleTest {
    let a = abs(dir);
    var kz = 2u;
    if a.x >= a.y && a.x >= a.z {
        kz = 0u;
    } else if a.y >= a.z {
        kz = 1u;
    }
    let d = permute(dir, kz);
    let scale = power_of_two_scale(max(max(a.x, a.y), a.z));
    return RayTriangleTest(origin, kz, d * scale, d.z, opaque_zero);
}

// A permuted point's 2D coordinates in the plane orthogonal to the ray, times the scaled dz.
fn sheared(test: RayTriangleTest, p: vec3<f32>) -> vec2<f32> {
    let s = test.shear;
    let z = test.opaque_zero;
    return vec2<f32>(
        unfused(s.z * p.x, z) - unfused(s.x * p.z, z),
        unfused(s.z * p.y, z) - unfused(s.y * p.z, z),
    );
}

// p.x * q.y - p.y * q.x: exactly negated when p and q swap.
fn edge_function(p: vec2<f32>, q: vec2<f32>, zero: u32) -> f32 {
    return unfused(p.x * q.y, zero) - unfused(p.y * q.x, zero);
}

// vec4(t, u, v, 1) when the ray hits with t_min < t < t_max (u, v: barycentric weights of v1
// and v2; edges and vertices inclusive, both windings), vec4(0) otherwise.
fn intersect_triangle(test: RayTriangleTest, tri: Triangle, t_min: f32, t_max: f32) -> vec4<f32> {
    let z = test.opaque_zero;
    let a = permute(tri.v0 - test.origin, test.kz);
    let b = permute(tri.v1 - test.origin, test.kz);
    let c = permute(tri.v2 - test.origin, test.kz);
    let a2 = sheared(test, a);
    let b2 = sheared(test, b);
    let c2 = sheared(test, c);
    let u = edge_function(c2, b2, z);
    let v = edge_function(a2, c2, z);
    let w = edge_function(b2, a2, z);
    let inside = (u >= 0.0 && v >= 0.0 && w >= 0.0) || (u <= 0.0 && v <= 0.0 && w <= 0.0);
    let det = u + v + w;
    if !inside || det == 0.0 {
        return vec4<f32>(0.0);
    }
    let scaled_t = unfused(u * a.z, z) + unfused(v * b.z, z) + unfused(w * c.z, z);
    let t = scaled_t / (det * test.dz);
    if t > t_min && t < t_max {
        return vec4<f32>(t, v / det, w / det, 1.0);
    }
    return vec4<f32>(0.0);
}
