//! Bounding volume hierarchies: the node layout, the SAH cost model, the validator and the CPU
//! reference builders (test oracles and quality anchors, never the per-frame path).

mod builder;
mod export;
pub mod lbvh;
mod node;
pub mod presplit;
mod sah;
mod sbvh;
mod sweep;
mod traverse;
pub mod treelet;
mod validate;

pub use builder::{BuildReport, Builder, GpuBuilder, DEFAULT_SPLIT_PERCENT};
pub use export::{read_bvh, write_bvh, BVH_MAGIC};
pub use node::{Bvh, BvhNode, LEAF_FLAG};
pub use sah::{sah_cost, SahParams};
pub use sbvh::build_sbvh;
pub use sweep::build_sweep_sah;
pub use traverse::BOX_EXIT_SLACK;
pub use validate::{validate, validate_with_references, ValidationError, ValidationStats};
