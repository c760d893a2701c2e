//! Bounding volume hierarchies: the node layout, the SAH cost model, the validator and the CPU
//! reference builders (test oracles and quality anchors, never the per-frame path).

mod builder;
pub mod lbvh;
mod node;
mod sah;
mod sweep;
mod validate;

pub use builder::Builder;
pub use node::{Bvh, BvhNode, LEAF_FLAG};
pub use sah::{sah_cost, SahParams};
pub use sweep::build_sweep_sah;
pub use validate::{validate, ValidationError, ValidationStats};
