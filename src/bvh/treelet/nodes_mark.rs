//! Leaf collapse step 1 (kernel `nodes_mark`; Karras & Aila 2013, §3): which nodes of the
//! optimized working tree survive, and which become output leaves.

use bytemuck::{Pod, Zeroable};

use crate::gpu::kernel;

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct MarkParams {
    pub leaf_count: u32,
    pub row_pitch: u32,
    pub max_leaf_size: u32,
    pub ct: f32,
    /// Always 0: keeps the kernel's area products unfused (see unfused.wgsl).
    pub zero: u32,
    pub _pad: [u32; 3],
}
const _: () = assert!(std::mem::size_of::<MarkParams>() == 32);

/// The pipeline-overridable constant that tells `nodes_mark` whether the primitives are
/// pre-split references (`override HAS_REFS` in nodes_mark.wgsl): 1 or 0, a pipeline each.
pub const HAS_REFS_OVERRIDE: &str = "HAS_REFS";

kernel!(pub NODES_MARK: MarkParams = "nodes_mark"::"main", [64, 1, 1],
    [Read, Read, Read, Read, ReadWrite, ReadWrite, Read, Read, Read, ReadWrite]);
