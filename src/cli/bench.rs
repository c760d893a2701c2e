//! `treelet bench`: for each requested builder and layout, build (and convert, for the wide
//! layout), validate, measure SAH and tree bytes and trace diffuse paths; print one JSON object per
//! line. Every timed series (builds, traces) follows a warm-up by time,
//! so that a real GPU runs at full clocks, and is reported as min / median / max. GPU builders run
//! before the CPU builders of the same scene (a long CPU build lets the GPU clock down).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;
use treelet::anim::load_still;
use treelet::bvh::treelet::{
    RootSlots, RoundSchedule, TreeletDp, MAX_LEVEL_DISPATCHES, MAX_SUBTREE_LEVELS, SUBTREE_LIST,
};
use treelet::bvh::wide::{
    validate_wide, validate_wide_with_references, wide_sah_costs, Layout, WideCollapse,
    WideOptions, MAX_WIDE_LEVEL_DISPATCHES,
};
use treelet::bvh::{
    sah_cost, tunes_by_default, validate, validate_with_references, write_bvh, write_wide_bvh,
    Builder, SchedulePins, TunedSchedule, TuningOptions,
};
use treelet::gpu::{aggregate_stages, check_climb_width, GpuContext, Spread, Timing, Warmup};
use treelet::scene::Triangle;
use treelet::sort::check_tile_items;
use treelet::trace::{PathTracer, TraceStats};
use treelet::Result;

use super::{
    builder_names, or_default, parse_builder, refuse_treelet_options, TraceArgs, TuneSchedule,
};

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    trace: TraceArgs,
    /// BVH builders to measure (comma-separated)
    #[arg(long, default_value = "sweep", value_delimiter = ',', value_parser = parse_builder)]
    builder: Vec<Builder>,
    /// Print JSON lines (the default and only format for now; kept for scripts that pass it)
    #[arg(long)]
    json: bool,
    /// Untimed runs (at least) before each timed build series and each timed trace series
    #[arg(long, default_value_t = 1)]
    warmup: u32,
    /// Untimed GPU work before each timed build series and each timed trace series, in ms of
    /// wall-clock time: an idle GPU needs ~0.1-0.5 s of work to reach full clocks
    #[arg(long, default_value_t = 500.0, value_parser = parse_warmup_ms)]
    warmup_ms: f64,
    /// Write each built tree to this file in the layout traced (formats in the README; with
    /// several builders or layouts their labels are added to the file name)
    #[arg(long)]
    export_bvh: Option<PathBuf>,
    /// Timed builds per GPU builder and timed traces per builder (min, median and max are reported)
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(1..))]
    repeats: u32,
    /// Treelet levels per round given a dispatch of their own, the rest climbed by one workgroup
    /// (trbvh, trbvh-split; default: from the tree's size); a comma-separated list to compare.
    /// The tree is the same for every value
    #[arg(long, value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_LEVEL_DISPATCHES)))]
    level_dispatches: Vec<u32>,
    /// Dispatched treelet levels of fewer treelets than this are optimized by teams of 32
    /// invocations, a workgroup per treelet, the others one treelet per invocation (trbvh,
    /// trbvh-split; default: 0, never; with --round-overlap, its dispatched waves); a
    /// comma-separated list to compare. The tree is the same for every value
    #[arg(long, value_delimiter = ',')]
    team_below: Vec<u32>,
    /// The same for the climb's waves, which its four teams take a treelet each at a time: waves
    /// of fewer treelets than this and than 32 (default: 0, never); a comma-separated list to
    /// compare. The tree is the same for every value
    #[arg(long, value_delimiter = ',')]
    climb_team_below: Vec<u32>,
    /// How a lone invocation writes the treelet DP: unrolled (every subset and partition written
    /// out; the default) or loop (trbvh, trbvh-split); a comma-separated list to compare. The
    /// tree is the same for both
    #[arg(long, value_delimiter = ',', value_enum)]
    treelet_dp: Vec<DpForm>,
    /// The same for the climbed top levels only, whose waves hold a few treelets each (default:
    /// as --treelet-dp); a comma-separated list to compare. The tree is the same for both
    #[arg(long, value_delimiter = ',', value_enum)]
    climb_dp: Vec<DpForm>,
    /// The treelet rounds overlapped in waves: each round starts on a root once it and its
    /// ancestors this many levels up are done in the round before (6: the trees of the rounds
    /// one after another on every scene measured; README, "Rounds can overlap"), or none (the
    /// default: one round after another); trbvh, trbvh-split; a comma-separated list to compare
    #[arg(long, value_delimiter = ',')]
    round_overlap: Vec<Reach>,
    /// Treelet levels per round optimized per subtree, 0-8: one dispatch, a workgroup per few
    /// subtrees holding them, instead of a dispatch per level (default: 0, none; not with
    /// --round-overlap); trbvh, trbvh-split; a comma-separated list to compare. The tree is the
    /// same for every value
    #[arg(long, value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_SUBTREE_LEVELS)))]
    subtree_levels: Vec<u32>,
    /// With --subtree-levels: how many subtrees a workgroup takes, at most this >> (l − 1) of
    /// level l (and as many as its list of 1024 roots holds, at most 32): 32 keeps a workgroup's
    /// steps near its subtrees' depths (latency), 1024 fills the list (throughput; default: 128
    /// on GPUs, 1024 on CPU devices); a comma-separated list to compare. The tree is the same for
    /// every value
    #[arg(long, value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(1..=i64::from(SUBTREE_LIST)))]
    subtree_width: Vec<u32>,
    /// How the phased rounds' roots take their slots in a phase's bucket: workgroup (one device
    /// atomic per workgroup, between two workgroup barriers; the default on GPUs) or root (one per
    /// root, no barrier; the default on CPU devices); trbvh, trbvh-split with --phases or the
    /// phased preset; a comma-separated list to compare. The tree is the same for both
    #[arg(long, value_delimiter = ',', value_enum)]
    root_slots: Vec<RootSlotsArg>,
    /// Tune the build schedule on this device and scene after the warm-up and before the timed
    /// builds: the options above, --sort-tile-items and --wide-level-dispatches, where they are
    /// not given, are varied one at a time from their defaults (every schedule builds the same
    /// tree, which the tuning checks) and the fastest schedule is kept and timed;
    /// `schedule_tuning` in the JSON lists the trials. auto (the default): on GPUs when none of
    /// those options is given, off on CPU devices (where a tuning takes minutes); on; off. GPU
    /// builders
    #[arg(long, value_enum, default_value_t = TuneSchedule::Auto)]
    tune_schedule: TuneSchedule,
    /// Builds of each schedule per comparison of a tuning (alternating with the schedule kept)
    #[arg(long, default_value_t = TuningOptions::default().pairs,
          value_parser = clap::value_parser!(u32).range(1..))]
    tune_pairs: u32,
    /// Levels of the wide conversion below the root's dispatch given an indirect dispatch of
    /// their own, 0-32, the subtrees below emitted by one more dispatch (wide layout; default:
    /// log2 of the references + 2); a comma-separated list to compare. The tree is the same for
    /// every value
    #[arg(long, value_delimiter = ',',
          value_parser = clap::value_parser!(u32).range(0..=i64::from(MAX_WIDE_LEVEL_DISPATCHES)))]
    wide_level_dispatches: Vec<u32>,
    /// Time every dispatch on its own (each in a compute pass of its own, which may cost a little
    /// more than the passes of a normal build) and list them in `dispatch_ms`
    #[arg(long)]
    pub(super) profile_dispatches: bool,
    /// Keys per invocation of the radix sort's tiles, 8, 16 or 32 (tiles of 2048, 4096 or 8192
    /// keys; default: from the key count on GPUs, 32 on CPU devices). The trees are the same
    #[arg(long, value_parser = parse_sort_tile_items)]
    pub(super) sort_tile_items: Option<u32>,
    /// Workgroup width of the bottom-up climbs (lbvh_climb, the first treelet round's
    /// nodes_level, nodes_refit): 8, 16, 32, 64, 128 or 256 (default: 64 on GPUs, 8 on CPU
    /// devices). The trees are the same
    #[arg(long, value_parser = parse_climb_width)]
    pub(super) climb_width: Option<u32>,
}

/// `bench --treelet-dp`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum DpForm {
    Unrolled,
    Loop,
}

impl From<DpForm> for TreeletDp {
    fn from(form: DpForm) -> Self {
        match form {
            DpForm::Unrolled => TreeletDp::Unrolled,
            DpForm::Loop => TreeletDp::Loop,
        }
    }
}

/// `bench --root-slots`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
enum RootSlotsArg {
    Workgroup,
    Root,
}

impl From<RootSlotsArg> for RootSlots {
    fn from(slots: RootSlotsArg) -> Self {
        match slots {
            RootSlotsArg::Workgroup => RootSlots::Workgroup,
            RootSlotsArg::Root => RootSlots::Root,
        }
    }
}

/// A `--round-overlap` value: a reach, or none.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Reach(Option<u32>);

impl std::str::FromStr for Reach {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        match s {
            "none" => Ok(Self(None)),
            _ => s
                .parse()
                .map(|reach| Self(Some(reach)))
                .map_err(|_| format!("'{s}' is neither a number of levels nor none")),
        }
    }
}

impl BenchArgs {
    /// Every combination of the requested round schedules (the default where none is given);
    /// fails when one is given but no builder has treelets to schedule.
    fn schedules(&self, builders: &[Builder]) -> Result<Vec<RoundSchedule>> {
        refuse_treelet_options(
            builders,
            &[
                ("--level-dispatches", !self.level_dispatches.is_empty()),
                ("--team-below", !self.team_below.is_empty()),
                ("--climb-team-below", !self.climb_team_below.is_empty()),
                ("--treelet-dp", !self.treelet_dp.is_empty()),
                ("--climb-dp", !self.climb_dp.is_empty()),
                ("--round-overlap", !self.round_overlap.is_empty()),
                ("--subtree-levels", !self.subtree_levels.is_empty()),
                ("--subtree-width", !self.subtree_width.is_empty()),
                ("--root-slots", !self.root_slots.is_empty()),
            ],
        )?;
        // No `--round-overlap` and `none` both mean one round after another.
        let overlaps: Vec<Option<u32>> = or_default(&self.round_overlap)
            .into_iter()
            .map(|reach| reach.and_then(|r| r.0))
            .collect();
        let mut schedules = Vec::new();
        for level_dispatches in or_default(&self.level_dispatches) {
            for (team_below, climb_team_below) in pairs(
                &or_default(&self.team_below),
                &or_default(&self.climb_team_below),
            ) {
                for dp in or_default(&self.treelet_dp) {
                    for climb_dp in or_default(&self.climb_dp) {
                        for &overlap in &overlaps {
                            for subtree_levels in or_default(&self.subtree_levels) {
                                for subtree_width in or_default(&self.subtree_width) {
                                    for root_slots in or_default(&self.root_slots) {
                                        schedules.push(RoundSchedule {
                                            level_dispatches,
                                            team_below,
                                            climb_team_below,
                                            dp: dp.map(TreeletDp::from),
                                            climb_dp: climb_dp.map(TreeletDp::from),
                                            overlap,
                                            subtree_levels,
                                            subtree_width,
                                            root_slots: root_slots.map(RootSlots::from),
                                        });
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        Ok(schedules)
    }

    /// The tuning of the GPU builders' build schedules (None: they are timed as given): the
    /// dimensions set by an option stay as given. `--tune-schedule on` is refused when no
    /// builder runs on the GPU.
    fn tuning(&self, gpu: &GpuContext, builders: &[Builder]) -> Result<Option<TuningOptions>> {
        if self.tune_schedule == TuneSchedule::On && !builders.iter().any(|b| b.is_gpu()) {
            return Err(treelet::Error::InvalidArgument(format!(
                "--tune-schedule on does not apply to builder {}: only GPU builders have a \
                 build schedule",
                builder_names(builders)
            )));
        }
        let pins = SchedulePins {
            overlap: !self.round_overlap.is_empty(),
            subtree_levels: !self.subtree_levels.is_empty(),
            subtree_width: !self.subtree_width.is_empty(),
            dp: !self.treelet_dp.is_empty(),
            climb_dp: !self.climb_dp.is_empty(),
            team_below: !self.team_below.is_empty(),
            climb_team_below: !self.climb_team_below.is_empty(),
            level_dispatches: !self.level_dispatches.is_empty(),
            root_slots: !self.root_slots.is_empty(),
            sort_tile_items: self.sort_tile_items.is_some(),
            wide_level_dispatches: !self.wide_level_dispatches.is_empty(),
        };
        let tune = match self.tune_schedule {
            TuneSchedule::On => true,
            TuneSchedule::Off => false,
            TuneSchedule::Auto => tunes_by_default(gpu) && pins == SchedulePins::default(),
        };
        Ok(tune.then_some(TuningOptions {
            pairs: self.tune_pairs,
            pins,
            ..TuningOptions::default()
        }))
    }

    /// The wide conversion's level dispatch counts asked for (None: the default), refused
    /// without the wide layout, to which they apply.
    fn wide_level_dispatches(&self, layouts: &[Layout]) -> Result<Vec<Option<u32>>> {
        if !self.wide_level_dispatches.is_empty() && !layouts.contains(&Layout::Wide) {
            return Err(treelet::Error::InvalidArgument(
                "--wide-level-dispatches applies to the wide layout (add --layout wide)".into(),
            ));
        }
        Ok(or_default(&self.wide_level_dispatches))
    }
}

/// Every pair of a value of `a` and one of `b`.
fn pairs<T: Copy>(a: &[T], b: &[T]) -> Vec<(T, T)> {
    a.iter()
        .flat_map(|&x| b.iter().map(move |&y| (x, y)))
        .collect()
}

fn parse_warmup_ms(s: &str) -> std::result::Result<f64, String> {
    let ms: f64 = s.parse().map_err(|e| format!("{e}"))?;
    if ms.is_finite() && ms >= 0.0 {
        Ok(ms)
    } else {
        Err(format!(
            "must be a non-negative number of milliseconds, got {s}"
        ))
    }
}

#[derive(Serialize)]
struct BenchRecord {
    scene: String,
    builder: &'static str,
    /// The node layout traced: binary, or wide (converted from the binary tree, stage "wide").
    layout: &'static str,
    treelet_size: Option<u32>,
    rounds: Option<u32>,
    /// Treelet builders with rounds: the last round's treelet size in effect.
    last_round_size: Option<u32>,
    /// Treelet builders: the phases per round (`--phases`; null: bottom-up, the paper's order).
    phases: Option<u32>,
    /// Treelet builders with phased rounds: the first round's phases in effect.
    first_round_phases: Option<u32>,
    split_budget: Option<f64>,
    /// Treelet builders: the levels per round given a dispatch (null: from the tree's size, per
    /// round) and the team thresholds in effect in the dispatched levels and in the climb.
    level_dispatches: Option<u32>,
    team_below: Option<u32>,
    climb_team_below: Option<u32>,
    /// Treelet builders: the lone invocation's DP form in effect in the dispatched levels
    /// (`--treelet-dp`) and in the climb (`--climb-dp`).
    treelet_dp: Option<&'static str>,
    climb_dp: Option<&'static str>,
    /// Treelet builders: the rounds' overlap reach (`--round-overlap`; null: one round after
    /// another).
    round_overlap: Option<u32>,
    /// Treelet builders: the levels per round optimized per subtree (`--subtree-levels`; 0:
    /// none).
    subtree_levels: Option<u32>,
    /// Treelet builders with subtrees: the subtree width in effect (`--subtree-width`).
    subtree_width: Option<u32>,
    /// Treelet builders with phased rounds: how their roots take their slots (`--root-slots`).
    root_slots: Option<&'static str>,
    /// GPU builders whose schedule was tuned (`--tune-schedule`): the tuning, whose kept
    /// schedule is the one in the schedule fields (these and `sort_tile_items`,
    /// `wide_level_dispatches`) and timed here.
    schedule_tuning: Option<TuningRecord>,
    /// The radix sort's keys per invocation asked for or kept by a tuning (null: chosen per
    /// sort).
    sort_tile_items: Option<u32>,
    /// GPU builders: the Morton key bits sorted (`lbvh`'s depend on the triangle count).
    key_bits: Option<u32>,
    /// The climbs' workgroup width in effect.
    climb_width: u32,
    adapter: String,
    /// The adapter's device type (DiscreteGpu, IntegratedGpu, VirtualGpu, Cpu, Other): CPU
    /// devices keep CPU defaults and do not tune by default.
    device_type: String,
    triangles: usize,
    /// Triangle references in the leaves: the triangle count, plus the pieces of split
    /// triangles that ended up in different leaves (sbvh, trbvh-split).
    references: usize,
    /// Binary tree: nodes and leaves; wide layout: wide nodes and leaf children.
    nodes: usize,
    leaves: usize,
    /// Bytes of the traced layout's nodes and references.
    tree_bytes: usize,
    /// Bytes of the triangles the traversal tests besides the scene's: the wide layout's copy of
    /// its references' triangles in leaf order (48 bytes each); 0 for the binary layout.
    leaf_triangle_bytes: usize,
    /// Timed runs of each series, and the warm-up asked for before each.
    repeats: u32,
    warmup_ms: f64,
    /// The median build.
    build_ms: f64,
    build_ms_spread: Spread,
    build_warmup: Warmup,
    build_wall_ms: f64,
    mtris_per_s: f64,
    /// Per stage, of the median build.
    stages_ms: BTreeMap<String, Option<f64>>,
    /// Compute dispatches per GPU stage of a build, and in all (on a real GPU each costs a fixed
    /// few microseconds besides its work).
    stages_dispatches: BTreeMap<String, u32>,
    dispatches: u32,
    /// With --profile-dispatches: every dispatch of the median build, in order.
    #[serde(skip_serializing_if = "Option::is_none")]
    dispatch_ms: Option<Vec<DispatchTime>>,
    /// SAH of the binary tree.
    sah: f32,
    /// Wide layout: the conversion's collapse (`--wide-collapse`: optimal or greedy).
    wide_collapse: Option<&'static str>,
    /// Wide layout: the level dispatches asked for (`--wide-level-dispatches`) or kept by a
    /// tuning (null: from the tree's size).
    wide_level_dispatches: Option<u32>,
    /// Wide layout: SAH of the traced wide tree (of its collapse, `wide_collapse`) and of the
    /// SAH-optimal collapse of the same binary tree (Ylitie et al.'s DP).
    wide_sah: Option<f64>,
    wide_sah_optimal: Option<f64>,
    /// Wide layout: levels of the traced wide tree (the GPU conversion emits a level per step:
    /// the level dispatches past them find no work).
    wide_levels: Option<usize>,
    valid: bool,
    width: u32,
    height: u32,
    spp: u32,
    max_depth: u32,
    rays: u64,
    /// The median trace.
    trace_ms: Option<f64>,
    trace_ms_spread: Option<Spread>,
    trace_warmup: Warmup,
    trace_wall_ms: f64,
    mrays_per_s: Option<f64>,
    mrays_per_s_spread: Option<Spread>,
    /// The traversal steps of the same rays, counted in one more trace: exact on any device
    /// (however noisy its timing), so two trees or layouts compare by them.
    steps: Option<StepsRecord>,
}

/// Traversal steps in the JSON: internal nodes whose children's boxes were tested (a binary
/// node's two, a wide node's eight) and triangles tested, in all and per ray.
#[derive(Serialize)]
struct StepsRecord {
    nodes: u64,
    triangles: u64,
    nodes_per_ray: f64,
    triangles_per_ray: f64,
}

/// A schedule tuning in the JSON: the schedule kept (labelled by what differs from the defaults),
/// the tuning's builds and wall-clock time, and every trial in order.
#[derive(Serialize)]
struct TuningRecord {
    kept: String,
    builds: u32,
    wall_ms: f64,
    trials: Vec<TrialRecord>,
}

/// A trial of a tuning: the candidate schedule (as in run labels), the median builds of the
/// schedule kept at the time and of the candidate over the same pairs (null: not timed), whether
/// it built another tree or its build failed (refused: `other_tree`, `error`) and whether it was
/// kept.
#[derive(Serialize)]
struct TrialRecord {
    schedule: String,
    kept_ms: Option<f64>,
    candidate_ms: Option<f64>,
    other_tree: bool,
    error: Option<String>,
    adopted: bool,
}

impl From<&TunedSchedule> for TuningRecord {
    fn from(tuned: &TunedSchedule) -> Self {
        Self {
            kept: tuned.schedule.label(),
            builds: tuned.builds,
            wall_ms: tuned.wall_ms,
            trials: tuned
                .trials
                .iter()
                .map(|t| TrialRecord {
                    schedule: t.candidate.label(),
                    kept_ms: t.kept_ms,
                    candidate_ms: t.candidate_ms,
                    other_tree: t.other_tree,
                    error: t.error.clone(),
                    adopted: t.adopted,
                })
                .collect(),
        }
    }
}

/// A radix sort tile's keys per invocation: one of `SORT_TILE_ITEMS`.
fn parse_sort_tile_items(value: &str) -> std::result::Result<u32, String> {
    let items = value.parse().map_err(|e| format!("{e}"))?;
    check_tile_items(items).map_err(|e| e.to_string())
}

/// A climb's workgroup width: one of `CLIMB_WIDTHS`.
fn parse_climb_width(value: &str) -> std::result::Result<u32, String> {
    let width = value.parse().map_err(|e| format!("{e}"))?;
    check_climb_width(width).map_err(|e| e.to_string())
}

/// One dispatch of a build timed on its own: its stage, kernel and GPU time.
#[derive(Serialize)]
struct DispatchTime {
    stage: String,
    kernel: &'static str,
    ms: Option<f64>,
}

pub fn run(gpu: &GpuContext, args: &BenchArgs) -> Result<()> {
    let scene = load_still(&args.trace.scene)?;
    let params = args.trace.sah_params()?;
    let mut builders = args.trace.builder_variants(&args.builder)?;
    builders.sort_by_key(|b| !b.is_gpu());
    let timing = Timing {
        warmup_ms: args.warmup_ms,
        warmup_runs: args.warmup,
        repeats: args.repeats,
    };
    let layouts = &args.trace.layout;
    let collapses = args.trace.wide_collapses()?;
    let schedules = args.schedules(&builders)?;
    let wide_level_dispatches = args.wide_level_dispatches(layouts)?;
    let tuning = args.tuning(gpu, &builders)?;
    // The binary layout once, the wide layout once per collapse and level dispatch count.
    let layout_runs: Vec<(Layout, WideOptions)> = layouts
        .iter()
        .flat_map(|&l| match l {
            Layout::Binary => vec![(l, WideOptions::default())],
            Layout::Wide => collapses
                .iter()
                .flat_map(|&collapse| {
                    wide_level_dispatches.iter().map(move |&level_dispatches| {
                        let wide = WideOptions {
                            collapse,
                            level_dispatches,
                        };
                        (l, wide)
                    })
                })
                .collect(),
        })
        .collect();
    let runs: Vec<(Builder, RoundSchedule, Layout, WideOptions)> = builders
        .iter()
        .flat_map(|&b| {
            let schedules = match b.treelet_settings() {
                Some(_) => schedules.clone(),
                None => vec![RoundSchedule::default()],
            };
            let layout_runs = &layout_runs;
            schedules
                .into_iter()
                .flat_map(move |s| layout_runs.iter().map(move |&(l, c)| (b, s, l, c)))
        })
        .collect();
    // Refused before any run, not after the runs before it.
    for &(builder, schedule, _, _) in &runs {
        if let Some(settings) = builder.treelet_settings() {
            schedule.check(settings.treelet_size)?;
        }
    }
    for &(builder, schedule, layout, wide_options) in &runs {
        let (geometry, tree, report) = builder.build(
            gpu,
            &scene,
            &params,
            &timing,
            layout,
            wide_options,
            schedule,
            tuning.as_ref(),
        )?;
        // The schedule timed: the tuned one where the schedule was tuned.
        let tuned = report.tuned.as_ref().map(|t| t.schedule);
        let schedule = tuned.map_or(schedule, |t| t.rounds);
        let sort_tile_items = tuned
            .and_then(|t| t.sort_tile_items)
            .or(gpu.sort_tile_items);
        let wide_level_dispatches = match tuned {
            Some(t) => t.wide_level_dispatches,
            None => wide_options.level_dispatches,
        };
        let bvh = tree.download(gpu)?;
        let collapse = wide_options.collapse;
        let optimal = collapse == WideCollapse::Optimal;
        let label = run_label(builder, schedule, layout, wide_options);
        let references = builder.duplicates_references();
        let mut wide_levels = None;
        let (validation, nodes, leaves, tree_bytes, leaf_triangle_bytes) = match &tree.wide {
            None => {
                let validation = if references {
                    validate_with_references(&bvh, &scene.triangles)
                } else {
                    validate(&bvh, &scene.triangles)
                };
                let bytes =
                    std::mem::size_of_val(bvh.nodes.as_slice()) + 4 * bvh.prim_indices.len();
                (validation, bvh.nodes.len(), bvh.leaf_count(), bytes, 0)
            }
            Some(wide) => {
                let wide = wide.download(gpu)?;
                let validation = if references {
                    validate_wide_with_references(&wide, &scene.triangles)
                } else {
                    validate_wide(&wide, &scene.triangles)
                };
                if let Some(path) = &args.export_bvh {
                    let path = export_path(path, &label, runs.len());
                    write_wide_bvh(&path, &wide, scene.triangles.len() as u32)?;
                    log::info!("wrote {}", path.display());
                }
                wide_levels = Some(wide.levels());
                (
                    validation,
                    wide.nodes.len(),
                    wide.leaf_count(),
                    wide.bytes(),
                    wide.prim_indices.len() * std::mem::size_of::<Triangle>(),
                )
            }
        };
        if let Err(e) = &validation {
            log::error!("{label} tree of {} is invalid: {e}", scene.name);
        }
        if let (Some(path), None) = (&args.export_bvh, &tree.wide) {
            let path = export_path(path, &label, runs.len());
            write_bvh(&path, &bvh, scene.triangles.len() as u32)?;
            log::info!("wrote {}", path.display());
        }
        let wide_sah = tree.wide.is_some().then(|| wide_sah_costs(&bvh, &params));
        let mut tracer = PathTracer::new(gpu, args.trace.render_settings(layout))?;
        let trace = |tracer: &mut PathTracer| {
            tracer.reset();
            tracer.trace(
                gpu,
                &geometry,
                &tree,
                &scene.camera,
                scene.sky,
                args.trace.spp,
            )
        };
        let trace_warmup = timing.warm_up(|| trace(&mut tracer).map(drop))?;
        let mut traces = Vec::new();
        for _ in 0..timing.repeats {
            traces.push(trace(&mut tracer)?);
        }
        let trace_ms: Option<Vec<f64>> = traces.iter().map(|t| t.trace_ms).collect();
        let mrays: Option<Vec<f64>> = traces.iter().map(TraceStats::mrays_per_s).collect();
        let stats = median_trace(traces);
        // The same rays once more, their traversal steps counted (a pipeline of its own, untimed).
        tracer.set_count_steps(true);
        let counted = trace(&mut tracer)?;
        if counted.rays != stats.rays {
            log::warn!(
                "{label}: the counting trace traced {} rays, the timed ones {}",
                counted.rays,
                stats.rays
            );
        }
        let per_ray = |count: u64| count as f64 / counted.rays.max(1) as f64;
        let steps = counted.steps.map(|s| StepsRecord {
            nodes: s.nodes,
            triangles: s.triangles,
            nodes_per_ray: per_ray(s.nodes),
            triangles_per_ray: per_ray(s.triangles),
        });
        let dispatch_ms = args.profile_dispatches.then(|| {
            report
                .stages
                .iter()
                .filter_map(|s| {
                    s.kernel.map(|kernel| DispatchTime {
                        stage: s.label.clone(),
                        kernel,
                        ms: s.ms,
                    })
                })
                .collect()
        });
        let stages = aggregate_stages(report.stages);
        let record = BenchRecord {
            scene: scene.name.clone(),
            builder: builder.name(),
            layout: layout.name(),
            treelet_size: builder.treelet_settings().map(|s| s.treelet_size),
            rounds: builder.treelet_settings().map(|s| s.rounds),
            last_round_size: builder
                .treelet_settings()
                .and_then(|s| s.last_round_treelets()),
            phases: builder.treelet_settings().and_then(|s| s.phases),
            first_round_phases: builder.treelet_settings().and_then(|s| s.round_phases(0)),
            split_budget: builder
                .treelet_settings()
                .map(|s| f64::from(s.split_percent) / 100.0),
            level_dispatches: schedule.level_dispatches,
            team_below: builder.treelet_settings().map(|_| schedule.team_below()),
            climb_team_below: builder
                .treelet_settings()
                .map(|_| schedule.climb_team_below()),
            treelet_dp: builder.treelet_settings().map(|_| schedule.dp().name()),
            climb_dp: builder
                .treelet_settings()
                .map(|_| schedule.climb_dp().name()),
            round_overlap: schedule.overlap,
            subtree_levels: builder
                .treelet_settings()
                .map(|_| schedule.subtree_levels()),
            subtree_width: builder
                .treelet_settings()
                .filter(|_| schedule.subtree_levels() > 0)
                .map(|_| schedule.subtree_width(gpu.info.device_type)),
            root_slots: builder
                .treelet_settings()
                .filter(|s| s.phases.is_some())
                .map(|_| schedule.root_slots(gpu.info.device_type).name()),
            schedule_tuning: report.tuned.as_ref().map(TuningRecord::from),
            sort_tile_items,
            key_bits: builder.morton_key_bits(scene.triangles.len() as u32),
            climb_width: gpu.climb_width(),
            adapter: gpu.adapter_description(),
            device_type: format!("{:?}", gpu.info.device_type),
            triangles: scene.triangles.len(),
            references: bvh.prim_indices.len(),
            nodes,
            leaves,
            tree_bytes,
            leaf_triangle_bytes,
            repeats: timing.repeats,
            warmup_ms: timing.warmup_ms,
            build_ms: report.build_ms,
            build_ms_spread: Spread::of(&report.builds_ms).expect("at least one timed build"),
            build_warmup: report.warmup,
            build_wall_ms: report.wall_ms,
            mtris_per_s: scene.triangles.len() as f64 / (report.build_ms * 1e3),
            stages_ms: stages.iter().map(|s| (s.label.clone(), s.ms)).collect(),
            stages_dispatches: stages
                .iter()
                .filter(|s| s.dispatches > 0)
                .map(|s| (s.label.clone(), s.dispatches))
                .collect(),
            dispatches: stages.iter().map(|s| s.dispatches).sum(),
            dispatch_ms,
            sah: sah_cost(&bvh, &params),
            wide_collapse: (layout == Layout::Wide).then_some(collapse.name()),
            wide_level_dispatches,
            wide_sah: wide_sah.map(|c| if optimal { c.1 } else { c.0 }),
            wide_sah_optimal: wide_sah.map(|c| c.1),
            wide_levels,
            valid: validation.is_ok(),
            width: args.trace.width,
            height: args.trace.height,
            spp: stats.samples,
            max_depth: args.trace.max_depth,
            rays: stats.rays,
            trace_ms: stats.trace_ms,
            trace_ms_spread: trace_ms.and_then(|v| Spread::of(&v)),
            trace_warmup,
            trace_wall_ms: stats.wall_ms,
            mrays_per_s: stats.mrays_per_s(),
            mrays_per_s_spread: mrays.and_then(|v| Spread::of(&v)),
            steps,
        };
        println!(
            "{}",
            serde_json::to_string(&record).expect("record serializes")
        );
    }
    Ok(())
}

/// A run's label in logs and export file names: the builder's, the schedule where one was given,
/// the layout (and the wide layout's collapse).
fn run_label(
    builder: Builder,
    schedule: RoundSchedule,
    layout: Layout,
    wide: WideOptions,
) -> String {
    let mut label = builder.label();
    if schedule != RoundSchedule::default() {
        label += &format!(" {}", schedule.label());
    }
    match (layout, wide.level_dispatches) {
        (Layout::Binary, _) => format!("{label} binary"),
        (Layout::Wide, None) => format!("{label} wide {}", wide.collapse.name()),
        (Layout::Wide, Some(levels)) => {
            format!("{label} wide {} wd={levels}", wide.collapse.name())
        }
    }
}

/// The trace of median throughput (GPU time where timestamps exist, wall-clock time otherwise).
fn median_trace(mut traces: Vec<TraceStats>) -> TraceStats {
    let key = |t: &TraceStats| {
        t.mrays_per_s()
            .unwrap_or(t.rays as f64 / t.wall_ms.max(1e-9))
    };
    traces.sort_by(|a, b| key(a).total_cmp(&key(b)));
    traces.swap_remove(traces.len() / 2)
}

/// The export file of a run: `path` itself when it is the only run, else labelled.
fn export_path(path: &Path, label: &str, runs: usize) -> PathBuf {
    if runs > 1 {
        labelled_path(path, label)
    } else {
        path.to_path_buf()
    }
}

/// `out.bvh` + "trbvh n=7 r=3" -> `out-trbvh-n7-r3.bvh`.
fn labelled_path(path: &Path, label: &str) -> PathBuf {
    let tag: String = label
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            ',' => Some('_'),
            '=' => None,
            c => Some(c),
        })
        .collect();
    let stem = path
        .file_stem()
        .map_or("tree".into(), |s| s.to_string_lossy());
    let ext = path
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!("{stem}-{tag}{ext}"))
}
