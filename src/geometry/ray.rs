//! Rays and the Möller–Trumbore ray/triangle test. The WGSL twin lives in
//! `shaders/include/ray_triangle.wgsl`; both use the same operation order so CPU brute force and
//! GPU traversal agree on hits.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// A ray as the GPU query kernel reads it (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Ray {
    pub origin: [f32; 3],
    pub t_min: f32,
    pub dir: [f32; 3],
    pub t_max: f32,
}
const _: () = assert!(std::mem::size_of::<Ray>() == 32);

/// A closest-hit result as the GPU query kernel writes it (16 bytes). `tri == Hit::MISS` on a miss.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub tri: u32,
    pub u: f32,
    pub v: f32,
}
const _: () = assert!(std::mem::size_of::<Hit>() == 16);

impl Hit {
    pub const MISS: u32 = u32::MAX;

    pub fn miss() -> Self {
        Self {
            t: f32::INFINITY,
            tri: Self::MISS,
            u: 0.0,
            v: 0.0,
        }
    }

    pub fn is_hit(&self) -> bool {
        self.tri != Self::MISS
    }
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Self {
        Self {
            origin: origin.to_array(),
            t_min,
            dir: dir.to_array(),
            t_max,
        }
    }
}

/// Möller–Trumbore. Returns (t, u, v) when the ray hits the triangle with t in (t_min, t_max).
/// Edges are inclusive (u >= 0, v >= 0, u + v <= 1).
pub fn intersect_triangle(ray: &Ray, v0: Vec3, v1: Vec3, v2: Vec3) -> Option<(f32, f32, f32)> {
    let o = Vec3::from(ray.origin);
    let d = Vec3::from(ray.dir);
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = d.cross(e2);
    let det = e1.dot(p);
    if det == 0.0 {
        return None;
    }
    let inv_det = 1.0 / det;
    let s = o - v0;
    let u = s.dot(p) * inv_det;
    let q = s.cross(e1);
    let v = d.dot(q) * inv_det;
    let t = e2.dot(q) * inv_det;
    let inside = u >= 0.0 && v >= 0.0 && u + v <= 1.0;
    (inside && t > ray.t_min && t < ray.t_max).then_some((t, u, v))
}
