//! Phased treelet rounds (`TreeletSettings::phases`; not the paper's order: README, "Phased
//! rounds"). The paper optimizes a round's treelets bottom-up, so a round waits on one treelet
//! per treelet level (20-37 levels on the shared scenes, the upper ones a few treelets each);
//! here each round takes P phases instead, phase k optimizing every root whose depth is ≡
//! P − 1 − k (mod P) in the tree the phases before left: a `roots_phase` dispatch finds them
//! (each root walks up to the tree's root) and buckets them with the phase's indirect arguments,
//! then a `treelets_optimize` dispatch optimizes them, one invocation each (a team of 32 each in a
//! phase of fewer than `RoundSchedule::team_below`). Roots of a phase lie at least P levels
//! apart, and a treelet's leaves at most P − 1 levels below its root (below the treelet size the
//! formation expands no leaf that deep: `treelet_dp.wgsl`), so the phase's treelets are
//! disjoint. CPU twin: `WorkingTree::optimize_phased`.

use std::sync::OnceLock;

use super::rounds::{Round, RoundParams, TreeletRounds, TreeletState, SCHEDULE_ARGS};
use crate::gpu::constants::MAX_LEVEL_DISPATCHES;
use crate::gpu::{
    flag_override, grow_storage_buffer, kernel, GpuContext, ItemCount, Kernel, Recorder,
};
use crate::Result;

kernel!(pub ROOTS_PHASE: RoundParams = "roots_phase"::"main", [256, 1, 1],
    [Read, Read, ReadWrite, Read, ReadWrite, ReadWrite]);

/// Phases per round at most: each phase counts its roots in a schedule word of its own.
pub const MAX_PHASES: u32 = 16;
/// Phases per round at least: a treelet's leaves lie at most P − 1 levels below its root, and a
/// treelet needs 3 leaves (2 levels).
pub const MIN_PHASES: u32 = 3;
const _: () = assert!(MAX_PHASES <= MAX_LEVEL_DISPATCHES);

/// The pipeline-overridable constant that makes `roots_phase` take its roots' slots per
/// workgroup (`override AGGREGATE_ROOTS` in roots_phase.wgsl): 1 for `RootSlots::Workgroup`.
pub const AGGREGATE_ROOTS_OVERRIDE: &str = "AGGREGATE_ROOTS";

/// How a phase's roots take their slots in its bucket (`roots_phase.wgsl`): the same roots, so the
/// same tree, either way.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum RootSlots {
    /// A workgroup counts its roots in workgroup memory and takes their slots with one device
    /// atomic, between two workgroup barriers (the default on GPUs, where the roots of a phase,
    /// thousands, would otherwise all add to one word).
    Workgroup,
    /// Each root takes its slot with a device atomic of its own, and the kernel has no barrier
    /// (the default on CPU devices, which run a kernel with barriers as a coroutine of its SIMD
    /// batches: lavapipe, conference's phased rounds, the 14 `roots_phase` dispatches 105-124 →
    /// 58-64 ms).
    Root,
}

impl RootSlots {
    /// How many ways there are (`slots as usize` counts them from 0).
    pub const WAYS: usize = 2;

    pub fn name(self) -> &'static str {
        match self {
            RootSlots::Workgroup => "workgroup",
            RootSlots::Root => "root",
        }
    }

    /// The default on a device of type `device`.
    pub fn default_for(device: wgpu::DeviceType) -> Self {
        match device {
            wgpu::DeviceType::Cpu => RootSlots::Root,
            _ => RootSlots::Workgroup,
        }
    }
}

/// The kernel that finds a phase's roots (the treelets are `TreeletRounds`' kernels) and the
/// depths its walks publish.
pub(crate) struct PhasedRounds {
    /// `roots_phase` per `RootSlots`, compiled when first used.
    roots_phase: [OnceLock<Kernel<RoundParams>>; RootSlots::WAYS],
    /// A word per leaf, stamped by the phase that published it (`roots_phase.wgsl`); grown on
    /// demand.
    depths: Option<wgpu::Buffer>,
}

impl PhasedRounds {
    pub fn new() -> Self {
        Self {
            roots_phase: Default::default(),
            depths: None,
        }
    }

    /// `roots_phase` taking its roots' slots `slots`.
    fn roots_phase(&self, ctx: &GpuContext, slots: RootSlots) -> &Kernel<RoundParams> {
        self.roots_phase[slots as usize].get_or_init(|| {
            let aggregate = flag_override(AGGREGATE_ROOTS_OVERRIDE, slots == RootSlots::Workgroup);
            Kernel::with_overrides(ctx, &ROOTS_PHASE, &[aggregate])
        })
    }

    /// Grows the published depths for trees of up to `n` leaves.
    pub fn reserve(&mut self, ctx: &GpuContext, n: u32) -> Result<()> {
        let size = 4 * u64::from(n.max(1));
        grow_storage_buffer(ctx, &mut self.depths, "treelet phase depths", size)
    }

    /// Records one round in `phases` phases, into the pass "treelets", over a working tree of
    /// `count` leaves whose counts and costs are set (the first round's schedule) and whose
    /// schedule is zero. Call `reserve` and `TreeletRounds::reserve` first, the latter with room
    /// for every internal node.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        count: ItemCount<'_>,
        state: &TreeletState<'_>,
        rounds: &TreeletRounds,
        round: &Round,
        phases: u32,
    ) {
        let ctx = rec.ctx;
        let n = count.capacity();
        let roots_phase = self.roots_phase(ctx, rounds.schedule.root_slots(ctx.info.device_type));
        let grid = roots_phase.grid(ctx, n);
        // The phases compute no next levels (`RoundParams::phase`).
        let optimize = rounds.optimize(ctx, round.treelet_size, u32::MAX);
        let team_below = rounds.schedule.team_below();
        let limit = count.limit(ctx);
        let roots = rounds.roots();
        let depths = self
            .depths
            .as_ref()
            .expect("reserve() allocates the depths");
        // No stamp of the round before: every phase's stamp reads as its own only.
        rec.encoder()
            .clear_buffer(depths, 0, Some(4 * u64::from(n)));
        let mut pass = rec.pass("treelets");
        for k in 0..phases {
            let params = RoundParams::phase(n, grid.row_pitch, round, (phases, k), team_below);
            pass.dispatch(
                roots_phase,
                grid,
                &params,
                &[
                    state.parents,
                    state.prim_counts,
                    state.schedule,
                    limit,
                    roots,
                    depths,
                ],
            );
            let args = 4 * (SCHEDULE_ARGS + 3 * u64::from(k));
            pass.dispatch_indirect(
                optimize,
                state.schedule,
                args,
                &params,
                &rounds.treelet_buffers(state),
            );
        }
    }
}
