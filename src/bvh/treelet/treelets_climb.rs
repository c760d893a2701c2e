//! Treelet round step 3 (kernel `treelets_climb`; Karras & Aila 2013, §4): the levels above the
//! dispatched ones, climbed by one workgroup.

use super::rounds::RoundParams;
use crate::gpu::kernel;

kernel!(pub TREELETS_CLIMB: RoundParams = "treelets_climb"::"main", [128, 1, 1],
    [ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, Read, Read, ReadWrite, Read, ReadWrite, ReadWrite]);
