//! Rays and hits as the GPU query kernel reads and writes them (WGSL twins `Ray` and `Hit` in
//! `shaders/include/bvh_node.wgsl`).

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// A ray as the GPU query kernel reads it (32 bytes). Hits are searched in [t_min, t_max], with
/// 0 <= t_min <= t_max (as in DXR and OptiX): the traversals order and cull boxes by entry
/// distances they take to be non-negative; the ray queries reject other intervals.
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
    pub const MISS: u32 = crate::gpu::constants::MISS;

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

    /// Whether 0 <= t_min <= t_max (false for NaN bounds).
    pub fn has_valid_interval(&self) -> bool {
        self.t_min >= 0.0 && self.t_min <= self.t_max
    }
}
