//! Geometric primitives shared by the CPU builders, the validator and the CPU reference tracer.

mod aabb;
mod polygon;
mod ray;
mod ray_triangle;

pub use aabb::{Aabb, GpuAabb};
pub use polygon::{HalfSpace, Polygon};
pub use ray::{Hit, Ray};
pub use ray_triangle::{intersect_triangle, RayTriangleTest};
