//! Every compute kernel's declaration in one table, for the checks that cover them all
//! (`tests/shaders.rs`: each declaration against its WGSL with naga, and every shader file
//! declared).

use crate::gpu::KernelInfo;
use crate::{anim, bvh, sort, trace};

/// Each kernel's declaration (see `gpu::KernelDecl`).
pub const ALL: &[&KernelInfo] = &[
    &bvh::lbvh::TRIANGLES_BOUNDS.info,
    &bvh::lbvh::CENTROIDS_REDUCE.info,
    &bvh::lbvh::MORTON_COMPUTE.info,
    &bvh::lbvh::LBVH_CLIMB.info,
    &sort::KEYS_HISTOGRAM.info,
    &sort::KEYS_SCATTER.info,
    &sort::COUNTS_SCAN.info,
    &sort::COUNTS_ADD.info,
    &bvh::treelet::NODES_LEVEL.info,
    &bvh::treelet::TREELETS_OPTIMIZE.info,
    &bvh::treelet::ROOTS_PHASE.info,
    &bvh::treelet::SUBTREES_OPTIMIZE.info,
    &bvh::treelet::TREELETS_CLIMB.info,
    &bvh::treelet::WAVES_FIND.info,
    &bvh::treelet::WAVES_OPTIMIZE.info,
    &bvh::treelet::WAVES_CLIMB.info,
    &bvh::treelet::NODES_MARK.info,
    &bvh::treelet::NODES_COMPACT.info,
    &bvh::presplit::TRIANGLES_PRIORITY.info,
    &bvh::presplit::SPLITS_COUNT.info,
    &bvh::presplit::SPLITS_ASSIGN.info,
    &bvh::presplit::TRIANGLES_SPLIT.info,
    &bvh::presplit::REFERENCES_SPLIT.info,
    &bvh::NODES_REFIT.info,
    &bvh::WORDS_HASH.info,
    &trace::PATHS_TRACE.info,
    &trace::IMAGE_TONEMAP.info,
    &trace::RAYS_INTERSECT.info,
    &trace::RAYS_INTERSECT_WIDE.info,
    &trace::PATHS_TRACE_WIDE.info,
    &bvh::wide::NODES_LINK.info,
    &bvh::wide::COSTS_CLIMB.info,
    &bvh::wide::WIDE_NODES_EMIT.info,
    &bvh::wide::WIDE_NODES_FINISH.info,
    &bvh::wide::TRIANGLES_GATHER.info,
    &anim::CLOTH_ANIMATE.info,
    &anim::BODIES_ANIMATE.info,
    &anim::DEBRIS_ANIMATE.info,
];
