//! treelet: per-frame GPU BVH construction after Karras & Aila, "Fast Parallel Construction of
//! High-Quality Bounding Volume Hierarchies" (HPG 2013), and a wgpu compute path tracer.
//!
//! Layout: `geometry` (boxes, rays, triangle tests), `scene` (OBJ, procedural scenes, registry),
//! `bvh` (node layout, CPU reference builders, SAH, validation), `gpu` (device, timing, shaders),
//! `trace` (camera, GPU path tracer and closest-hit queries), `tradeoff` (build time against ray
//! throughput: the frame-time model, measurements and charts), `anim` (animated scenes: per-frame
//! GPU animation, rebuilds and refits).

pub mod anim;
#[cfg(feature = "app")]
pub mod app;
pub mod bvh;
pub mod device;
pub mod error;
pub mod geometry;
pub mod gpu;
pub mod kernels;

pub mod scene;
pub mod sort;
pub mod trace;
pub mod tradeoff;

pub use error::{Error, Result};
