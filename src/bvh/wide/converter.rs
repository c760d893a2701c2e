//! The GPU binary-to-wide conversion, a build stage (pass "wide"): top-down, one wide node per
//! invocation (`shaders/include/wide_collapse.wgsl`, CPU twin `WideBvh::from_binary`). The root
//! and the `START_LEVELS` levels below it (at most 8 and 64 wide nodes) are one direct dispatch
//! of one workgroup; each of the next levels up to `level_dispatches` is an indirect dispatch
//! whose size the previous level wrote (`wide_nodes_emit`); whatever lies deeper is emitted by
//! one workgroup, level after level (`wide_nodes_finish`). No CPU round trip.

use super::convert::max_wide_nodes;
use super::wide_nodes_emit::{WideParams, WIDE_NODES_EMIT};
use super::wide_nodes_finish::WIDE_NODES_FINISH;
use crate::bvh::BvhNode;
use crate::device::{Tree, WideTree};
use crate::gpu::GpuContext;
use crate::gpu::{Grid, Kernel, Recorder};
use crate::Result;

/// Level dispatches a conversion records at most.
pub const MAX_WIDE_LEVEL_DISPATCHES: u32 = 32;
/// Levels below the root that the root's dispatch emits too, where `level_dispatches` allows
/// (WGSL twin in wide_nodes_emit.wgsl).
const START_LEVELS: u32 = 2;
/// Words per level record (`RECORD_WORDS` in wide_collapse.wgsl).
const RECORD_WORDS: u32 = 8;

pub struct WideConverter {
    emit: Kernel<WideParams>,
    finish: Kernel<WideParams>,
    forced_level_dispatches: Option<u32>,
}

impl WideConverter {
    pub fn new(ctx: &GpuContext) -> Self {
        Self {
            emit: Kernel::new(ctx, &WIDE_NODES_EMIT),
            finish: Kernel::new(ctx, &WIDE_NODES_FINISH),
            forced_level_dispatches: None,
        }
    }

    /// Level dispatches for a tree of up to `prims` references on a device of this type: on a
    /// GPU about every level a deep tree has, log2 of the references plus 2 (the tail's one
    /// workgroup runs on one multiprocessor: with log8 + 4 levels dispatched, conference's wide
    /// stage took 4.7-5.3 ms on an H200 against 0.5-0.8 ms for the other shared scenes, whose
    /// trees are shallower; an empty level costs only its launch); on a CPU device, where that
    /// workgroup is one thread, log8 + 8 (lavapipe, trbvh trees, the stage in three alternating
    /// runs against log8 + 4: conference 47-48 -> 36-39 ms, crytek_sponza 30-33 -> 28-29 ms,
    /// lost_empire unchanged).
    pub fn level_dispatches(prims: u32, device: wgpu::DeviceType) -> u32 {
        let prims = prims.max(1);
        let levels = match device {
            wgpu::DeviceType::Cpu => prims.ilog2() / 3 + 8,
            _ => prims.ilog2() + 2,
        };
        levels.min(MAX_WIDE_LEVEL_DISPATCHES)
    }

    /// Fixes the number of level dispatches (tests: every schedule gives the same tree); `None`
    /// restores the default.
    pub fn set_level_dispatches(&mut self, dispatches: Option<u32>) {
        self.forced_level_dispatches = dispatches.map(|d| d.min(MAX_WIDE_LEVEL_DISPATCHES));
    }

    /// Records the conversion of `tree`'s binary tree into `tree.wide` (created or grown to the
    /// capacity of the binary buffers).
    pub fn record(&self, rec: &mut Recorder<'_>, tree: &mut Tree) -> Result<()> {
        let ctx = rec.ctx;
        let binary_nodes = (tree.nodes.size() / std::mem::size_of::<BvhNode>() as u64) as u32;
        let prims = (tree.prim_indices.size() / 4) as u32;
        // The tree in a buffer of n binary nodes has at most (n + 1) / 2 leaves.
        let capacity = max_wide_nodes(binary_nodes.div_ceil(2));
        let level_dispatches = self
            .forced_level_dispatches
            .unwrap_or_else(|| Self::level_dispatches(prims, ctx.info.device_type));
        let record_bytes = u64::from(RECORD_WORDS * (MAX_WIDE_LEVEL_DISPATCHES + 2)) * 4;
        let fits = tree.wide.as_ref().is_some_and(|w| {
            w.capacity >= capacity && w.prim_indices.size() >= u64::from(prims) * 4
        });
        if !fits {
            tree.wide = Some(WideTree::new(ctx, capacity, prims, record_bytes)?);
        }
        let wide = tree.wide.as_ref().expect("created above");
        rec.encoder().clear_buffer(&wide.counters, 0, None);
        for records in &wide.records {
            rec.encoder().clear_buffer(records, 0, None);
        }
        // Level L reads its record from records[L % 2] and writes the next into the other.
        let buffers = |level: u32| -> [&wgpu::Buffer; 8] {
            [
                &tree.nodes,
                &tree.prim_indices,
                &wide.nodes,
                &wide.prim_indices,
                &wide.sources,
                &wide.counters,
                &wide.records[(level % 2) as usize],
                &wide.records[((level + 1) % 2) as usize],
            ]
        };
        let params = |level| WideParams {
            level,
            level_dispatches,
            capacity: wide.capacity,
            zero: 0,
        };
        let mut pass = rec.pass("wide");
        // The root's dispatch writes the record of the level after its last one.
        let top = START_LEVELS.min(level_dispatches);
        pass.dispatch(
            &self.emit,
            Grid::workgroups(1, 1),
            &params(0),
            &buffers(top),
        );
        for level in top + 1..=level_dispatches {
            let offset = u64::from(RECORD_WORDS * level) * 4;
            pass.dispatch_indirect(
                &self.emit,
                &wide.records[(level % 2) as usize],
                offset,
                &params(level),
                &buffers(level),
            );
        }
        let last = level_dispatches + 1;
        pass.dispatch(
            &self.finish,
            Grid::workgroups(1, 1),
            &params(last),
            &buffers(last),
        );
        Ok(())
    }
}
