//! Scene data resident on the GPU, split by ownership: [`Geometry`] (triangles, materials, point
//! lights), read-only to builders and tracers alike, and [`Tree`] (nodes and primitive
//! references), owned by whoever built it and handed over by value. `bvh` writes trees from
//! geometry, `trace` reads both; neither depends on the other for its data.

mod geometry;
mod tree;
mod wide_tree;

pub use geometry::Geometry;
pub use tree::{RefitLinks, Tree};
pub use wide_tree::WideTree;
