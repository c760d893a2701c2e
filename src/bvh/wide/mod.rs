//! Compressed wide BVHs after Ylitie, Karras & Laine, "Efficient Incoherent Ray Traversal on GPUs
//! Through Compressed Wide BVHs" (HPG 2017): the 8-wide, 80-byte node layout with quantized child
//! boxes (`node`), the conversion of any binary tree into it on the GPU (`WideConverter`, a build
//! stage) by a greedy collapse (CPU twin `WideBvh::from_binary`) or the paper's SAH-optimal one
//! (`OptimalCollapse`; CPU twin `WideBvh::from_binary_optimal`), and the validator. The
//! traversal is `shaders/include/wide_traverse.wgsl`; `Layout` says which layout a tracer uses,
//! `WideCollapse` how the conversion picks a wide node's children.

mod convert;
mod converter;
mod costs_climb;
mod node;
mod nodes_link;
mod optimal;
mod sah;
mod triangles_gather;
mod validate;
mod wide_nodes_emit;
mod wide_nodes_finish;

pub use convert::{check_leaf_sizes, max_wide_nodes, MAX_WIDE_LEAF_SIZE};
pub use converter::{WideConverter, FINISH_POOL, MAX_WIDE_LEVEL_DISPATCHES};
pub use costs_climb::{CostParams, COSTS_CLIMB};
pub use node::{Slot, WideBvh, WideNode, WIDTH};
pub use nodes_link::NODES_LINK;
pub use optimal::OptimalCollapse;
pub use sah::wide_sah_costs;
pub use triangles_gather::{gather_triangles, TRIANGLES_GATHER};
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

/// How the wide conversion picks the children of a wide node among the binary nodes below the
/// one it is made from.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum WideCollapse {
    /// Open the child of the largest surface area until 8 slots are taken: no pass of its own.
    /// The default: on an H200 the optimal trees traced no faster (README, "SAH-optimal
    /// collapse").
    #[default]
    Greedy = 0,
    /// Ylitie et al.'s SAH-optimal collapse: a dynamic program over the binary tree, bottom-up
    /// (kernels `nodes_link`, `costs_climb`), whose choices the conversion follows: a wide SAH
    /// 2-4.5 % lower and about a third fewer wide nodes on the shared scenes.
    Optimal = 1,
}

impl WideCollapse {
    pub const ALL: &[WideCollapse] = &[WideCollapse::Greedy, WideCollapse::Optimal];

    /// The value of the conversion kernels' override `WIDE_COLLAPSE` (`COLLAPSE_GREEDY`,
    /// `COLLAPSE_OPTIMAL` in wide_collapse.wgsl).
    pub fn override_value(self) -> f64 {
        f64::from(self as u8)
    }

    pub fn name(self) -> &'static str {
        match self {
            WideCollapse::Optimal => "optimal",
            WideCollapse::Greedy => "greedy",
        }
    }

    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .copied()
            .find(|c| c.name() == name)
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "unknown wide collapse '{name}' (known: greedy, optimal)"
                ))
            })
    }
}

/// How a build's wide conversion runs: its collapse, and how many levels below the root's
/// dispatch get an indirect dispatch of their own before the finish emits the subtrees below
/// (`WideConverter::set_options`; None: from the tree's size). Every count makes the same
/// tree (tested); `bench --wide-level-dispatches` times them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideOptions {
    pub collapse: WideCollapse,
    pub level_dispatches: Option<u32>,
}

impl WideOptions {
    /// The options of a conversion by `collapse` with the default level dispatches.
    pub fn collapse(collapse: WideCollapse) -> Self {
        Self {
            collapse,
            level_dispatches: None,
        }
    }
}
