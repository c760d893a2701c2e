//! Compressed wide BVHs after Ylitie, Karras & Laine, "Efficient Incoherent Ray Traversal on GPUs
//! Through Compressed Wide BVHs" (HPG 2017): the 8-wide, 80-byte node layout with quantized child
//! boxes (`node`), the conversion of any binary tree into it on the GPU (`WideConverter`, a build
//! stage) with its CPU twin (`WideBvh::from_binary`), the SAH-optimal collapse as a CPU reference
//! (`OptimalCollapse`, `WideBvh::from_binary_optimal`), and the validator. The traversal is
//! `shaders/include/wide_traverse.wgsl`; `Layout` says which layout a tracer uses.

mod convert;
mod converter;
mod node;
mod optimal;
mod sah;
mod validate;
mod wide_nodes_emit;
mod wide_nodes_finish;

pub use convert::{check_leaf_sizes, max_wide_nodes, MAX_WIDE_LEAF_SIZE};
pub use converter::{WideConverter, MAX_WIDE_LEVEL_DISPATCHES};
pub use node::{Slot, WideBvh, WideNode, WIDTH};
pub use optimal::OptimalCollapse;
pub use sah::wide_sah_costs;
pub use validate::{validate_wide, validate_wide_with_references};
pub use wide_nodes_emit::{WideParams, WIDE_NODES_EMIT};
pub use wide_nodes_finish::WIDE_NODES_FINISH;

use crate::{Error, Result};

/// The node layout a tree is traced in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Layout {
    /// The builders' binary tree (`BvhNode`, 32 bytes per node).
    #[default]
    Binary,
    /// The compressed 8-wide tree converted from it (`WideNode`, 80 bytes per node).
    Wide,
}

impl Layout {
    pub const ALL: &[Layout] = &[Layout::Binary, Layout::Wide];

    pub fn name(self) -> &'static str {
        match self {
            Layout::Binary => "binary",
            Layout::Wide => "wide",
        }
    }

    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .copied()
            .find(|l| l.name() == name)
            .ok_or_else(|| {
                Error::InvalidArgument(format!("unknown layout '{name}' (known: binary, wide)"))
            })
    }
}
