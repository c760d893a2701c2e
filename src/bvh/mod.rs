//! Bounding volume hierarchies: the node layout, the SAH cost model, the validator and the CPU
//! reference builders (test oracles and quality anchors, never the per-frame path).

mod builder;
mod export;
mod fingerprint;
pub mod lbvh;
mod node;
mod nodes_refit;
pub mod presplit;
mod sah;
mod sbvh;
mod sweep;
mod topdown;
mod traverse;
pub mod treelet;
mod tuning;
mod update;
mod validate;
pub mod wide;

pub use builder::{BuildReport, Builder, DEFAULT_SPLIT_PERCENT};
pub use export::{read_bvh, read_wide_bvh, write_bvh, write_wide_bvh, BVH_MAGIC, WIDE_BVH_MAGIC};
pub use fingerprint::{words_hash_cpu, TreeFingerprint, WordsHash, WordsHasher, WORDS_HASH};
pub use node::{Bvh, BvhNode, LEAF_FLAG};
pub use nodes_refit::{derive_refit_links, parents_and_leaves, NodesRefit, NODES_REFIT};
pub use sah::{sah_cost, SahParams};
pub use sbvh::build_sbvh;
pub use sweep::build_sweep_sah;
pub use traverse::TraversalSteps;
pub use tuning::{
    tune_schedule, tune_updater, tunes_by_default, BuildSchedule, DeviceTrials, SchedulePins,
    ScheduleTrial, ScheduleTrials, TunedSchedule, TuningOptions, TuningSpace,
};
pub use update::{TreeUpdater, UpdateMode};
pub use validate::{validate, validate_with_references, ValidationError, ValidationStats};
