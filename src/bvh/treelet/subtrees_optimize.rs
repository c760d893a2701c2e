//! Treelet round step 2 per subtree (kernel `subtrees_optimize`; Karras & Aila 2013, §4): the
//! treelets of the lowest levels, a workgroup for each subtree that holds them, depth by depth
//! between workgroup barriers (`RoundSchedule::subtree_levels`).

use super::rounds::RoundParams;
use crate::gpu::kernel;

kernel!(pub SUBTREES_OPTIMIZE: RoundParams = "subtrees_optimize"::"main", [32, 1, 1],
    [ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, Read, ReadWrite]);
