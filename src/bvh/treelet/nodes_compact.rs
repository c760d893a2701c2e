//! Leaf collapse step 2 (kernel `nodes_compact`; Karras & Aila 2013, §3): the kept nodes written
//! in the traversal layout at their scanned indices, each working leaf's primitive (or triangle)
//! at its slot in its output leaf's scanned range.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct CompactParams {
    pub leaf_count: u32,
    pub row_pitch: u32,
    /// 1 when the primitives are pre-split references mapped through `ref_tris`.
    pub has_refs: u32,
    pub _pad: u32,
}

kernel!(pub NODES_COMPACT: CompactParams = "nodes_compact"::"main", [64, 1, 1],
    [Read, Read, Read, Read, Read, ReadWrite, ReadWrite, ReadWrite, Read, Read, Read, Read]);
