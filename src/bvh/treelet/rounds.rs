//! GPU treelet restructuring rounds (Karras & Aila 2013, §3-4), processed level by level. A round
//! schedules the tree (kernel `nodes_level`: in the first round a bottom-up climb that builds the
//! LBVH from the sorted keys, its hierarchy and boxes, and gives every node its count, cost and
//! treelet level; in later rounds one pass over the roots, whose levels the round before
//! computed) and buckets the roots by level as it finds them, optimizes each of the lowest levels
//! in one indirect dispatch (`treelets_optimize`), and climbs the remaining top levels in one
//! workgroup (`treelets_climb`). The treelet kernels also compute the next round's levels of the
//! nodes they finish. Roots of one level are disjoint subtrees, and every level is processed
//! after the levels below it, so the result is the one of the paper's bottom-up traversal: the
//! CPU twin `WorkingTree::optimize_round` processes the nodes in post-order. Dispatch boundaries
//! order memory, so the treelet kernels read and write node data with plain loads and stores, not
//! atomics.
//!
//! Who optimizes a treelet: by default its own invocation, which runs the whole DP alone
//! (throughput). On request (`RoundSchedule::team_below`) a dispatched level of fewer treelets
//! gives each a team of 32 invocations that runs the DP's subsets of one size side by side, as the
//! paper does with a warp (for latency: the levels near the top of a tree hold a few treelets each,
//! and a tree has 20-40 levels per round, each waiting for the one before), and so does the climb
//! for its small waves (`RoundSchedule::climb_team_below`); measured with one threshold for both,
//! teams paid neither on lavapipe nor on an H200. Both find the same topology (same operations,
//! same tie-breaking). The treelet size is a pipeline constant: the treelet kernels are compiled
//! per size when first used, the lone DP written out for it (`dp_unrolled`), or as loops on request
//! (`RoundSchedule::dp` for the dispatched levels, `RoundSchedule::climb_dp` for the climb, for
//! GPUs to compare; the same tree). On request the rounds run overlapped in waves instead
//! (`RoundSchedule::overlap`, module `waves`), after the first round's schedule here. On request
//! the lowest K levels of a round take one dispatch (`RoundSchedule::subtree_levels`, kernel
//! `subtrees_optimize`): the schedule buckets only the roots of the disjoint subtrees that hold
//! them (of level K at most, their parent above), each in its level's bucket, and each workgroup
//! optimizes a few of these subtrees depth by depth between workgroup barriers, where a dispatch
//! per level pays its launch and the wait for its slowest treelet (a floor of ~24 µs a level on an
//! H200; README, "Where a small treelet level's time goes"); the levels above as before.

use std::sync::OnceLock;

use bytemuck::{Pod, Zeroable};

use super::dp::{subsets_by_size, CostModel};
use super::dp_unrolled::{TreeletDp, TREELET_DP_LOOP_OVERRIDE, TREELET_SIZE_OVERRIDE};
use super::nodes_level::NODES_LEVEL;
use super::phases::RootSlots;
use super::subtrees_optimize::SUBTREES_OPTIMIZE;
use super::treelets_climb::TREELETS_CLIMB;
use super::treelets_optimize::TREELETS_OPTIMIZE;
use super::waves::{overlap_reach, Overlap};
use crate::gpu::constants::{
    MAX_LEVEL_DISPATCHES, MAX_SUBTREE_LEVELS, MAX_TREELET_SIZE, MIN_TREELET_SIZE, SUBTREE_LIST,
};
use crate::gpu::{
    flag_override, grow_storage_buffer, storage_buffer, GpuContext, Grid, ItemCount, Kernel,
    KernelDecl, Pass, Recorder,
};
use crate::{Error, Result};

/// Parameters of every kernel of a round (WGSL twin in `shaders/include/treelet_round.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct RoundParams {
    count: u32,
    row_pitch: u32,
    gamma: u32,
    max_leaf_size: u32,
    ci: f32,
    ct: f32,
    /// Always 0: keeps the kernels' area products unfused (see unfused.wgsl).
    zero: u32,
    level_dispatches: u32,
    level: u32,
    levels_only: u32,
    /// Levels of fewer treelets are optimized by teams (see the module header): in the
    /// dispatched levels' kernels (and `nodes_level`, which sizes their dispatches)
    /// `RoundSchedule::team_below`, in the climb's `RoundSchedule::climb_team_below`.
    team_below: u32,
    /// γ of the next round (u32::MAX: none), whose levels the treelet kernels compute.
    next_gamma: u32,
    /// `level_start` of `level`: where the roots the dispatch optimizes start (of level
    /// level_dispatches + 1 for the climb). Computed here once, not by every workgroup from
    /// `level` − 1 divisions (a chain of dependent divisions before its first load).
    level_first: u32,
    /// The overlapped rounds (`waves`): how many, the reach and the wave a dispatch processes
    /// (the first for the climb); 0 elsewhere.
    pub(crate) rounds: u32,
    pub(crate) reach: u32,
    pub(crate) wave: u32,
    /// The levels up to this one are optimized per subtree (`RoundSchedule::subtree_levels`;
    /// 0: by level, as the levels above).
    subtree_levels: u32,
    /// Cut roots of level l per workgroup of `subtrees_optimize` at most: this >> (l − 1)
    /// (`RoundSchedule::subtree_width`).
    subtree_width: u32,
    /// Phased rounds (`phases`): the phases per round and the depth residue of the phase's
    /// roots (`roots_phase`); 0 elsewhere.
    phases: u32,
    residue: u32,
}
const _: () = assert!(std::mem::size_of::<RoundParams>() == 80);

impl RoundParams {
    /// The round's parameters for its climb, which starts at level `level` (its roots' slots
    /// from `level_first`) and takes the climb's team threshold.
    fn for_climb(self, level: u32, level_first: u32, schedule: &RoundSchedule) -> Self {
        Self {
            level,
            level_first,
            team_below: schedule.climb_team_below(),
            ..self
        }
    }

    /// The parameters of phase `phase` (from 0) of a round in `phases` phases (`phases`) over a
    /// tree of `n` leaves: `roots_phase` (grid row pitch `row_pitch`) buckets the roots of depth
    /// ≡ phases − 1 − phase in schedule word `phase` (level `phase` + 1), `treelets_optimize`
    /// optimizes them from slot 0, one invocation each (a team each in a phase of fewer than
    /// `team_below`), computing no next levels.
    pub(crate) fn phase(
        n: u32,
        row_pitch: u32,
        round: &Round,
        (phases, phase): (u32, u32),
        team_below: u32,
    ) -> Self {
        Self {
            count: n,
            row_pitch,
            gamma: round.gamma,
            max_leaf_size: round.model.max_leaf_size,
            ci: round.model.ci,
            ct: round.model.ct,
            zero: 0,
            level_dispatches: 0,
            level: phase + 1,
            levels_only: 0,
            team_below,
            next_gamma: u32::MAX,
            level_first: 0,
            rounds: 0,
            reach: 0,
            wave: 0,
            subtree_levels: 0,
            subtree_width: 0,
            phases,
            residue: phases - 1 - phase,
        }
    }

    /// The parameters of the overlapped rounds' kernels (`waves`) for a tree of `n` leaves:
    /// `overlap`'s rounds (γ_r = treelet size · 2^r) and reach, wave `wave`, and the team
    /// threshold of a dispatched wave, or the climb's past them.
    pub(crate) fn waves(n: u32, overlap: &Overlap, wave: u32) -> Self {
        let model = &overlap.model;
        Self {
            count: n,
            row_pitch: 0,
            gamma: overlap.treelet_size,
            max_leaf_size: model.max_leaf_size,
            ci: model.ci,
            ct: model.ct,
            zero: 0,
            level_dispatches: 0,
            level: 0,
            levels_only: 0,
            team_below: if wave > overlap.dispatched {
                overlap.climb_team_below
            } else {
                overlap.team_below
            },
            next_gamma: u32::MAX,
            level_first: 0,
            rounds: overlap.rounds,
            reach: overlap.reach,
            wave,
            subtree_levels: 0,
            subtree_width: 0,
            phases: 0,
            residue: 0,
        }
    }
}

/// Words of the schedule buffer: the roots per level (levels 1 ..= MAX_LEVEL_DISPATCHES + 1), the
/// subtrees' workgroups, then the indirect arguments (x, y, z) of each dispatched level
/// (treelet_round.wgsl).
pub(crate) const SCHEDULE_WORDS: u64 = SCHEDULE_ARGS + 3 * MAX_LEVEL_DISPATCHES as u64;
/// First word of the indirect arguments in the schedule buffer.
pub(crate) const SCHEDULE_ARGS: u64 = MAX_LEVEL_DISPATCHES as u64 + 2;

/// First slot of level `level`'s roots in the roots buffer of a tree of `n` leaves and smallest
/// root `gamma` (WGSL twin in `treelet_round.wgsl`): level l has ⌊n / (γ + l − 1)⌋ slots, as the
/// roots of a level are disjoint subtrees and a root of level l holds at least γ + l − 1 leaves
/// (γ, and one more than its child of level l − 1).
pub(crate) fn level_start(n: u32, gamma: u32, level: u32) -> u64 {
    (1..level)
        .map(|l| u64::from(n / gamma.saturating_add(l - 1)))
        .sum()
}

/// Per-node state the rounds and the collapse share (sized for n leaves, 2n-1 nodes).
pub(crate) struct TreeletState<'a> {
    /// The working tree: the LBVH (which the first round builds), then the rounds' topology.
    pub nodes: &'a wgpu::Buffer,
    /// The primitive boxes, the sorted keys and the primitive of each leaf (the keys' order),
    /// from which the first round builds the LBVH.
    pub prim_boxes: &'a wgpu::Buffer,
    pub keys: &'a wgpu::Buffer,
    pub order: &'a wgpu::Buffer,
    /// The parent links (the first round writes the LBVH's).
    pub parents: &'a wgpu::Buffer,
    pub prim_counts: &'a wgpu::Buffer,
    pub costs: &'a wgpu::Buffer,
    /// Treelet level of each root in this round (computed by the first round's schedule, or by
    /// the round before), and in the next round (computed by this round's treelet kernels for
    /// every node they finish); a node below γ has no level.
    pub levels: &'a wgpu::Buffer,
    pub next_levels: &'a wgpu::Buffer,
    /// Arrival words (n): per split in the first round's climb (`radix_climb.wgsl`), per internal
    /// node in the treelet climbs. Zero before the first round's climb, which leaves them zero;
    /// zeroed again by each later round's `nodes_level` for its treelet climb.
    pub arrivals: &'a wgpu::Buffer,
    /// `SCHEDULE_WORDS` words (storage and indirect), zeroed before each round.
    pub schedule: &'a wgpu::Buffer,
    /// The climb's two waves (n words).
    pub waves: &'a wgpu::Buffer,
}

/// What one round does: the cost model, the treelet size and γ (the smallest treelet root).
pub(crate) struct Round {
    pub model: CostModel,
    pub treelet_size: u32,
    pub gamma: u32,
    /// γ of the round after this one, u32::MAX if none.
    pub next_gamma: u32,
    /// A round ran before: the counts and costs are those of the tree, and the treelet roots'
    /// levels were computed by its treelet kernels (the schedule only counts them).
    pub levels_only: bool,
}

/// Levels a round of `n` leaves and smallest root `gamma` gives a dispatch each on a device of
/// type `device`; the levels above are climbed by one workgroup. A level's dispatch costs its
/// launch and a wait (~45-60 µs a level on an H200, however few its treelets), a climbed wave a
/// few barriers (~20 µs) but only 128 invocations: dispatches pay while a level has more
/// treelets than that.
/// - On a GPU: log2(n) − 4, fitted to an H200 sweep of 8-20 levels (trbvh, the fastest build
///   within 2 %: conference and crytek_sponza 14, sibenik and lost_empire 12, field:224 10,
///   field:707 14-16, field:2000 18; `scripts/gpu-schedules.sh`). The shared scenes' trees have
///   20-37 levels per round and more roots per level than a balanced tree: each level of more
///   than 128 roots (14 on conference) gets a dispatch.
/// - On a CPU device: the levels of more roots than 128 in a balanced tree (level L has about
///   n / (γ·2^L)), plus two for unbalanced trees.
///
/// `TreeletRounds::dispatched` caps it at `MAX_LEVEL_DISPATCHES`, as it does a forced count.
fn level_dispatches(n: u32, gamma: u32, device: wgpu::DeviceType) -> u32 {
    match device {
        wgpu::DeviceType::Cpu => {
            let workgroup = TREELETS_CLIMB.info.workgroup_size[0];
            (n / gamma.max(1) / workgroup).max(1).ilog2() + 2
        }
        _ => n.max(1).ilog2().saturating_sub(4),
    }
}

/// How the rounds spread their work over the device. Any schedule builds the same tree (tests
/// check the extremes); the defaults come from sweeps on lavapipe and an H200 (`treelet bench
/// --level-dispatches ... --team-below ...`, `scripts/gpu-schedules.sh`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RoundSchedule {
    /// Treelet levels per round that get a dispatch of their own, at most
    /// `MAX_LEVEL_DISPATCHES` (the rest are climbed by one workgroup); None: `level_dispatches`
    /// of the tree's size and the round's γ.
    pub level_dispatches: Option<u32>,
    /// Dispatched levels (and, with overlapped rounds, dispatched waves) of fewer treelets than
    /// this are optimized by teams of 32 invocations (a workgroup per treelet), the others one
    /// treelet per invocation; 0 never uses teams, u32::MAX uses them for every dispatched level
    /// or wave. None: `DEFAULT_TEAM_BELOW` (never).
    pub team_below: Option<u32>,
    /// The same for the climb's waves (those of the overlapped rounds too), which the workgroup's
    /// four teams take a treelet each at a time: waves of fewer treelets than this and than 32.
    /// None: `DEFAULT_TEAM_BELOW` (never; it does not follow `team_below`, as a climbed wave of
    /// many treelets takes several turns of the four teams).
    pub climb_team_below: Option<u32>,
    /// How a lone invocation's DP is written (`TreeletDp`) in the dispatched levels; None:
    /// written out.
    pub dp: Option<TreeletDp>,
    /// How it is written in the climb (`treelets_climb`: the top levels, a few treelets per
    /// wave, where one treelet's latency is the wave's); None: as in the dispatched levels.
    pub climb_dp: Option<TreeletDp>,
    /// The rounds overlapped in waves with this reach (`waves`, the GPU twin of
    /// `WorkingTree::optimize_overlapped`), each round starting on a root once it and its
    /// ancestors within the reach are done in the round before; at least `overlap_reach` of the
    /// treelet size (a build refuses less); None: the rounds one after another. The level
    /// dispatches (above) times the rounds are the waves dispatched (teams by `team_below`), the
    /// climb takes the rest (teams by `climb_team_below`).
    pub overlap: Option<u32>,
    /// Treelet levels 1 ..= K of each round optimized per subtree (`subtrees_optimize`), K at
    /// most `MAX_SUBTREE_LEVELS`: one dispatch, each workgroup taking a few of the subtrees whose
    /// root is of level K at most and its parent above (one of level l holds at most 2^l − 1
    /// roots), their treelets depth by depth between workgroup barriers instead of a dispatch
    /// per level. The levels above as without it (at least K levels count as dispatched). None
    /// or 0: every level by level. Not with overlapped rounds (a build refuses both).
    pub subtree_levels: Option<u32>,
    /// How many subtrees a workgroup takes: at most `subtree_width` >> (l − 1) of level l (and
    /// as many as its list holds, at most 32). A subtree of level l has up to 2^(l − 1) roots at
    /// its lowest depth, so 32 keeps a workgroup's steps near its subtrees' depths (latency: on
    /// a GPU most of the subtrees' lanes idle at the top depths, but the GPU has lanes to
    /// spare), while `SUBTREE_LIST` fills the list (throughput: fewer idle lanes, each
    /// workgroup longer). None: `DEFAULT_SUBTREE_WIDTH` of the device type.
    pub subtree_width: Option<u32>,
    /// How the phased rounds' roots take their slots in a phase's bucket (`RootSlots`; the
    /// bottom-up rounds have no phases); None: `RootSlots::default_for` the device type.
    pub root_slots: Option<RootSlots>,
}

impl RoundSchedule {
    /// Fails when the rounds overlap with a reach below the least for treelets of
    /// `treelet_size` leaves (`overlap_reach`): a wave's treelets could then share nodes; when
    /// subtrees take more than `MAX_SUBTREE_LEVELS` levels (their roots would not fit a
    /// workgroup's list); and when the rounds both overlap and take subtrees.
    pub fn check(&self, treelet_size: u32) -> Result<()> {
        let least = overlap_reach(treelet_size);
        let subtrees = self.subtree_levels();
        match self.overlap {
            Some(reach) if reach < least => Err(Error::InvalidArgument(format!(
                "a round overlap reach of {reach} is below {least}, the least for treelets of \
                 {treelet_size} leaves (a treelet reaches that many levels below its root, so the \
                 treelets of one wave could share nodes)"
            ))),
            _ if subtrees > MAX_SUBTREE_LEVELS => Err(Error::InvalidArgument(format!(
                "subtrees of {subtrees} treelet levels exceed the most, {MAX_SUBTREE_LEVELS} (a \
                 workgroup lists the up to 2^levels − 1 treelet roots of its subtree)"
            ))),
            Some(_) if subtrees > 0 => Err(Error::InvalidArgument(
                "the treelet rounds either overlap or take subtrees, not both (the overlapped \
                 rounds find their own waves)"
                    .into(),
            )),
            _ => Ok(()),
        }
    }

    /// The levels optimized per subtree (0: none).
    pub fn subtree_levels(&self) -> u32 {
        self.subtree_levels.unwrap_or(0)
    }

    /// The subtree width in effect on a device of type `device`.
    pub fn subtree_width(&self, device: wgpu::DeviceType) -> u32 {
        self.subtree_width.unwrap_or(match device {
            wgpu::DeviceType::Cpu => SUBTREE_LIST,
            _ => DEFAULT_SUBTREE_WIDTH,
        })
    }

    /// How the phased rounds' roots take their slots on a device of type `device`.
    pub fn root_slots(&self, device: wgpu::DeviceType) -> RootSlots {
        self.root_slots
            .unwrap_or_else(|| RootSlots::default_for(device))
    }

    /// The team threshold in effect in the dispatched levels.
    pub fn team_below(&self) -> u32 {
        self.team_below.unwrap_or(DEFAULT_TEAM_BELOW)
    }

    /// The team threshold in effect in the climb.
    pub fn climb_team_below(&self) -> u32 {
        self.climb_team_below.unwrap_or(DEFAULT_TEAM_BELOW)
    }

    /// The DP form in effect in the dispatched levels.
    pub fn dp(&self) -> TreeletDp {
        self.dp.unwrap_or_default()
    }

    /// The DP form in effect in the climb.
    pub fn climb_dp(&self) -> TreeletDp {
        self.climb_dp.unwrap_or_else(|| self.dp())
    }

    /// The options that are set, as `treelet bench` labels its runs ("d=14 t=1024 climb-t=4
    /// dp=loop climb-dp=loop overlap=6 subtrees=6 slots=root"; "default" when none is).
    pub fn label(&self) -> String {
        let mut parts = Vec::new();
        if let Some(levels) = self.level_dispatches {
            parts.push(format!("d={levels}"));
        }
        if let Some(below) = self.team_below {
            parts.push(format!("t={below}"));
        }
        if let Some(below) = self.climb_team_below {
            parts.push(format!("climb-t={below}"));
        }
        if let Some(dp) = self.dp {
            parts.push(format!("dp={}", dp.name()));
        }
        if let Some(dp) = self.climb_dp {
            parts.push(format!("climb-dp={}", dp.name()));
        }
        if let Some(reach) = self.overlap {
            parts.push(format!("overlap={reach}"));
        }
        if let Some(levels) = self.subtree_levels {
            parts.push(format!("subtrees={levels}"));
        }
        if let Some(width) = self.subtree_width {
            parts.push(format!("subtree-width={width}"));
        }
        if let Some(slots) = self.root_slots {
            parts.push(format!("slots={}", slots.name()));
        }
        if parts.is_empty() {
            return "default".into();
        }
        parts.join(" ")
    }

    /// The level dispatches the default schedule gives a round of `n` leaves and smallest root
    /// `gamma` on a device of type `device` (see `level_dispatches`).
    pub fn default_level_dispatches(n: u32, gamma: u32, device: wgpu::DeviceType) -> u32 {
        level_dispatches(n, gamma, device).min(MAX_LEVEL_DISPATCHES)
    }
}

/// The level (and climbed wave) size below which teams optimize the treelets by default: 0,
/// never. On lavapipe invocations are SIMD lanes and every barrier switches between them: teams
/// cost ~17x more per treelet (field:224: treelet stage 205 ms never, 228 ms below 64, 3.6 s
/// always). On an H200, with one threshold for the levels and the climb's waves, teams did not
/// pay either: trbvh with 16 levels dispatched, conference 4.49 ms never, 7.54 ms below 512,
/// 8.37 ms below 4096; field:707 5.40, 6.44 and 7.36 ms; below 4, which reaches the climb's
/// smallest waves only, conference 4.60 ms (`scripts/gpu-schedules.sh`). Those thresholds also
/// gave teams every climbed wave of up to 31 treelets, four at a time, so the dispatched levels'
/// teams alone are not measured yet: the two thresholds are apart now, and the tuning tries
/// each alone (`tuning::TEAM_THRESHOLDS`, `tuning::CLIMB_TEAM_THRESHOLDS`).
const DEFAULT_TEAM_BELOW: u32 = 0;

/// `RoundSchedule::subtree_width` on GPUs: the fastest of the widths timed on an NVIDIA H200
/// on the shared scenes (K = 6, build ms for W = 32 / 64 / 128 / 1024: conference 5.74 / 4.88 /
/// 4.49 / 5.18, sibenik 3.21 / 2.83 / 2.65 / 2.96, crytek_sponza 5.76 / 4.70 / 4.15 / 4.41;
/// field:707 and field:2000 are fastest with the list filled, 5.38 and 23.42 ms; README,
/// "Subtrees for the lowest levels"). Counted on the CPU twin's trees
/// (`examples/subtree_schedule.rs`), narrower workgroups trade warp steps for fewer dependent
/// steps per workgroup. CPU devices (lavapipe: invocations are SIMD lanes, throughput-bound)
/// fill the list.
const DEFAULT_SUBTREE_WIDTH: u32 = 128;

/// Treelet sizes with kernels of their own, MIN_TREELET_SIZE..=MAX_TREELET_SIZE.
const TREELET_SIZES: usize = (MAX_TREELET_SIZE - MIN_TREELET_SIZE + 1) as usize;

/// The pipeline-overridable constant that gives a treelet kernel its team path (`override
/// TREELET_TEAMS` in treelet_team.wgsl): 1 where its dispatches give teams a threshold, else 0,
/// and a GPU compiler drops the path, which the default schedules never run (RADV:
/// `treelets_optimize` 49,156 → 37,708 bytes of code, 3.5 KiB → 0.5 KiB of workgroup memory, no
/// scalar register spilled instead of 30; README, "Kernel statistics").
pub const TREELET_TEAMS_OVERRIDE: &str = "TREELET_TEAMS";

/// The pipeline-overridable constant that gives a treelet kernel the code for the next round's
/// levels (`override NEXT_LEVELS` in treelet_dp.wgsl, step 5): 1 for the treelets of a round with
/// a next round, 0 for a last round's, the phased rounds' and the overlapped rounds' (RADV:
/// `treelets_optimize` 240 → 216 registers, 37,708 → 35,416 bytes of code).
pub const NEXT_LEVELS_OVERRIDE: &str = "NEXT_LEVELS";

/// Treelet kernels compiled when first used, one per treelet size from MIN_TREELET_SIZE, DP form
/// (`dp as usize`), for a kernel with a team path whether it has it, and whether it computes the
/// next round's levels: the WGSL overrides `TREELET_SIZE` and `TREELET_DP_LOOP` select the
/// generated DP (`dp_unrolled`), `TREELET_TEAMS` the team path, `NEXT_LEVELS` step 5.
pub(crate) struct TreeletKernels {
    decl: &'static KernelDecl<RoundParams>,
    /// Whether the kernel includes treelet_team.wgsl (and so declares `TREELET_TEAMS`).
    has_teams: bool,
    compiled: [[TreeletVariants; TreeletDp::FORMS]; TREELET_SIZES],
}

/// One treelet size's and DP form's kernels: without and with the team path, each without and
/// with the next round's levels.
type TreeletVariants = [[OnceLock<Kernel<RoundParams>>; 2]; 2];

/// The line by which a treelet kernel takes the team path (and its override).
const TEAM_INCLUDE: &str = "#include \"treelet_team.wgsl\"";

impl TreeletKernels {
    pub(crate) fn new(decl: &'static KernelDecl<RoundParams>) -> Self {
        Self {
            decl,
            has_teams: decl.info.source.contains(TEAM_INCLUDE),
            compiled: Default::default(),
        }
    }

    /// The kernel for treelets of `treelet_size` leaves and this DP form, dispatched with the
    /// team threshold `team_below` (`RoundParams::team_below`) and the next round's smallest
    /// root `next_gamma` (`RoundParams::next_gamma`; u32::MAX: none): with the team path only
    /// where the threshold can send a treelet to it, and the next round's levels only where there
    /// is one.
    pub(crate) fn get(
        &self,
        ctx: &GpuContext,
        treelet_size: u32,
        dp: TreeletDp,
        team_below: u32,
        next_gamma: u32,
    ) -> &Kernel<RoundParams> {
        let team_path = self.team_path(team_below);
        let next_levels = next_gamma != u32::MAX;
        let slot = &self.compiled[(treelet_size - MIN_TREELET_SIZE) as usize][dp as usize];
        slot[usize::from(team_path)][usize::from(next_levels)].get_or_init(|| {
            let overrides = self.overrides(treelet_size, dp, team_path, next_levels);
            Kernel::with_overrides(ctx, self.decl, &overrides)
        })
    }

    /// Whether the kernel dispatched with the team threshold `team_below` needs the team path.
    fn team_path(&self, team_below: u32) -> bool {
        self.has_teams && team_below > 0
    }

    /// The override values of the kernel with these settings (`TREELET_TEAMS` only where the
    /// kernel declares it).
    fn overrides(
        &self,
        treelet_size: u32,
        dp: TreeletDp,
        team_path: bool,
        next_levels: bool,
    ) -> Vec<(&'static str, f64)> {
        let mut overrides = vec![
            (TREELET_SIZE_OVERRIDE, f64::from(treelet_size)),
            (TREELET_DP_LOOP_OVERRIDE, dp.override_value()),
            flag_override(NEXT_LEVELS_OVERRIDE, next_levels),
        ];
        if self.has_teams {
            overrides.push(flag_override(TREELET_TEAMS_OVERRIDE, team_path));
        }
        overrides
    }
}

/// The kernels of a round and their buckets.
pub(crate) struct TreeletRounds {
    /// `nodes_level` for the first round's climb (`Kernel::climb`: the device's climb
    /// width) and for the later rounds (one pass over the internal nodes: the declared width).
    climb_level: Kernel<RoundParams>,
    level: Kernel<RoundParams>,
    /// `treelets_optimize`, `subtrees_optimize` and `treelets_climb` per treelet size and DP
    /// form.
    optimize: TreeletKernels,
    subtrees: TreeletKernels,
    climb: TreeletKernels,
    /// `subsets_by_size`, read by the teams.
    subsets: wgpu::Buffer,
    /// The roots of the dispatched levels and the first climbed one, each level in its slots
    /// (`level_start`); grown on demand.
    roots: Option<wgpu::Buffer>,
    pub schedule: RoundSchedule,
}

impl TreeletRounds {
    pub fn new(ctx: &crate::gpu::GpuContext) -> Result<Self> {
        Ok(Self {
            climb_level: Kernel::climb(ctx, &NODES_LEVEL),
            level: Kernel::new(ctx, &NODES_LEVEL),
            optimize: TreeletKernels::new(&TREELETS_OPTIMIZE),
            subtrees: TreeletKernels::new(&SUBTREES_OPTIMIZE),
            climb: TreeletKernels::new(&TREELETS_CLIMB),
            subsets: storage_buffer(ctx, "treelet subsets by size", &subsets_by_size())?,
            roots: None,
            schedule: RoundSchedule::default(),
        })
    }

    /// Levels of a round of `n` leaves and smallest root `gamma` that get a dispatch each (those
    /// optimized per subtree count as dispatched: the climb starts above them).
    pub(crate) fn dispatched(&self, n: u32, gamma: u32, device: wgpu::DeviceType) -> u32 {
        self.schedule
            .level_dispatches
            .unwrap_or_else(|| level_dispatches(n, gamma, device))
            .min(MAX_LEVEL_DISPATCHES)
            .max(self.schedule.subtree_levels())
    }

    /// Grows the buckets for rounds of up to `n` leaves with these smallest roots (u32::MAX: a
    /// round without treelets).
    /// With `every_internal`, room for every internal node (a phase's roots: `phases`).
    pub fn reserve(
        &mut self,
        ctx: &GpuContext,
        n: u32,
        gammas: &[u32],
        every_internal: bool,
    ) -> Result<()> {
        let words = gammas
            .iter()
            .filter(|&&gamma| gamma != u32::MAX)
            .map(|&gamma| {
                // At least one level dispatched: the overlapped rounds take the first level's
                // roots and arguments from the first schedule.
                level_start(
                    n,
                    gamma,
                    self.dispatched(n, gamma, ctx.info.device_type).max(1) + 2,
                )
            })
            .max()
            .unwrap_or(0)
            .max(if every_internal { u64::from(n) } else { 1 });
        grow_storage_buffer(ctx, &mut self.roots, "treelet roots", words * 4)
    }

    /// Records one round over a working tree of `count` leaves (LBVH layout) whose schedule is
    /// zero (and whose arrival counters are, before the first round): the schedule and the
    /// dispatched levels in a pass "treelets", the climb in a pass "treelets climb" (timed
    /// apart: the one is throughput, the other a chain of small waves). `gamma = u32::MAX` only
    /// computes boxes, counts and costs. Call `reserve` first.
    pub fn record(
        &self,
        rec: &mut Recorder<'_>,
        count: ItemCount<'_>,
        state: &TreeletState<'_>,
        round: &Round,
    ) {
        let ctx = rec.ctx;
        let n = count.capacity();
        let dispatched = self.dispatched(n, round.gamma, ctx.info.device_type);
        let mut pass = rec.pass("treelets");
        let mut params = self.record_levels(&mut pass, ctx, count, state, round, dispatched);
        if round.gamma == u32::MAX {
            return;
        }
        let optimize = self.optimize(ctx, round.treelet_size, round.next_gamma);
        let treelet_buffers = self.treelet_buffers(state);
        // The GPU's u32 sum wraps; truncating the exact sum gives the same word.
        let first_slot = |level: u32| level_start(n, round.gamma, level) as u32;
        let subtree_levels = params.subtree_levels;
        for level in 1..=dispatched {
            params.level = level;
            params.level_first = first_slot(level);
            let args = 4 * (SCHEDULE_ARGS + 3 * u64::from(level - 1));
            if level > subtree_levels {
                pass.dispatch_indirect(optimize, state.schedule, args, &params, &treelet_buffers);
            } else if level == 1 {
                // The levels up to subtree_levels: a workgroup per few cut roots (level 1's
                // arguments count them all); the treelet buffers but the teams' subsets.
                // No team path there: its threshold does not apply.
                let subtrees = self.subtrees.get(
                    ctx,
                    round.treelet_size,
                    self.schedule.dp(),
                    0,
                    round.next_gamma,
                );
                let subtree_buffers = [&treelet_buffers[..6], &[state.next_levels]].concat();
                pass.dispatch_indirect(subtrees, state.schedule, args, &params, &subtree_buffers);
            }
        }
        drop(pass);
        let params = params.for_climb(dispatched + 1, first_slot(dispatched + 1), &self.schedule);
        let mut climb_buffers = treelet_buffers.to_vec();
        climb_buffers.extend([state.levels, state.arrivals, state.waves]);
        let climb = self.climb.get(
            ctx,
            round.treelet_size,
            self.schedule.climb_dp(),
            params.team_below,
            round.next_gamma,
        );
        rec.pass("treelets climb")
            .dispatch(climb, Grid::workgroups(1, 1), &params, &climb_buffers);
    }

    /// The buffers `treelets_optimize` binds (and `treelets_climb` first): the working tree, the
    /// schedule, the roots, the teams' subsets and the next round's levels.
    pub(crate) fn treelet_buffers<'b>(&'b self, state: &TreeletState<'b>) -> [&'b wgpu::Buffer; 8] {
        [
            state.nodes,
            state.parents,
            state.prim_counts,
            state.costs,
            state.schedule,
            self.roots(),
            &self.subsets,
            state.next_levels,
        ]
    }

    /// `treelets_optimize` for treelets of `treelet_size` leaves, with the DP form and the team
    /// threshold of the dispatched levels (and phases), for a round whose next round's smallest
    /// root is `next_gamma` (u32::MAX: none).
    pub(crate) fn optimize(
        &self,
        ctx: &GpuContext,
        treelet_size: u32,
        next_gamma: u32,
    ) -> &Kernel<RoundParams> {
        let team_below = self.schedule.team_below();
        self.optimize.get(
            ctx,
            treelet_size,
            self.schedule.dp(),
            team_below,
            next_gamma,
        )
    }

    /// `subsets_by_size`, which the teams read.
    pub(crate) fn subsets(&self) -> &wgpu::Buffer {
        &self.subsets
    }

    /// The roots bucketed by level (`reserve` allocates them).
    pub(crate) fn roots(&self) -> &wgpu::Buffer {
        self.roots.as_ref().expect("reserve() allocates the roots")
    }

    /// Records a round's `nodes_level` (its schedule: counts, costs, levels, the roots of the
    /// first `dispatched` levels bucketed with their indirect arguments, in the first round also
    /// the LBVH) into `pass`; returns the parameters for the round's treelet kernels.
    pub(crate) fn record_levels(
        &self,
        pass: &mut Pass<'_>,
        ctx: &GpuContext,
        count: ItemCount<'_>,
        state: &TreeletState<'_>,
        round: &Round,
        dispatched: u32,
    ) -> RoundParams {
        let n = count.capacity();
        let roots = self.roots();
        // One invocation per leaf, or per internal node when only levels are computed.
        let level = if round.levels_only {
            &self.level
        } else {
            &self.climb_level
        };
        let grid = level.grid(ctx, n);
        let params = RoundParams {
            count: n,
            row_pitch: grid.row_pitch,
            gamma: round.gamma,
            max_leaf_size: round.model.max_leaf_size,
            ci: round.model.ci,
            ct: round.model.ct,
            zero: 0,
            level_dispatches: dispatched,
            level: 0,
            levels_only: u32::from(round.levels_only),
            // The overlapped rounds' first wave takes the first level's arguments (no teams).
            team_below: match self.schedule.overlap {
                Some(_) => 0,
                None => self.schedule.team_below(),
            },
            next_gamma: round.next_gamma,
            level_first: 0,
            rounds: 0,
            reach: 0,
            wave: 0,
            // 0 with overlapped rounds, which take level 1's roots as their first wave (`check`
            // refuses both).
            subtree_levels: self.schedule.subtree_levels(),
            subtree_width: self.schedule.subtree_width(ctx.info.device_type),
            phases: 0,
            residue: 0,
        };
        let limit = count.limit(ctx);
        pass.dispatch(
            level,
            grid,
            &params,
            &[
                state.nodes,
                state.parents,
                state.prim_counts,
                state.costs,
                state.levels,
                state.arrivals,
                state.schedule,
                limit,
                state.prim_boxes,
                state.order,
                roots,
                state.keys,
            ],
        );
        params
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use rand::{Rng, SeedableRng};
    use rand_pcg::Pcg64;

    use super::{level_start, RoundParams, RoundSchedule};
    use crate::bvh::lbvh::{build_lbvh_from_boxes_cpu, TRBVH_KEY_BITS};
    use crate::bvh::treelet::waves::Overlap;
    use crate::bvh::treelet::TreeletDp;
    use crate::bvh::treelet::{optimize_lbvh_cpu, CostModel, TreeletSettings, WorkingTree};
    use crate::bvh::SahParams;
    use crate::geometry::Aabb;
    use crate::gpu::constants::MAX_SUBTREE_LEVELS;

    /// A schedule is refused with subtrees of more levels than a workgroup's list holds, and
    /// with both subtrees and overlapped rounds; each alone is taken.
    #[test]
    fn subtrees_beyond_the_list_or_with_overlapped_rounds_are_refused() {
        let with = |subtree_levels: u32, overlap: Option<u32>| {
            RoundSchedule {
                subtree_levels: Some(subtree_levels),
                overlap,
                ..RoundSchedule::default()
            }
            .check(7)
        };
        assert!(with(MAX_SUBTREE_LEVELS, None).is_ok());
        assert!(with(0, Some(6)).is_ok());
        let beyond = with(MAX_SUBTREE_LEVELS + 1, None).unwrap_err().to_string();
        assert!(beyond.contains("exceed the most"), "{beyond}");
        let both = with(4, Some(6)).unwrap_err().to_string();
        assert!(both.contains("not both"), "{both}");
    }

    /// The overlapped rounds' dispatched waves take the dispatched levels' team threshold, the
    /// waves past them (the climb's dispatch) the climb's, and so does the climb of the rounds
    /// one after another: a swap builds the same trees, so only this checks it.
    #[test]
    fn each_dispatch_takes_its_team_threshold() {
        let overlap = Overlap {
            model: CostModel::from(&SahParams::default()),
            treelet_size: 7,
            rounds: 3,
            reach: 6,
            dispatched: 12,
            dp: TreeletDp::Unrolled,
            climb_dp: TreeletDp::Unrolled,
            team_below: 1024,
            climb_team_below: 5,
        };
        for wave in [1, 12] {
            assert_eq!(RoundParams::waves(1000, &overlap, wave).team_below, 1024);
        }
        assert_eq!(RoundParams::waves(1000, &overlap, 13).team_below, 5);
        // The rounds one after another: the climb's dispatch likewise.
        let schedule = RoundSchedule {
            team_below: Some(1024),
            climb_team_below: Some(5),
            ..RoundSchedule::default()
        };
        let climb = RoundParams::waves(1000, &overlap, 1).for_climb(13, 77, &schedule);
        assert_eq!(
            (climb.level, climb.level_first, climb.team_below),
            (13, 77, 5)
        );
    }

    /// Boxes of `n` triangles: uniform, in two far clusters, or all at one point.
    fn boxes(n: usize, kind: u32, seed: u64) -> Vec<Aabb> {
        let mut rng = Pcg64::seed_from_u64(seed);
        (0..n)
            .map(|i| {
                let c = match kind {
                    0 => Vec3::new(rng.random(), rng.random(), rng.random()),
                    1 => {
                        let far = if i % 5 == 0 { 1000.0 } else { 0.0 };
                        Vec3::new(rng.random::<f32>() + far, rng.random(), rng.random())
                    }
                    _ => Vec3::ZERO,
                };
                Aabb::new(c, c + Vec3::splat(0.01))
            })
            .collect()
    }

    /// The slots `level_start` gives each level hold all of its roots, in LBVHs and in the trees
    /// after restructuring rounds (whose levels the next round buckets), for several gammas.
    #[test]
    fn level_slots_hold_every_root() {
        let model = CostModel::from(&SahParams::default());
        for (kind, n) in [(0, 3000), (1, 3000), (2, 700), (0, 257)] {
            let (lbvh, parents) =
                build_lbvh_from_boxes_cpu(&boxes(n, kind, 7 + n as u64), TRBVH_KEY_BITS);
            let lbvh = WorkingTree::from_lbvh(lbvh, parents);
            for rounds in 0..3 {
                let settings = TreeletSettings {
                    treelet_size: 7,
                    rounds,
                    split_percent: 0,
                    last_round_size: None,
                    phases: None,
                    first_round_phases: None,
                };
                let tree = optimize_lbvh_cpu(lbvh.clone(), &settings, &model);
                for gamma in [3u32, 5, 7, 14, 28, 56] {
                    let (leaves, levels) = tree.treelet_levels(gamma);
                    let top = levels.iter().copied().max().unwrap_or(0);
                    for level in 1..=top {
                        let roots = (0..tree.nodes.len())
                            .filter(|&i| leaves[i] >= gamma && levels[i] == level)
                            .count() as u64;
                        let slots = level_start(n as u32, gamma, level + 1)
                            - level_start(n as u32, gamma, level);
                        assert!(
                            roots <= slots,
                            "kind {kind}, n {n}, {rounds} rounds, gamma {gamma}: level {level} \
                             has {roots} roots in {slots} slots"
                        );
                    }
                }
            }
        }
    }

    /// A kernel with a team path gets it only where its threshold can send a treelet there, and
    /// the override is declared where the team path is included (the kernels without one are
    /// compiled without the override, which wgpu would refuse as unknown).
    #[test]
    fn team_path_only_with_a_threshold() {
        use super::{TreeletKernels, TREELET_TEAMS_OVERRIDE};
        use crate::bvh::treelet::{
            SUBTREES_OPTIMIZE, TREELETS_CLIMB, TREELETS_OPTIMIZE, WAVES_CLIMB, WAVES_OPTIMIZE,
        };
        use crate::gpu::shader_source;
        let teams = |kernels: &TreeletKernels, team_below: u32| {
            kernels
                .overrides(7, TreeletDp::Unrolled, kernels.team_path(team_below), true)
                .iter()
                .find(|(name, _)| *name == TREELET_TEAMS_OVERRIDE)
                .map(|&(_, value)| value)
        };
        for decl in [
            &TREELETS_OPTIMIZE,
            &TREELETS_CLIMB,
            &WAVES_OPTIMIZE,
            &WAVES_CLIMB,
        ] {
            let kernels = TreeletKernels::new(decl);
            assert_eq!(teams(&kernels, 0), Some(0.0), "{}", decl.info.name);
            assert_eq!(teams(&kernels, 1), Some(1.0), "{}", decl.info.name);
            assert_eq!(teams(&kernels, u32::MAX), Some(1.0), "{}", decl.info.name);
            let source = shader_source(decl.info.source, &[]);
            assert!(
                source.contains("override TREELET_TEAMS"),
                "{}",
                decl.info.name
            );
        }
        let subtrees = TreeletKernels::new(&SUBTREES_OPTIMIZE);
        assert_eq!(teams(&subtrees, 256), None);
        assert!(
            !shader_source(SUBTREES_OPTIMIZE.info.source, &[]).contains("override TREELET_TEAMS")
        );
    }

    /// Every treelet kernel declares `NEXT_LEVELS` (through treelet_dp.wgsl) and gets it set: 1
    /// for a round with a next round, 0 for one without (`TreeletKernels::get`'s next γ).
    #[test]
    fn next_levels_only_with_a_next_round() {
        use super::{TreeletKernels, NEXT_LEVELS_OVERRIDE};
        use crate::bvh::treelet::{
            SUBTREES_OPTIMIZE, TREELETS_CLIMB, TREELETS_OPTIMIZE, WAVES_CLIMB, WAVES_OPTIMIZE,
        };
        use crate::gpu::shader_source;
        for decl in [
            &TREELETS_OPTIMIZE,
            &TREELETS_CLIMB,
            &SUBTREES_OPTIMIZE,
            &WAVES_OPTIMIZE,
            &WAVES_CLIMB,
        ] {
            let kernels = TreeletKernels::new(decl);
            for (next_levels, value) in [(false, 0.0), (true, 1.0)] {
                let overrides = kernels.overrides(7, TreeletDp::Unrolled, false, next_levels);
                assert!(
                    overrides.contains(&(NEXT_LEVELS_OVERRIDE, value)),
                    "{}",
                    decl.info.name
                );
            }
            let source = shader_source(decl.info.source, &[]);
            assert!(
                source.contains("override NEXT_LEVELS"),
                "{}",
                decl.info.name
            );
        }
    }
}
