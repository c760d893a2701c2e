//! Treelet round step 2 (kernel `treelets_optimize`; Karras & Aila 2013, §4): the treelets of one
//! level, one invocation each, or a workgroup each in a level of few treelets.

use super::rounds::RoundParams;
use crate::gpu::kernel;

kernel!(pub TREELETS_OPTIMIZE: RoundParams = "treelets_optimize"::"main", [32, 1, 1],
    [ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, Read, Read, ReadWrite]);
