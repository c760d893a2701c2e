//! The treelet rounds overlapped in waves on the GPU (Karras & Aila 2013, §4: the rounds of
//! bottom-up restructuring, each run ahead of the one before where its treelets cannot meet a
//! treelet still to come of it): kernels `waves_find` and `waves_optimize` (a dispatch each per
//! wave, for the waves of many treelets) and `waves_climb` (one workgroup, the waves after them),
//! sharing `treelet_waves.wgsl`. The first round's schedule (`nodes_level`, which also builds the
//! LBVH) gives the first wave's candidates: the roots of treelet level 1. GPU twin of the CPU's
//! `WorkingTree::optimize_overlapped`, which tests compare it against exactly; selected by
//! `RoundSchedule::overlap`.

use std::sync::OnceLock;

use super::dp::CostModel;
use super::dp_unrolled::TreeletDp;
use super::rounds::{level_start, RoundParams, TreeletKernels, TreeletState, SCHEDULE_ARGS};
use crate::gpu::{
    indirect_buffer_zeroed, kernel, storage_buffer_zeroed, GpuContext, Grid, Kernel, Recorder,
};
use crate::Result;

kernel!(pub WAVES_FIND: RoundParams = "waves_find"::"main", [32, 1, 1],
    [Read, Read, Read, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite]);
kernel!(pub WAVES_OPTIMIZE: RoundParams = "waves_optimize"::"main", [32, 1, 1],
    [ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
     ReadWrite, Read]);
kernel!(pub WAVES_CLIMB: RoundParams = "waves_climb"::"main", [128, 1, 1],
    [ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
     Read]);

/// The smallest reach the overlapped rounds take for treelets of `treelet_size` leaves
/// (`RoundSchedule::overlap`; a smaller one is refused): a treelet reaches `treelet_size` − 1
/// levels below its root (its leaves), so a round starts on a root once it and its ancestors
/// that many levels up are done in the round before, and no treelet of that round still to come
/// can touch it. With less, two treelets of one wave could share nodes, which a GPU runs side by
/// side (a race; the CPU twin, one treelet after another, would hide it). With 7 leaves this is
/// 6, at which on every scene measured the trees are those of the rounds one after another
/// (README, "Rounds can overlap"), and the tests compare them.
pub fn overlap_reach(treelet_size: u32) -> u32 {
    treelet_size.saturating_sub(1)
}

/// Words of the wave state (`treelet_waves.wgsl`): counts, tickets, the stop flag.
const WAVE_STATE_WORDS: u64 = 6;

/// The waves' next γ: none, as the waves of all rounds compute no next levels
/// (`RoundParams::waves`).
const NO_NEXT_LEVELS: u32 = u32::MAX;

/// Where the wave state holds the count of odd waves' candidates (`CANDIDATE_COUNT + 1` in
/// `treelet_waves.wgsl`).
const ODD_CANDIDATES_WORD: u64 = 2;
/// The entries' node field (`ROUND_SHIFT` in `treelet_waves.wgsl`).
const MAX_NODES: u32 = 1 << 28;

struct WaveBuffers {
    /// Leaves and rounds the buffers have room for.
    capacity: u32,
    rounds: u32,
    done: wgpu::Buffer,
    candidate_waves: wgpu::Buffer,
    lists: wgpu::Buffer,
    state: wgpu::Buffer,
    /// The indirect arguments of the find and the optimize dispatches (each written by the
    /// other).
    find_args: wgpu::Buffer,
    optimize_args: wgpu::Buffer,
}

/// The overlapped rounds' kernels and scratch, reused per build.
pub(crate) struct OverlappedRounds {
    /// Compiled when first used: a build that never overlaps its rounds never needs it.
    find: OnceLock<Kernel<RoundParams>>,
    optimize: TreeletKernels,
    climb: TreeletKernels,
    buffers: Option<WaveBuffers>,
}

/// What one overlapped build of the rounds does.
pub(crate) struct Overlap {
    pub model: CostModel,
    pub treelet_size: u32,
    pub rounds: u32,
    pub reach: u32,
    /// Waves given a find and an optimize dispatch each; the climb takes the rest.
    pub dispatched: u32,
    pub dp: TreeletDp,
    pub climb_dp: TreeletDp,
    /// Dispatched waves of fewer treelets than this are optimized by teams, a workgroup per
    /// treelet.
    pub team_below: u32,
    /// Climbed waves of fewer treelets than this (and than 32) are optimized by teams.
    pub climb_team_below: u32,
}

impl OverlappedRounds {
    pub fn new() -> Self {
        Self {
            find: OnceLock::new(),
            optimize: TreeletKernels::new(&WAVES_OPTIMIZE),
            climb: TreeletKernels::new(&WAVES_CLIMB),
            buffers: None,
        }
    }

    /// Grows the scratch for trees of up to `n` leaves and `rounds` rounds.
    pub fn reserve(&mut self, ctx: &GpuContext, n: u32, rounds: u32) -> Result<()> {
        if n >= MAX_NODES {
            return Err(crate::Error::InvalidArgument(format!(
                "overlapped treelet rounds take fewer than {MAX_NODES} leaves, got {n}"
            )));
        }
        if self
            .buffers
            .as_ref()
            .is_some_and(|b| b.capacity >= n && b.rounds >= rounds)
        {
            return Ok(());
        }
        self.buffers = None;
        let per_round = u64::from(n) * u64::from(rounds) * 4;
        self.buffers = Some(WaveBuffers {
            capacity: n,
            rounds,
            done: storage_buffer_zeroed(ctx, "treelet waves done", per_round)?,
            candidate_waves: storage_buffer_zeroed(ctx, "treelet waves candidates", per_round)?,
            lists: storage_buffer_zeroed(
                ctx,
                "treelet waves lists",
                2 * per_round + u64::from(n) * 4,
            )?,
            state: storage_buffer_zeroed(ctx, "treelet waves state", WAVE_STATE_WORDS * 4)?,
            find_args: indirect_buffer_zeroed(ctx, "treelet waves find arguments", 12)?,
            optimize_args: indirect_buffer_zeroed(ctx, "treelet waves optimize arguments", 12)?,
        });
        Ok(())
    }

    /// Records the rounds over a working tree of `n` leaves (capacity) whose first schedule
    /// (`TreeletRounds::record_levels` of the first round, with its roots in `roots`) was
    /// recorded before; `subsets` is `subsets_by_size`, for the teams. Call `reserve` first.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        n: u32,
        state: &TreeletState<'_>,
        roots: &wgpu::Buffer,
        subsets: &wgpu::Buffer,
        overlap: &Overlap,
    ) {
        let ctx = rec.ctx;
        let b = self
            .buffers
            .as_ref()
            .expect("reserve() allocates the wave buffers");
        // Lists sized for the rounds this build has (params.rounds · n per wave parity).
        let rounds = overlap.rounds;
        let encoder = rec.encoder();
        encoder.clear_buffer(&b.done, 0, None);
        encoder.clear_buffer(&b.candidate_waves, 0, None);
        encoder.clear_buffer(&b.state, 0, None);
        // Wave 1 (odd): the first round's roots of level 1, their count and arguments.
        let level_one = level_start(n, overlap.treelet_size, 2) * 4;
        if level_one > 0 {
            let odd = u64::from(rounds) * u64::from(n) * 4;
            encoder.copy_buffer_to_buffer(roots, 0, &b.lists, odd, level_one);
        }
        encoder.copy_buffer_to_buffer(state.schedule, 0, &b.state, ODD_CANDIDATES_WORD * 4, 4);
        encoder.copy_buffer_to_buffer(state.schedule, SCHEDULE_ARGS * 4, &b.find_args, 0, 12);
        let params = |wave| RoundParams::waves(n, overlap, wave);
        let find_buffers = [
            state.nodes,
            state.parents,
            state.prim_counts,
            &b.done,
            &b.candidate_waves,
            &b.lists,
            &b.state,
            &b.optimize_args,
        ];
        let climb_buffers = [
            state.nodes,
            state.parents,
            state.prim_counts,
            state.costs,
            state.next_levels,
            &b.done,
            &b.candidate_waves,
            &b.lists,
            &b.state,
        ];
        let mut optimize_buffers = climb_buffers.to_vec();
        optimize_buffers.extend([&b.find_args, subsets]);
        let mut climb_buffers = climb_buffers.to_vec();
        climb_buffers.push(subsets);
        let find = self.find.get_or_init(|| Kernel::new(ctx, &WAVES_FIND));
        let optimize = self.optimize.get(
            ctx,
            overlap.treelet_size,
            overlap.dp,
            overlap.team_below,
            NO_NEXT_LEVELS,
        );
        let mut pass = rec.pass("treelets");
        for wave in 1..=overlap.dispatched {
            let params = params(wave);
            pass.dispatch_indirect(find, &b.find_args, 0, &params, &find_buffers);
            pass.dispatch_indirect(optimize, &b.optimize_args, 0, &params, &optimize_buffers);
        }
        drop(pass);
        let climb = self.climb.get(
            ctx,
            overlap.treelet_size,
            overlap.climb_dp,
            overlap.climb_team_below,
            NO_NEXT_LEVELS,
        );
        rec.pass("treelets climb").dispatch(
            climb,
            Grid::workgroups(1, 1),
            &params(overlap.dispatched + 1),
            &climb_buffers,
        );
    }
}
