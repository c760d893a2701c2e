//! Treelet round step 1 (kernel `nodes_level`; Karras & Aila 2013, §4): primitive counts, SAH
//! costs and treelet levels bottom-up, the roots bucketed by level and each dispatched level's
//! indirect arguments; in the first round also the LBVH's hierarchy and boxes (Karras 2012;
//! Apetrei 2014).

use super::rounds::RoundParams;
use crate::gpu::kernel;

kernel!(pub NODES_LEVEL: RoundParams = "nodes_level"::"main", [64, 1, 1],
    [ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, Read, Read, Read, ReadWrite, Read]);
