//! TRBVH: treelet restructuring of an LBVH on the GPU (Karras & Aila 2013, "Fast Parallel
//! Construction of High-Quality Bounding Volume Hierarchies", §3-4), then leaf collapse and
//! compaction into the traversal layout.
//!
//! Per build, recorded into one recording: the GPU LBVH (`bvh::lbvh`) into a working tree,
//! `rounds` restructuring rounds (`rounds`: level by level, kernels `nodes_level`,
//! `treelets_optimize`, `treelets_climb`; γ = treelet size, doubling each round; or overlapped in
//! waves, `waves`; or each round in phases by depth, `phases`), the collapse into the output tree
//! (`collapse`: kernels `nodes_mark`, `nodes_compact`).
//! Each part has a CPU twin (`build_trbvh_cpu`), the test oracle.

mod collapse;
mod cpu;
mod dp;
pub(crate) mod dp_unrolled;
mod nodes_compact;
mod nodes_level;
mod nodes_mark;
mod phases;
mod rounds;
mod subtrees_optimize;
mod treelets_climb;
mod treelets_optimize;
mod waves;

pub use cpu::WorkingTree;
pub use dp::{
    solve_treelet, subsets_by_size, surface_area, CostModel, TreeletLeaf, TreeletSolution,
};
pub use nodes_compact::NODES_COMPACT;
pub use nodes_level::NODES_LEVEL;
pub use nodes_mark::NODES_MARK;
pub use phases::{RootSlots, MAX_PHASES, MIN_PHASES, ROOTS_PHASE};
pub use subtrees_optimize::SUBTREES_OPTIMIZE;
pub use treelets_climb::TREELETS_CLIMB;
pub use treelets_optimize::TREELETS_OPTIMIZE;
pub use waves::{overlap_reach, WAVES_CLIMB, WAVES_FIND, WAVES_OPTIMIZE};

pub use dp_unrolled::TreeletDp;
pub use rounds::RoundSchedule;

pub use crate::gpu::constants::{
    MAX_GPU_LEAF_SIZE, MAX_LEVEL_DISPATCHES, MAX_SUBTREE_LEVELS, MAX_TREELET_SIZE,
    MIN_TREELET_SIZE, SUBTREE_LIST,
};

use collapse::{Collapse, CollapseBuffers};
use phases::PhasedRounds;
use rounds::{Round, TreeletRounds, TreeletState, SCHEDULE_WORDS};
use waves::{Overlap, OverlappedRounds};

use super::lbvh::{
    build_lbvh_from_boxes_cpu, prim_boxes_cpu, LbvhBuilder, LbvhInput, LBVH_PASSES, TRBVH_KEY_BITS,
};
use super::presplit::{presplit_cpu, split_budget, PreSplitter};
use super::{Bvh, BvhNode, SahParams};
use crate::device::{Geometry, Tree};
use crate::geometry::Aabb;
use crate::gpu::{
    indirect_buffer_zeroed, read_buffer, storage_buffer_zeroed, GpuContext, GpuTimer, ItemCount,
    ParamSlab, Recorder, StageTime,
};
use crate::scene::Triangle;
use crate::{Error, Result};

/// Treelet optimizer settings (presets as named constants; the paper's setting is `BALANCED`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TreeletSettings {
    /// Leaves per treelet, 3..=8 (the paper uses 7).
    pub treelet_size: u32,
    /// Restructuring rounds (γ = treelet_size, doubled each round); 0 = LBVH + collapse only.
    pub rounds: u32,
    /// Triangle pre-splitting budget β in percent of the triangle count (0 disables; §5 of the
    /// paper, which uses 30).
    pub split_percent: u32,
    /// Leaves per treelet of the last round, where it takes smaller (cheaper) treelets than the
    /// others, 3..=8, with the same γ; None: `treelet_size`. Not from the paper: its DP is the
    /// round's cost (966 partition tests for 7 leaves, 90 for 5), and the last round improves
    /// the tree least (README, "A cheaper last round").
    pub last_round_size: Option<u32>,
    /// Each round in P phases by depth instead of bottom-up: phase k optimizes the roots whose
    /// depth is ≡ P − 1 − k (mod P), depths as the phases before left them
    /// (`WorkingTree::optimize_phased`). A treelet's leaves lie at most P − 1 levels below its
    /// root, so a phase's treelets are disjoint: below the treelet size, the formation expands no
    /// leaf at that depth (and may end with fewer leaves). Not the paper's order, so not its
    /// tree: a round is P phases (two dispatches each) of many treelets each, not a step per
    /// treelet level (20-37 on the shared scenes, most of them a few treelets waiting on one
    /// another). None: the paper's bottom-up rounds.
    pub phases: Option<u32>,
    /// Phases of the first round, where the LBVH leaves the most to repair and the order counts
    /// most (README, "Phased rounds": 14 then 7 is within 0.35 % of the paper's SAH on the shared
    /// scenes); None: `phases`. Only with `phases`.
    pub first_round_phases: Option<u32>,
}

impl TreeletSettings {
    /// Quick: small treelets, one round.
    pub const FAST: Self = Self {
        treelet_size: 5,
        rounds: 1,
        split_percent: 0,
        last_round_size: None,
        phases: None,
        first_round_phases: None,
    };
    /// The paper's reference setting: treelets of 7 leaves, 3 rounds.
    pub const BALANCED: Self = Self {
        treelet_size: 7,
        rounds: 3,
        split_percent: 0,
        last_round_size: None,
        phases: None,
        first_round_phases: None,
    };
    /// Largest treelets the kernel supports, more rounds.
    pub const HIGH_QUALITY: Self = Self {
        treelet_size: 8,
        rounds: 4,
        split_percent: 0,
        last_round_size: None,
        phases: None,
        first_round_phases: None,
    };
    /// The paper's treelets and rounds in phases, with the fewest dependent steps that keep its
    /// tree quality: 3 rounds of 6, 4 and 4 phases (14 steps instead of 57-108 treelet levels;
    /// SAH within 0.9 % of `BALANCED`'s on the shared scenes, trbvh and trbvh-split, README
    /// "Phased rounds").
    pub const PHASED: Self = Self {
        treelet_size: 7,
        rounds: 3,
        split_percent: 0,
        last_round_size: None,
        phases: Some(4),
        first_round_phases: Some(6),
    };

    /// Leaves per treelet of round `round` (from 0).
    pub fn round_size(&self, round: usize) -> u32 {
        match self.last_round_size {
            Some(size) if round + 1 == self.rounds as usize => size,
            _ => self.treelet_size,
        }
    }

    /// Phases of round `round` (from 0) in effect; None: the paper's bottom-up rounds.
    pub fn round_phases(&self, round: usize) -> Option<u32> {
        match self.first_round_phases {
            Some(phases) if round == 0 => Some(phases),
            _ => self.phases,
        }
    }

    /// Leaves per treelet of the last round in effect; None without rounds.
    pub fn last_round_treelets(&self) -> Option<u32> {
        (self.rounds > 0).then(|| self.round_size(self.rounds as usize - 1))
    }

    /// Whether every round takes treelets of one size (the overlapped rounds need it).
    pub fn one_treelet_size(&self) -> bool {
        self.last_round_treelets()
            .is_none_or(|size| size == self.treelet_size)
    }

    /// A preset by name: `fast`, `balanced`, `high` or `phased`.
    pub fn preset(name: &str) -> Result<Self> {
        match name {
            "fast" => Ok(Self::FAST),
            "balanced" => Ok(Self::BALANCED),
            "high" => Ok(Self::HIGH_QUALITY),
            "phased" => Ok(Self::PHASED),
            _ => Err(Error::InvalidArgument(format!(
                "unknown treelet preset '{name}' (known: fast, balanced, high, phased)"
            ))),
        }
    }

    /// Checks the settings together with the SAH parameters (whose max leaf size the collapse uses).
    pub fn validate(&self, sah: &SahParams) -> Result<()> {
        if !(MIN_TREELET_SIZE..=MAX_TREELET_SIZE).contains(&self.treelet_size) {
            return Err(Error::InvalidArgument(format!(
                "treelet size must be {MIN_TREELET_SIZE}..={MAX_TREELET_SIZE}, got {}",
                self.treelet_size
            )));
        }
        if let Some(size) = self.last_round_size {
            if !(MIN_TREELET_SIZE..=MAX_TREELET_SIZE).contains(&size) {
                return Err(Error::InvalidArgument(format!(
                    "last round's treelet size must be {MIN_TREELET_SIZE}..={MAX_TREELET_SIZE}, \
                     got {size}"
                )));
            }
            // A root holds at least γ leaves, and its treelet takes `size` of them.
            let last_gamma = self.gammas().last().copied().unwrap_or(u32::MAX);
            if self.rounds > 0 && last_gamma < size {
                return Err(Error::InvalidArgument(format!(
                    "the last round's treelets of {size} leaves need γ ≥ {size}, but its γ is \
                     {last_gamma} (treelet size {} doubled each round)",
                    self.treelet_size
                )));
            }
        }
        if !(1..=MAX_GPU_LEAF_SIZE).contains(&sah.max_leaf_size) {
            return Err(Error::InvalidArgument(format!(
                "max leaf size must be 1..={MAX_GPU_LEAF_SIZE} for the GPU treelet builder, got {}",
                sah.max_leaf_size
            )));
        }
        if self.split_percent > 100 {
            return Err(Error::InvalidArgument(format!(
                "split budget must be 0..=1 (0..=100 %), got {} %",
                self.split_percent
            )));
        }
        if self.first_round_phases.is_some() && self.phases.is_none() {
            return Err(Error::InvalidArgument(
                "first-round phases need phased rounds (treelet phases)".into(),
            ));
        }
        for round in 0..self.rounds as usize {
            let Some(phases) = self.round_phases(round) else {
                break;
            };
            let which = if round == 0 && self.first_round_phases.is_some() {
                "first-round treelet phases"
            } else {
                "treelet phases"
            };
            if !(MIN_PHASES..=MAX_PHASES).contains(&phases) {
                return Err(Error::InvalidArgument(format!(
                    "{which} must be {MIN_PHASES}..={MAX_PHASES} (a treelet's leaves lie at most \
                     P − 1 levels below its root, and a treelet needs 3 leaves), got {phases}"
                )));
            }
        }
        if self.rounds > 16 {
            return Err(Error::InvalidArgument(format!(
                "at most 16 rounds, got {}",
                self.rounds
            )));
        }
        Ok(())
    }

    /// γ of each round; a single cost-only pass (no treelets) when `rounds` is 0.
    pub fn gammas(&self) -> Vec<u32> {
        if self.rounds == 0 {
            return vec![u32::MAX];
        }
        (0..self.rounds)
            .map(|r| self.treelet_size.saturating_mul(1 << r))
            .collect()
    }
}

impl Default for TreeletSettings {
    fn default() -> Self {
        Self::BALANCED
    }
}

/// CPU twin of the whole GPU TRBVH build.
pub fn build_trbvh_cpu(triangles: &[Triangle], settings: &TreeletSettings, sah: &SahParams) -> Bvh {
    optimize_cpu(triangles, settings, sah).collapse(&CostModel::from(sah), None)
}

/// CPU twin of the whole GPU TRBVH build with triangle pre-splitting (`settings.split_percent`).
pub fn build_trbvh_split_cpu(
    triangles: &[Triangle],
    settings: &TreeletSettings,
    sah: &SahParams,
) -> Bvh {
    let budget = split_budget(triangles.len() as u32, settings.split_percent);
    if budget == 0 {
        return build_trbvh_cpu(triangles, settings, sah);
    }
    let (boxes, ref_tris) = presplit_cpu(triangles, budget);
    optimize_prims_cpu(&boxes, settings, sah).collapse(&CostModel::from(sah), Some(&ref_tris))
}

/// CPU twin up to the end of the rounds (the working tree before the collapse).
pub fn optimize_cpu(
    triangles: &[Triangle],
    settings: &TreeletSettings,
    sah: &SahParams,
) -> WorkingTree {
    optimize_prims_cpu(&prim_boxes_cpu(triangles), settings, sah)
}

/// CPU twin of the rounds over primitive boxes (pre-split references or triangle boxes).
pub fn optimize_prims_cpu(
    prim_boxes: &[Aabb],
    settings: &TreeletSettings,
    sah: &SahParams,
) -> WorkingTree {
    let (lbvh, parents) = build_lbvh_from_boxes_cpu(prim_boxes, TRBVH_KEY_BITS);
    optimize_lbvh_cpu(
        WorkingTree::from_lbvh(lbvh, parents),
        settings,
        &CostModel::from(sah),
    )
}

/// CPU twin of the rounds over a given LBVH (e.g. the GPU's own, read back).
pub fn optimize_lbvh_cpu(
    mut tree: WorkingTree,
    settings: &TreeletSettings,
    model: &CostModel,
) -> WorkingTree {
    let gammas = settings.gammas();
    match settings.phases {
        Some(phases) if gammas[0] != u32::MAX => {
            let rounds: Vec<(u32, u32, u32)> = gammas
                .iter()
                .enumerate()
                .map(|(round, &gamma)| {
                    let phases = settings.round_phases(round).unwrap_or(phases);
                    (settings.round_size(round), gamma, phases)
                })
                .collect();
            tree.optimize_phased(model, &rounds);
        }
        _ => {
            for (round, gamma) in gammas.into_iter().enumerate() {
                tree.optimize_round(model, settings.round_size(round), gamma);
            }
        }
    }
    tree
}

/// Scratch space for working trees of up to `capacity` leaves.
struct Scratch {
    capacity: u32,
    /// The working tree: nodes in the LBVH layout and the primitive of each leaf.
    nodes: wgpu::Buffer,
    order: wgpu::Buffer,
    prim_counts: wgpu::Buffer,
    costs: wgpu::Buffer,
    /// Treelet levels of the odd and even rounds (each round computes the next one's).
    levels: [wgpu::Buffer; 2],
    arrivals: wgpu::Buffer,
    schedule: wgpu::Buffer,
    waves: wgpu::Buffer,
    flags: wgpu::Buffer,
    scans: wgpu::Buffer,
    leaf_slots: wgpu::Buffer,
}

impl Scratch {
    fn new(ctx: &GpuContext, capacity: u32) -> Result<Self> {
        let nodes = u64::from(2 * capacity - 1);
        Ok(Self {
            capacity,
            nodes: storage_buffer_zeroed(
                ctx,
                "treelet working nodes",
                nodes * std::mem::size_of::<BvhNode>() as u64,
            )?,
            order: storage_buffer_zeroed(ctx, "treelet working order", u64::from(capacity) * 4)?,
            prim_counts: storage_buffer_zeroed(ctx, "treelet prim counts", nodes * 4)?,
            costs: storage_buffer_zeroed(ctx, "treelet costs", nodes * 4)?,
            levels: [
                storage_buffer_zeroed(ctx, "treelet levels", nodes * 4)?,
                storage_buffer_zeroed(ctx, "treelet levels", nodes * 4)?,
            ],
            arrivals: storage_buffer_zeroed(ctx, "treelet arrivals", u64::from(capacity) * 4)?,
            schedule: indirect_buffer_zeroed(ctx, "treelet schedule", SCHEDULE_WORDS * 4)?,
            waves: storage_buffer_zeroed(ctx, "treelet waves", u64::from(capacity) * 4)?,
            flags: storage_buffer_zeroed(ctx, "collapse flags", nodes * 4)?,
            scans: storage_buffer_zeroed(ctx, "collapse scans", 2 * nodes * 4)?,
            leaf_slots: storage_buffer_zeroed(ctx, "collapse leaf slots", u64::from(capacity) * 8)?,
        })
    }
}

/// A GPU build's intermediate trees, read back for comparison in tests: the LBVH the rounds start
/// from (costs and counts not yet set), the working tree after the rounds, the collapsed tree.
#[derive(Clone, Debug)]
pub struct TrbvhStages {
    pub lbvh: WorkingTree,
    pub working: WorkingTree,
    pub bvh: Bvh,
    /// With pre-splitting, the triangle of each reference (the working tree's primitives).
    pub ref_tris: Option<Vec<u32>>,
}

/// GPU TRBVH builder: LBVH + treelet rounds + collapse, kernels and scratch reused per frame.
pub struct TrbvhBuilder {
    lbvh: LbvhBuilder,
    presplit: Option<PreSplitter>,
    rounds: TreeletRounds,
    /// The rounds overlapped in waves (`RoundSchedule::overlap`).
    waves: OverlappedRounds,
    /// The rounds in phases by depth (`TreeletSettings::phases`).
    phased: PhasedRounds,
    collapse: Collapse,
    scratch: Option<Scratch>,
    /// Leaves the last build's working tree had room for.
    last_capacity: u32,
    /// The last build pre-split its triangles (its leaf count is on the GPU).
    last_split: bool,
    pub settings: TreeletSettings,
    pub sah: SahParams,
    /// Parameters of the builds this builder records and submits itself (`build`).
    params: ParamSlab,
}

impl TrbvhBuilder {
    pub fn new(ctx: &GpuContext, settings: TreeletSettings, sah: SahParams) -> Result<Self> {
        settings.validate(&sah)?;
        Ok(Self {
            lbvh: LbvhBuilder::new(ctx).with_key_bits(TRBVH_KEY_BITS)?,
            presplit: None,
            rounds: TreeletRounds::new(ctx)?,
            waves: OverlappedRounds::new(),
            phased: PhasedRounds::new(),
            collapse: Collapse::new(ctx)?,
            scratch: None,
            last_capacity: 0,
            last_split: false,
            settings,
            sah,
            params: ParamSlab::new(ctx),
        })
    }

    /// How the rounds spread their work over the device (the tree does not depend on it).
    pub fn set_schedule(&mut self, schedule: RoundSchedule) {
        self.rounds.schedule = schedule;
    }

    pub fn schedule(&self) -> RoundSchedule {
        self.rounds.schedule
    }

    /// The LBVH's radix sort tile in the next builds (`LbvhBuilder::set_sort_tile_items`).
    pub fn set_sort_tile_items(&mut self, items: Option<u32>) -> Result<()> {
        self.lbvh.set_sort_tile_items(items)
    }

    /// The leaves of a build over `triangles` triangles, as the build sizes its stages: the
    /// triangles, or with pre-splitting the references there can be.
    pub fn leaf_capacity(&self, triangles: u32) -> u32 {
        let budget = split_budget(triangles, self.settings.split_percent);
        if budget == 0 {
            triangles
        } else {
            PreSplitter::capacity(triangles, budget)
        }
    }

    /// Timestamped passes one build records (at most: each round two).
    pub fn pass_count(&self) -> u32 {
        LBVH_PASSES + 3 + 2 * self.settings.gammas().len() as u32
    }

    /// Builds `geometry`'s optimized tree into `tree` and waits; returns the stage times.
    pub fn build(
        &mut self,
        ctx: &GpuContext,
        geometry: &Geometry,
        tree: &mut Tree,
    ) -> Result<Vec<StageTime>> {
        let mut timer = GpuTimer::new(ctx, self.pass_count());
        let mut params = std::mem::replace(&mut self.params, ParamSlab::new(ctx));
        let result = {
            let mut rec = Recorder::new(ctx, &mut params, Some(&mut timer));
            let result = self.record_inner(&mut rec, geometry, tree, None);
            rec.submit();
            result
        };
        self.params = params;
        result?;
        timer.read(ctx)
    }

    /// Records a build of `geometry`'s optimized tree into `tree` (grown as needed).
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        tree: &mut Tree,
    ) -> Result<()> {
        self.record_inner(rec, geometry, tree, None)
    }

    /// Like `build`, reading back the LBVH before the rounds and the working tree after them
    /// (tests).
    pub fn build_stages(&mut self, ctx: &GpuContext, geometry: &Geometry) -> Result<TrbvhStages> {
        let mut tree = Tree::empty(ctx)?;
        let mut trees = None;
        let mut params = ParamSlab::new(ctx);
        let mut rec = Recorder::new(ctx, &mut params, None);
        self.record_inner(&mut rec, geometry, &mut tree, Some(&mut trees))?;
        rec.submit();
        let lbvh = trees.take().expect("requested");
        let working = self.read_working(ctx)?;
        let ref_tris = match (&self.presplit, self.last_split) {
            (Some(splitter), true) => splitter
                .ref_tris()
                .map(|buffer| read_buffer(ctx, buffer, working.prims.len()))
                .transpose()?,
            _ => None,
        };
        Ok(TrbvhStages {
            lbvh,
            working,
            bvh: tree.download(ctx)?,
            ref_tris,
        })
    }

    /// The working tree of the last build (after its rounds), read back.
    fn read_working(&self, ctx: &GpuContext) -> Result<WorkingTree> {
        let s = self.scratch.as_ref().expect("built");
        let parents = self.lbvh.parents().expect("built");
        let n = self.read_leaf_count(ctx)?;
        let count = (2 * n - 1) as usize;
        Ok(WorkingTree {
            nodes: read_buffer(ctx, &s.nodes, count)?,
            parents: read_buffer(ctx, parents, count)?,
            prims: read_buffer(ctx, &s.order, n as usize)?,
            prim_counts: read_buffer(ctx, &s.prim_counts, count)?,
            costs: read_buffer(ctx, &s.costs, count)?,
        })
    }

    /// Leaves of the last build's working tree, read back (tests).
    fn read_leaf_count(&self, ctx: &GpuContext) -> Result<u32> {
        match (&self.presplit, self.last_split) {
            (Some(splitter), true) => Ok(read_buffer::<u32>(ctx, splitter.total(), 1)?[0]),
            _ => Ok(self.last_capacity),
        }
    }

    /// Records the build; with `lbvh_out`, flushes after the LBVH and reads it back (tests).
    fn record_inner(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        tree: &mut Tree,
        lbvh_out: Option<&mut Option<WorkingTree>>,
    ) -> Result<()> {
        self.settings.validate(&self.sah)?;
        self.rounds.schedule.check(self.settings.treelet_size)?;
        let schedule = &self.rounds.schedule;
        if self.settings.phases.is_some()
            && (schedule.overlap.is_some()
                || schedule.subtree_levels() > 0
                || schedule.level_dispatches.is_some()
                || schedule.climb_team_below.is_some()
                || schedule.climb_dp.is_some())
        {
            return Err(Error::InvalidArgument(
                "the phased treelet rounds take no overlap, subtrees, level dispatches or climb \
                 options (a phase is one dispatch of every root at its depths, and there is no \
                 climb): drop the phases or those schedule options"
                    .into(),
            ));
        }
        if self.rounds.schedule.overlap.is_some() && !self.settings.one_treelet_size() {
            return Err(Error::InvalidArgument(
                "the overlapped treelet rounds take one treelet size (a wave runs the treelets of \
                 several rounds in one dispatch): drop the last round's size or the overlap"
                    .into(),
            ));
        }
        let ctx = rec.ctx;
        let budget = split_budget(geometry.triangle_count, self.settings.split_percent);
        // The leaves: the triangles, or the references of pre-splitting (counted on the GPU).
        let n = self.leaf_capacity(geometry.triangle_count);
        let scratch = self.reserve(ctx, n)?;
        let (nodes, order) = (scratch.nodes.clone(), scratch.order.clone());
        let split_total = if budget == 0 {
            None
        } else {
            self.lbvh.reserve(ctx, n)?;
            let prim_boxes = self.lbvh.prim_boxes().expect("reserved").clone();
            let splitter = self.presplit.get_or_insert_with(|| PreSplitter::new(ctx));
            splitter.record(rec, geometry, budget, &prim_boxes)?;
            Some(splitter.total().clone())
        };
        let (count, input) = match &split_total {
            None => (
                ItemCount::Known(n),
                LbvhInput::Triangles {
                    buffer: &geometry.triangles,
                    count: n,
                },
            ),
            Some(total) => {
                let count = ItemCount::OnGpu {
                    buffer: total,
                    capacity: n,
                };
                (count, LbvhInput::PrimBoxes(count))
            }
        };
        // The first round's schedule builds the LBVH (hierarchy and boxes) with its counts and
        // costs; a test that reads the LBVH back has the LBVH's own climb build it first (the
        // same tree, which the first round then builds again).
        if lbvh_out.is_some() {
            self.lbvh.record_into(rec, input, &nodes, &order)?;
        } else {
            self.lbvh.record_sorted_into(rec, input, &order)?;
        }
        self.last_capacity = n;
        self.last_split = split_total.is_some();
        if let Some(out) = lbvh_out {
            rec.flush();
            let n = self.read_leaf_count(ctx)?;
            let s = self.scratch.as_ref().expect("reserved");
            let count = (2 * n - 1) as usize;
            *out = Some(WorkingTree::from_lbvh(
                Bvh {
                    nodes: read_buffer(ctx, &s.nodes, count)?,
                    prim_indices: read_buffer(ctx, &s.order, n as usize)?,
                },
                read_buffer(ctx, self.lbvh.parents().expect("built"), count)?,
            ));
        }
        tree.reserve(ctx, 2 * n - 1, n)?;
        self.collapse.reserve(ctx, n)?;
        let gammas = self.settings.gammas();
        let phases = self.settings.phases.filter(|_| gammas[0] != u32::MAX);
        self.rounds.reserve(ctx, n, &gammas, phases.is_some())?;
        if phases.is_some() {
            self.phased.reserve(ctx, n)?;
        }
        let scratch = self.scratch.as_ref().expect("reserved");
        let mut state = TreeletState {
            nodes: &scratch.nodes,
            prim_boxes: self.lbvh.prim_boxes().expect("reserved"),
            keys: self.lbvh.keys().expect("reserved"),
            order: &scratch.order,
            parents: self.lbvh.parents().expect("built"),
            prim_counts: &scratch.prim_counts,
            costs: &scratch.costs,
            levels: &scratch.levels[0],
            next_levels: &scratch.levels[1],
            arrivals: &scratch.arrivals,
            schedule: &scratch.schedule,
            waves: &scratch.waves,
        };
        let model = CostModel::from(&self.sah);
        let treelet_size = self.settings.treelet_size;
        let settings = self.settings;
        let round = |r: usize| Round {
            model,
            treelet_size: settings.round_size(r),
            gamma: gammas[r],
            next_gamma: gammas.get(r + 1).copied().unwrap_or(u32::MAX),
            levels_only: r > 0,
        };
        // The first round's schedule climbs the LBVH and counts arrivals.
        rec.encoder().clear_buffer(&scratch.arrivals, 0, None);
        let overlap = self
            .rounds
            .schedule
            .overlap
            .filter(|_| gammas[0] != u32::MAX);
        match (phases, overlap) {
            (Some(phases), _) => {
                // The first round's schedule builds the LBVH with its counts and costs only (γ =
                // u32::MAX: no levels or roots, which the phases find for themselves); then every
                // round phase by phase.
                rec.encoder().clear_buffer(&scratch.schedule, 0, None);
                let mut pass = rec.pass("treelets");
                let lbvh = Round {
                    gamma: u32::MAX,
                    ..round(0)
                };
                self.rounds
                    .record_levels(&mut pass, ctx, count, &state, &lbvh, 0);
                drop(pass);
                for r in 0..gammas.len() {
                    rec.encoder().clear_buffer(&scratch.schedule, 0, None);
                    let phases = settings.round_phases(r).unwrap_or(phases);
                    self.phased
                        .record(rec, count, &state, &self.rounds, &round(r), phases);
                }
            }
            (None, Some(reach)) => {
                // The first round's schedule (with the LBVH), then every round in waves.
                rec.encoder().clear_buffer(&scratch.schedule, 0, None);
                let rounds = gammas.len() as u32;
                self.waves.reserve(ctx, n, rounds)?;
                let levels = self.rounds.dispatched(n, gammas[0], ctx.info.device_type);
                let mut pass = rec.pass("treelets");
                self.rounds
                    .record_levels(&mut pass, ctx, count, &state, &round(0), levels.max(1));
                drop(pass);
                let overlap = Overlap {
                    model,
                    treelet_size,
                    rounds,
                    reach,
                    dispatched: levels * rounds,
                    dp: self.rounds.schedule.dp(),
                    climb_dp: self.rounds.schedule.climb_dp(),
                    team_below: self.rounds.schedule.team_below(),
                    climb_team_below: self.rounds.schedule.climb_team_below(),
                };
                self.waves.record(
                    rec,
                    n,
                    &state,
                    self.rounds.roots(),
                    self.rounds.subsets(),
                    &overlap,
                );
            }
            (None, None) => {
                for r in 0..gammas.len() {
                    rec.encoder().clear_buffer(&scratch.schedule, 0, None);
                    state.levels = &scratch.levels[r % 2];
                    state.next_levels = &scratch.levels[(r + 1) % 2];
                    self.rounds.record(rec, count, &state, &round(r));
                }
            }
        }
        let mut pass = rec.pass("collapse");
        let out = CollapseBuffers {
            flags: &scratch.flags,
            scans: &scratch.scans,
            leaf_slots: &scratch.leaf_slots,
            out_nodes: &tree.nodes,
            out_prims: &tree.prim_indices,
            tree_counts: &tree.counts,
            ref_tris: split_total
                .is_some()
                .then(|| self.presplit.as_ref().and_then(PreSplitter::ref_tris))
                .flatten(),
        };
        self.collapse
            .record(&mut pass, count, &scratch.order, &state, &model, &out)
    }

    /// Grows the working tree's scratch to `n` leaves.
    fn reserve(&mut self, ctx: &GpuContext, n: u32) -> Result<&Scratch> {
        if self.scratch.as_ref().is_none_or(|s| s.capacity < n) {
            self.scratch = None;
            self.scratch = Some(Scratch::new(ctx, n)?);
        }
        Ok(self.scratch.as_ref().expect("allocated above"))
    }
}
