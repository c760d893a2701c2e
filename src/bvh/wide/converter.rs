//! The GPU binary-to-wide conversion, a build stage (pass "wide"). With the SAH-optimal collapse
//! (`WideCollapse::Optimal`) two dispatches first compute its dynamic program bottom-up:
//! `nodes_link` (parent links) and `costs_climb` (costs and choices per binary node). Then the
//! wide nodes are emitted top-down, one per invocation (`shaders/include/wide_collapse.wgsl`; CPU
//! twins `WideBvh::from_binary` for the greedy collapse, `WideBvh::from_binary_optimal`). The root
//! and the `START_LEVELS` levels below it (at most 8 and 64 wide nodes) are one direct dispatch
//! of one workgroup; each of the next levels up to `level_dispatches` is an indirect dispatch
//! whose size the previous level wrote (`wide_nodes_emit`); whatever lies deeper is emitted by
//! one more indirect dispatch, a subtree per wide node of the next level, depth-first
//! (`wide_nodes_finish`). Last, `triangles_gather` turns the references (positions in the binary
//! tree's `prim_indices`) into triangle indices and copies their triangles in order for the
//! traversal. No CPU round trip.

use std::sync::OnceLock;

use super::convert::max_wide_nodes;
use super::costs_climb::{CostParams, COSTS_CLIMB};
use super::nodes_link::NODES_LINK;
use super::triangles_gather::TRIANGLES_GATHER;
use super::wide_nodes_emit::{WideParams, WIDE_COLLAPSE_OVERRIDE, WIDE_NODES_EMIT};
use super::wide_nodes_finish::WIDE_NODES_FINISH;
use super::{WideCollapse, WideOptions};
use crate::bvh::{BvhNode, SahParams};
use crate::device::{Geometry, Tree, WideTree};
use crate::gpu::{GpuContext, ItemCount, Items};
use crate::gpu::{Grid, Kernel, Recorder};
use crate::{Error, Result};

/// Level dispatches a conversion records at most.
pub const MAX_WIDE_LEVEL_DISPATCHES: u32 = 32;
/// Levels below the root that the root's dispatch emits too, where `level_dispatches` allows
/// (WGSL twin in wide_nodes_emit.wgsl).
const START_LEVELS: u32 = 2;
/// Words per level record (`RECORD_WORDS` in wide_collapse.wgsl).
const RECORD_WORDS: u32 = 8;
/// Subtree roots a workgroup of the finish holds in its pool by default, and at most (the
/// WGSL `override POOL` of wide_nodes_finish.wgsl).
pub const FINISH_POOL: u32 = 1024;

pub struct WideConverter {
    link: Kernel<Items>,
    costs: Kernel<CostParams>,
    /// `wide_nodes_emit` and `wide_nodes_finish` per collapse (`collapse as usize`), compiled
    /// when first used: the collapse is a pipeline constant.
    emit: [OnceLock<Kernel<WideParams>>; 2],
    finish: [OnceLock<Kernel<WideParams>>; 2],
    /// The finish's pool of subtree roots (`set_finish_pool`; `None`: FINISH_POOL).
    finish_pool: Option<u32>,
    gather: Kernel<Items>,
    /// The collapse and the forced level dispatches of the next conversions.
    options: WideOptions,
    /// Ci and Ct of the optimal collapse's costs.
    sah: SahParams,
}

impl WideConverter {
    /// A converter with the default (greedy) collapse; the optimal one costs under `sah`'s Ci
    /// and Ct.
    pub fn new(ctx: &GpuContext, sah: &SahParams) -> Self {
        Self {
            link: Kernel::new(ctx, &NODES_LINK),
            costs: Kernel::climb(ctx, &COSTS_CLIMB),
            emit: Default::default(),
            finish: Default::default(),
            finish_pool: None,
            gather: Kernel::new(ctx, &TRIANGLES_GATHER),
            options: WideOptions::default(),
            sah: *sah,
        }
    }

    /// The collapse and level dispatches of the next conversions (`set_collapse`,
    /// `set_level_dispatches`).
    pub fn set_options(&mut self, options: WideOptions) {
        self.set_collapse(options.collapse);
        self.set_level_dispatches(options.level_dispatches);
    }

    /// The collapse of the next conversions.
    pub fn set_collapse(&mut self, collapse: WideCollapse) {
        self.options.collapse = collapse;
    }

    pub fn collapse(&self) -> WideCollapse {
        self.options.collapse
    }

    /// Level dispatches for a tree of up to `prims` references: about every level a deep tree
    /// has, log2 of the references plus 2 (a level past the tree's depth launches no
    /// workgroups; the finish takes whatever lies deeper). With the tail in one workgroup, as it
    /// was, fewer cost much more on an H200 (conference, 14 wide levels: 0.86 ms at 14, 5.1 at
    /// 10); the finish now spreads the tail over a workgroup per 64 of its roots, and the best
    /// count on a GPU is not yet measured (`bench --wide-level-dispatches`; the tuner tries
    /// counts down to 12 below this).
    pub fn level_dispatches(prims: u32) -> u32 {
        (prims.max(1).ilog2() + 2).min(MAX_WIDE_LEVEL_DISPATCHES)
    }

    /// Gives the finish's workgroups a pool of `roots` subtree roots (1..=`FINISH_POOL`; tests:
    /// a pool that fills gives the same tree); `None` restores the default.
    pub fn set_finish_pool(&mut self, roots: Option<u32>) -> Result<()> {
        if let Some(roots) = roots.filter(|roots| !(1..=FINISH_POOL).contains(roots)) {
            return Err(Error::InvalidArgument(format!(
                "a pool of {roots} subtree roots (1 to {FINISH_POOL})"
            )));
        }
        self.finish_pool = roots;
        self.finish = Default::default();
        Ok(())
    }

    /// The emit and finish kernels of the current collapse (and finish pool).
    fn level_kernels(&self, ctx: &GpuContext) -> (&Kernel<WideParams>, &Kernel<WideParams>) {
        let collapse = self.options.collapse;
        let overrides = [(WIDE_COLLAPSE_OVERRIDE, collapse.override_value())];
        let emit = self.emit[collapse as usize]
            .get_or_init(|| Kernel::with_overrides(ctx, &WIDE_NODES_EMIT, &overrides));
        let finish = self.finish[collapse as usize].get_or_init(|| {
            let mut overrides = overrides.to_vec();
            if let Some(roots) = self.finish_pool {
                overrides.push(("POOL", f64::from(roots)));
            }
            Kernel::with_overrides(ctx, &WIDE_NODES_FINISH, &overrides)
        });
        (emit, finish)
    }

    /// Fixes the number of level dispatches (tests: every schedule gives the same tree); `None`
    /// restores the default.
    pub fn set_level_dispatches(&mut self, dispatches: Option<u32>) {
        self.options.level_dispatches = dispatches.map(|d| d.min(MAX_WIDE_LEVEL_DISPATCHES));
    }

    /// Records the conversion of `tree`'s binary tree over `geometry` into `tree.wide` (created
    /// or grown to the capacity of the binary buffers).
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        tree: &mut Tree,
    ) -> Result<()> {
        let ctx = rec.ctx;
        let binary_nodes = (tree.nodes.size() / std::mem::size_of::<BvhNode>() as u64) as u32;
        let prims = (tree.prim_indices.size() / 4) as u32;
        // The tree in a buffer of n binary nodes has at most (n + 1) / 2 leaves.
        let capacity = max_wide_nodes(binary_nodes.div_ceil(2), self.options.collapse);
        // The optimal collapse's scratch, per binary node (one word where the greedy one binds it).
        let scratch_nodes = match self.options.collapse {
            WideCollapse::Optimal => binary_nodes,
            WideCollapse::Greedy => 1,
        };
        let level_dispatches = self
            .options
            .level_dispatches
            .unwrap_or_else(|| Self::level_dispatches(prims));
        let record_bytes = u64::from(RECORD_WORDS * (MAX_WIDE_LEVEL_DISPATCHES + 2)) * 4;
        let fits = tree.wide.as_ref().is_some_and(|w| {
            w.capacity >= capacity
                && w.prim_indices.size() >= u64::from(prims) * 4
                && w.collapse.capacity >= scratch_nodes
        });
        if !fits {
            tree.wide = Some(WideTree::new(
                ctx,
                capacity,
                prims,
                scratch_nodes,
                record_bytes,
            )?);
        }
        let wide = tree.wide.as_ref().expect("created above");
        rec.encoder().clear_buffer(&wide.counters, 0, None);
        for records in &wide.records {
            rec.encoder().clear_buffer(records, 0, None);
        }
        let scratch = &wide.collapse;
        let mut pass = rec.pass("wide");
        if self.options.collapse == WideCollapse::Optimal {
            let nodes = ItemCount::OnGpu {
                buffer: &tree.counts,
                capacity: binary_nodes,
            };
            pass.dispatch_counted(
                &self.link,
                nodes,
                &[&tree.nodes, &scratch.parents, &scratch.arrivals],
            );
            let grid = self.costs.grid(ctx, binary_nodes);
            pass.dispatch(
                &self.costs,
                grid,
                &CostParams {
                    count: binary_nodes,
                    row_pitch: grid.row_pitch,
                    ci: self.sah.ci,
                    ct: self.sah.ct,
                    zero: 0,
                    _pad: [0; 3],
                },
                &[
                    &tree.nodes,
                    &scratch.parents,
                    &scratch.arrivals,
                    &scratch.costs,
                    &scratch.choices,
                    &tree.counts,
                ],
            );
        }
        // Level L reads its record from records[L % 2] and writes the next into the other.
        let buffers = |level: u32| -> [&wgpu::Buffer; 8] {
            [
                &tree.nodes,
                &wide.nodes,
                &wide.prim_indices,
                &wide.sources,
                &wide.counters,
                &wide.records[(level % 2) as usize],
                &wide.records[((level + 1) % 2) as usize],
                &scratch.choices,
            ]
        };
        let params = |level| WideParams {
            level,
            level_dispatches,
            capacity: wide.capacity,
            zero: 0,
        };
        let (emit, finish) = self.level_kernels(ctx);
        // The root's dispatch writes the record of the level after its last one.
        let top = START_LEVELS.min(level_dispatches);
        pass.dispatch(emit, Grid::workgroups(1, 1), &params(0), &buffers(top));
        for level in top + 1..=level_dispatches {
            let offset = u64::from(RECORD_WORDS * level) * 4;
            pass.dispatch_indirect(
                emit,
                &wide.records[(level % 2) as usize],
                offset,
                &params(level),
                &buffers(level),
            );
        }
        let last = level_dispatches + 1;
        pass.dispatch_indirect(
            finish,
            &wide.records[(last % 2) as usize],
            u64::from(RECORD_WORDS * last) * 4,
            &params(last),
            &buffers(last),
        );
        pass.dispatch_items(
            &self.gather,
            prims,
            &[
                &geometry.triangles,
                &tree.prim_indices,
                &wide.prim_indices,
                &wide.counters,
                &wide.triangles,
            ],
        );
        Ok(())
    }
}
