//! Geometric primitives shared by the CPU builders, the validator and the CPU reference tracer.

mod aabb;
mod ray;

pub use aabb::Aabb;
pub use ray::{intersect_triangle, Hit, Ray};
