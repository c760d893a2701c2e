//! Build-schedule tuning. A build's schedule (`BuildSchedule`: the treelet rounds' —
//! `RoundSchedule`: the rounds one after another, overlapped or with their lowest levels per
//! subtree, the lone DP's form in the dispatched levels and in the climb, the team thresholds of
//! both, the levels given a dispatch; for the phased rounds the DP's form, the team threshold and
//! how a phase's roots take their slots — the radix sort's tile and the wide conversion's level
//! dispatches) never changes the tree (tests), so it
//! sets only the build's time, and which one is fastest depends on the device and the tree.
//! `tune_schedule` finds it where the build runs: a coordinate descent from a starting schedule
//! over the dimensions that apply (`TuningSpace`) and that the caller left free; each alternative
//! is first built once (compiling its kernels) and refused unless its tree is the starting
//! schedule's (on a device where it is not, a schedule has a bug: the tuner logs it and never
//! keeps it), then timed in alternation with the schedule kept so far (pairs of builds, so that a
//! change of clocks hits both) and kept when it is faster pair by pair: by a margin in the median
//! ratio, and in four pairs of five.
//! `DeviceTrials` runs the trials on the GPU through a `TreeUpdater`. Not from the paper, whose
//! schedule is one (§4): the README's "Schedule tuning" says what it varies and why.

use std::time::Instant;

use super::fingerprint::{TreeFingerprint, WordsHasher};
use super::treelet::{RootSlots, RoundSchedule, TreeletDp, MAX_LEVEL_DISPATCHES};
use super::wide::MAX_WIDE_LEVEL_DISPATCHES;
use super::TreeUpdater;
use crate::device::{Geometry, Tree};
use crate::gpu::{GpuContext, GpuTimer, ParamSlab, Recorder};
use crate::scene::Triangle;
use crate::sort::SORT_TILE_ITEMS;
use crate::{Error, Result};

/// Team thresholds a tuning tries in the dispatched levels (treelets per level below which teams
/// of 32 optimize them, a workgroup per treelet; 0: never). The dispatched levels mostly hold
/// from a few hundred treelets (those above are climbed) to tens of thousands; a team's DP is
/// ~46 partition tests deep instead of 966, at the cost of a warp per treelet. With overlapped
/// rounds it applies to their dispatched waves.
const TEAM_THRESHOLDS: [u32; 4] = [0, 256, 1024, 4096];
/// The same for the phased rounds' phases, each of which holds the treelets of every level at its
/// depths: thousands (CPU twin, the `phased` preset: conference 5,000-17,000 per phase,
/// field-100k 1,000-6,000), so that the levels' thresholds would mostly leave every phase to lone
/// invocations; u32::MAX: teams in every phase.
const PHASE_TEAM_THRESHOLDS: [u32; 4] = [0, 2048, 8192, u32::MAX];
/// The same for the climb's waves (`RoundSchedule::climb_team_below`), which its four teams take
/// a treelet each at a time: waves of up to 4 treelets in one turn, of up to 8 in two (more lost
/// on an H200 with the team DP's older form).
const CLIMB_TEAM_THRESHOLDS: [u32; 3] = [0, 5, 9];
/// Treelet levels per round optimized per subtree that a tuning tries (0: none; see
/// `RoundSchedule::subtree_levels`).
const SUBTREE_LEVEL_CHOICES: [u32; 4] = [0, 4, 6, 8];
/// Subtree widths a tuning tries where the rounds take subtrees (`RoundSchedule::subtree_width`:
/// about one, two or four lowest depths of a subtree per invocation, or the list filled).
const SUBTREE_WIDTH_CHOICES: [u32; 4] = [32, 64, 128, 1024];
/// How far from the device's default the treelet level dispatches a tuning tries lie (the
/// overlapped rounds dispatch this many waves per round, and may want fewer).
const LEVEL_DISPATCH_STEPS: [i32; 3] = [-6, -3, 3];
/// The same for the wide conversion's level dispatches (the default is about every level a deep
/// wide tree has, plus a few: a level past the tree dispatches no workgroups, and the finish
/// emits the subtrees below the last level dispatched, so a shallow tree may want far fewer).
const WIDE_LEVEL_STEPS: [i32; 5] = [-12, -9, -6, -3, 3];

/// How a build spreads over the device, in every way that leaves its tree as it is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BuildSchedule {
    /// The treelet rounds' (trbvh, trbvh-split).
    pub rounds: RoundSchedule,
    /// Keys per invocation of the radix sort's tiles (one of `SORT_TILE_ITEMS`); None: the
    /// context's `sort_tile_items`, else chosen by key count and device (`sort::tile_items`).
    pub sort_tile_items: Option<u32>,
    /// Levels of the wide conversion given a dispatch (wide layout); None: by reference count and
    /// device (`WideConverter::level_dispatches`).
    pub wide_level_dispatches: Option<u32>,
}

impl BuildSchedule {
    /// The options that are set, as `treelet bench` labels its runs ("overlap=6 tile=16 wd=14";
    /// "default" when none is).
    pub fn label(&self) -> String {
        let mut parts = Vec::new();
        if self.rounds != RoundSchedule::default() {
            parts.push(self.rounds.label());
        }
        if let Some(items) = self.sort_tile_items {
            parts.push(format!("tile={items}"));
        }
        if let Some(levels) = self.wide_level_dispatches {
            parts.push(format!("wd={levels}"));
        }
        if parts.is_empty() {
            return "default".into();
        }
        parts.join(" ")
    }
}

/// The dimensions that apply to an updater's builds, with the device's defaults for the tree
/// (`TreeUpdater::tuning_space`): the treelet rounds' level dispatches (treelet builders with
/// bottom-up rounds), the phased rounds (treelet builders with phases), the sort tile (every GPU
/// builder), the wide conversion's level dispatches (wide layout).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TuningSpace {
    pub round_levels: Option<u32>,
    /// The builds' treelet rounds are phased (`TreeletSettings::phases`): no levels, no climb, no
    /// overlap and no subtrees, but the phases' DP form, team threshold and root slots.
    pub phased: bool,
    /// The device's way of taking a phase's root slots (`RoundSchedule::root_slots` unset).
    pub root_slots: RootSlots,
    /// The rounds' default level dispatches differ (on CPU devices they depend on each round's
    /// γ): `round_levels` is round 1's, and a count equal to it is not the default in effect.
    pub round_levels_vary: bool,
    /// The reach the overlapped rounds take (`treelet::overlap_reach` of the treelet size); 0:
    /// the rounds cannot overlap (their treelets are not all of one size).
    pub overlap_reach: u32,
    /// The device's subtree width (`RoundSchedule::subtree_width` unset).
    pub subtree_width: u32,
    pub sort_tile_items: u32,
    pub wide_levels: Option<u32>,
}

/// The schedule dimensions a tuning leaves as the starting schedule has them (the user fixed
/// them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SchedulePins {
    pub overlap: bool,
    pub subtree_levels: bool,
    pub subtree_width: bool,
    pub dp: bool,
    pub climb_dp: bool,
    pub team_below: bool,
    pub climb_team_below: bool,
    pub level_dispatches: bool,
    pub root_slots: bool,
    pub sort_tile_items: bool,
    pub wide_level_dispatches: bool,
}

/// How a tuning measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TuningOptions {
    /// Builds of each of the two schedules of a comparison (alternating), at least 1.
    pub pairs: u32,
    /// An alternative is kept when its builds are shorter than the kept schedule's by at least
    /// this fraction, as the median of the pairs' ratios, and in four pairs of five (`faster`;
    /// the measurements' noise on a warm GPU is about 1 %).
    pub min_gain: f64,
    /// Descents over all free dimensions at most; a descent that keeps nothing ends the tuning.
    pub max_descents: u32,
    pub pins: SchedulePins,
}

impl Default for TuningOptions {
    fn default() -> Self {
        Self {
            pairs: 5,
            min_gain: 0.02,
            max_descents: 2,
            pins: SchedulePins::default(),
        }
    }
}

/// What a tuning needs from the device.
pub trait ScheduleTrials {
    /// Builds once with `schedule`, untimed (its kernels compile), and tells whether the tree is
    /// the one the starting schedule built (`DeviceTrials`: by their `TreeFingerprint`s).
    fn builds_reference_tree(&mut self, schedule: BuildSchedule) -> Result<bool>;
    /// Builds once with `schedule`: the build's time, ms.
    fn time_build(&mut self, schedule: BuildSchedule) -> Result<f64>;
}

/// One alternative a tuning tried against the schedule kept at the time.
#[derive(Clone, Debug, PartialEq)]
pub struct ScheduleTrial {
    pub candidate: BuildSchedule,
    /// Median builds, ms, of the kept schedule and of the candidate over the same pairs (None:
    /// the candidate was refused and not timed).
    pub kept_ms: Option<f64>,
    pub candidate_ms: Option<f64>,
    /// The candidate built another tree than the starting schedule (refused).
    pub other_tree: bool,
    /// The candidate's build failed, with this error (refused; e.g. its scratch beyond the
    /// device's limits).
    pub error: Option<String>,
    /// The candidate became the kept schedule.
    pub adopted: bool,
}

/// The outcome of a tuning: the schedule kept and every trial, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct TunedSchedule {
    pub schedule: BuildSchedule,
    pub trials: Vec<ScheduleTrial>,
    /// Builds the tuning ran (untimed ones included) and its wall-clock time.
    pub builds: u32,
    pub wall_ms: f64,
}

/// A dimension of the schedule.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dimension {
    Overlap,
    Subtrees,
    SubtreeWidth,
    Dp,
    ClimbDp,
    TeamBelow,
    ClimbTeamBelow,
    LevelDispatches,
    RootSlots,
    SortTile,
    WideLevels,
}

impl Dimension {
    /// In the order a descent tries them: the dispatched levels' teams first, with the rounds one
    /// after another (the default), then the overlap (its dispatched waves take the kept teams).
    const ALL: [Dimension; 11] = [
        Dimension::TeamBelow,
        Dimension::Overlap,
        Dimension::Subtrees,
        Dimension::SubtreeWidth,
        Dimension::Dp,
        Dimension::ClimbDp,
        Dimension::ClimbTeamBelow,
        Dimension::LevelDispatches,
        Dimension::RootSlots,
        Dimension::SortTile,
        Dimension::WideLevels,
    ];

    fn is_pinned(self, pins: &SchedulePins) -> bool {
        match self {
            Dimension::Overlap => pins.overlap,
            Dimension::Subtrees => pins.subtree_levels,
            Dimension::SubtreeWidth => pins.subtree_width,
            Dimension::Dp => pins.dp,
            Dimension::ClimbDp => pins.climb_dp,
            Dimension::TeamBelow => pins.team_below,
            Dimension::ClimbTeamBelow => pins.climb_team_below,
            Dimension::LevelDispatches => pins.level_dispatches,
            Dimension::RootSlots => pins.root_slots,
            Dimension::SortTile => pins.sort_tile_items,
            Dimension::WideLevels => pins.wide_level_dispatches,
        }
    }

    fn applies(self, space: &TuningSpace) -> bool {
        match self {
            Dimension::SortTile => true,
            Dimension::WideLevels => space.wide_levels.is_some(),
            // Rounds of more than one treelet size cannot overlap.
            Dimension::Overlap => space.round_levels.is_some() && space.overlap_reach > 0,
            // The phases' treelets take a DP form and a team threshold as a level's do.
            Dimension::TeamBelow | Dimension::Dp => space.round_levels.is_some() || space.phased,
            Dimension::RootSlots => space.phased,
            _ => space.round_levels.is_some(),
        }
    }

    /// The schedules that differ from `kept` in this dimension alone and run differently.
    /// Overlapped rounds and subtrees exclude each other: a candidate of one drops the other
    /// (none where the other is pinned on).
    fn alternatives(
        self,
        kept: BuildSchedule,
        space: &TuningSpace,
        pins: &SchedulePins,
    ) -> Vec<BuildSchedule> {
        let rounds = |r: RoundSchedule| BuildSchedule { rounds: r, ..kept };
        let k = kept.rounds;
        let values: Vec<BuildSchedule> = match self {
            Dimension::Overlap => [None, Some(space.overlap_reach)]
                .into_iter()
                .filter(|overlap| {
                    overlap.is_none() || !pins.subtree_levels || k.subtree_levels() == 0
                })
                .map(|overlap| {
                    let subtree_levels = k.subtree_levels.filter(|_| overlap.is_none());
                    rounds(RoundSchedule {
                        overlap,
                        subtree_levels,
                        ..k
                    })
                })
                .collect(),
            Dimension::Subtrees => SUBTREE_LEVEL_CHOICES
                .into_iter()
                .filter(|&levels| levels == 0 || !pins.overlap || k.overlap.is_none())
                .map(|levels| {
                    let overlap = k.overlap.filter(|_| levels == 0);
                    rounds(RoundSchedule {
                        subtree_levels: Some(levels),
                        overlap,
                        ..k
                    })
                })
                .collect(),
            // The width matters only where the rounds take subtrees.
            Dimension::SubtreeWidth if k.subtree_levels() == 0 => Vec::new(),
            Dimension::SubtreeWidth => SUBTREE_WIDTH_CHOICES
                .map(|width| {
                    rounds(RoundSchedule {
                        subtree_width: Some(width),
                        ..k
                    })
                })
                .to_vec(),
            // The climb keeps its form (by default it follows the dispatched levels'); the phased
            // rounds have no climb.
            Dimension::Dp => [TreeletDp::Unrolled, TreeletDp::Loop]
                .map(|dp| {
                    rounds(RoundSchedule {
                        dp: Some(dp),
                        climb_dp: if space.phased {
                            k.climb_dp
                        } else {
                            Some(k.climb_dp())
                        },
                        ..k
                    })
                })
                .to_vec(),
            Dimension::ClimbDp => [TreeletDp::Unrolled, TreeletDp::Loop]
                .map(|dp| {
                    rounds(RoundSchedule {
                        climb_dp: Some(dp),
                        ..k
                    })
                })
                .to_vec(),
            Dimension::TeamBelow => if space.phased {
                PHASE_TEAM_THRESHOLDS
            } else {
                TEAM_THRESHOLDS
            }
            .map(|below| {
                rounds(RoundSchedule {
                    team_below: Some(below),
                    ..k
                })
            })
            .to_vec(),
            Dimension::ClimbTeamBelow => CLIMB_TEAM_THRESHOLDS
                .map(|below| {
                    rounds(RoundSchedule {
                        climb_team_below: Some(below),
                        ..k
                    })
                })
                .to_vec(),
            Dimension::LevelDispatches => stepped_counts(
                space.round_levels,
                LEVEL_DISPATCH_STEPS,
                MAX_LEVEL_DISPATCHES,
            )
            .map(|level_dispatches| {
                rounds(RoundSchedule {
                    level_dispatches,
                    ..k
                })
            })
            .collect(),
            Dimension::RootSlots => [RootSlots::Workgroup, RootSlots::Root]
                .map(|slots| {
                    rounds(RoundSchedule {
                        root_slots: Some(slots),
                        ..k
                    })
                })
                .to_vec(),
            Dimension::SortTile => std::iter::once(None)
                .chain(SORT_TILE_ITEMS.map(Some))
                .map(|sort_tile_items| BuildSchedule {
                    sort_tile_items,
                    ..kept
                })
                .collect(),
            Dimension::WideLevels => stepped_counts(
                space.wide_levels,
                WIDE_LEVEL_STEPS,
                MAX_WIDE_LEVEL_DISPATCHES,
            )
            .map(|wide_level_dispatches| BuildSchedule {
                wide_level_dispatches,
                ..kept
            })
            .collect(),
        };
        let mut distinct: Vec<BuildSchedule> = Vec::new();
        for v in values {
            if !same_in_effect(v, kept, space)
                && !distinct.iter().any(|d| same_in_effect(*d, v, space))
            {
                distinct.push(v);
            }
        }
        distinct
    }

    /// Whether `a` and `b` take the same value in this dimension.
    fn same_value(self, a: BuildSchedule, b: BuildSchedule, space: &TuningSpace) -> bool {
        let (ra, rb) = (a.rounds, b.rounds);
        match self {
            Dimension::Overlap => ra.overlap == rb.overlap,
            Dimension::Subtrees => ra.subtree_levels() == rb.subtree_levels(),
            Dimension::SubtreeWidth => {
                (ra.subtree_levels() == 0 && rb.subtree_levels() == 0)
                    || same_count(ra.subtree_width, rb.subtree_width, space.subtree_width)
            }
            Dimension::Dp => ra.dp() == rb.dp(),
            Dimension::ClimbDp => ra.climb_dp() == rb.climb_dp(),
            Dimension::TeamBelow => ra.team_below() == rb.team_below(),
            Dimension::ClimbTeamBelow => ra.climb_team_below() == rb.climb_team_below(),
            Dimension::LevelDispatches if space.round_levels_vary => {
                ra.level_dispatches == rb.level_dispatches
            }
            Dimension::LevelDispatches => same_count(
                ra.level_dispatches,
                rb.level_dispatches,
                space.round_levels.unwrap_or(0),
            ),
            Dimension::RootSlots => {
                ra.root_slots.unwrap_or(space.root_slots)
                    == rb.root_slots.unwrap_or(space.root_slots)
            }
            Dimension::SortTile => {
                same_count(a.sort_tile_items, b.sort_tile_items, space.sort_tile_items)
            }
            Dimension::WideLevels => same_count(
                a.wide_level_dispatches,
                b.wide_level_dispatches,
                space.wide_levels.unwrap_or(0),
            ),
        }
    }
}

/// The counts a tuning tries of a dimension whose default is `default`: None (the default), then
/// the default moved by each of `steps`, at most `max`.
fn stepped_counts<const STEPS: usize>(
    default: Option<u32>,
    steps: [i32; STEPS],
    max: u32,
) -> impl Iterator<Item = Option<u32>> {
    let default = default.unwrap_or(0);
    std::iter::once(None)
        .chain(steps.map(move |step| Some(default.saturating_add_signed(step).min(max))))
}

/// Whether two settings of a count (None: `default`) are the same in effect.
fn same_count(a: Option<u32>, b: Option<u32>, default: u32) -> bool {
    a.unwrap_or(default) == b.unwrap_or(default)
}

/// Whether two schedules run the same way.
fn same_in_effect(a: BuildSchedule, b: BuildSchedule, space: &TuningSpace) -> bool {
    Dimension::ALL.iter().all(|d| d.same_value(a, b, space))
}

/// `schedule` with every value that is the default in effect unset (the same schedule, labelled
/// by what differs from the default).
fn without_defaults(schedule: BuildSchedule, space: &TuningSpace) -> BuildSchedule {
    let r = schedule.rounds;
    let round_levels = space.round_levels.unwrap_or(0);
    BuildSchedule {
        rounds: RoundSchedule {
            level_dispatches: r
                .level_dispatches
                .filter(|&l| space.round_levels_vary || l != round_levels),
            team_below: r
                .team_below
                .filter(|&t| t != RoundSchedule::default().team_below()),
            climb_team_below: r
                .climb_team_below
                .filter(|&t| t != RoundSchedule::default().climb_team_below()),
            dp: r.dp.filter(|&dp| dp != TreeletDp::default()),
            climb_dp: r.climb_dp.filter(|&dp| !space.phased && dp != r.dp()),
            overlap: r.overlap,
            subtree_levels: r.subtree_levels.filter(|&levels| levels != 0),
            subtree_width: r
                .subtree_width
                .filter(|&w| r.subtree_levels() > 0 && w != space.subtree_width),
            root_slots: r.root_slots.filter(|&slots| slots != space.root_slots),
        },
        sort_tile_items: schedule
            .sort_tile_items
            .filter(|&t| t != space.sort_tile_items),
        wide_level_dispatches: schedule
            .wide_level_dispatches
            .filter(|&l| Some(l) != space.wide_levels),
    }
}

/// Whether the candidate's builds beat the kept schedule's, pair by pair (each pair ran back to
/// back, so a change of clocks or load hits both): the median of the pairs' time ratios is below
/// 1 − `min_gain`, and the candidate was faster in at least four pairs of five.
fn faster(kept: &[f64], candidate: &[f64], min_gain: f64) -> bool {
    let ratios: Vec<f64> = kept
        .iter()
        .zip(candidate)
        .map(|(k, c)| c / k.max(f64::MIN_POSITIVE))
        .collect();
    let wins = ratios.iter().filter(|&&r| r < 1.0).count();
    median(ratios.clone()) < 1.0 - min_gain && 5 * wins >= 4 * ratios.len()
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Tunes the schedule from `start` over the dimensions of `space` (see the module header).
pub fn tune_schedule(
    trials: &mut impl ScheduleTrials,
    start: BuildSchedule,
    space: &TuningSpace,
    options: &TuningOptions,
) -> Result<TunedSchedule> {
    if options.pairs == 0 {
        return Err(Error::InvalidArgument(
            "a schedule tuning needs at least one pair of builds per comparison".into(),
        ));
    }
    let begin = Instant::now();
    let mut kept = start;
    let mut record = Vec::new();
    let mut builds = 0;
    // Values that built another tree (never tried again), and the pairs of (kept, candidate)
    // schedules compared so far (not compared again).
    let mut refused: Vec<(Dimension, BuildSchedule)> = Vec::new();
    let mut compared: Vec<(BuildSchedule, BuildSchedule)> = Vec::new();
    for _ in 0..options.max_descents {
        let mut changed = false;
        let free = Dimension::ALL
            .into_iter()
            .filter(|d| d.applies(space) && !d.is_pinned(&options.pins));
        for dimension in free {
            for candidate in dimension.alternatives(kept, space, &options.pins) {
                let was_refused = refused
                    .iter()
                    .any(|(d, r)| *d == dimension && d.same_value(*r, candidate, space));
                let was_compared = compared.iter().any(|(k, c)| {
                    same_in_effect(*k, kept, space) && same_in_effect(*c, candidate, space)
                });
                if was_refused || was_compared {
                    continue;
                }
                builds += 1;
                let refusal = match trials.builds_reference_tree(candidate) {
                    Ok(true) => None,
                    Ok(false) => Some((
                        true,
                        None,
                        "built another tree than the given schedule: a kernel or device bug, or \
                         for overlapped rounds a tree where the reach does not keep the rounds' \
                         trees (README, \"Rounds can overlap\")"
                            .to_string(),
                    )),
                    Err(e) => Some((false, Some(e.to_string()), format!("failed: {e}"))),
                };
                if let Some((other_tree, error, why)) = refusal {
                    log::warn!("schedule [{}] {why}; not used", candidate.label());
                    refused.push((dimension, candidate));
                    record.push(ScheduleTrial {
                        candidate,
                        kept_ms: None,
                        candidate_ms: None,
                        other_tree,
                        error,
                        adopted: false,
                    });
                    continue;
                }
                let (mut kept_times, mut candidate_times) = (Vec::new(), Vec::new());
                for _ in 0..options.pairs {
                    kept_times.push(trials.time_build(kept)?);
                    candidate_times.push(trials.time_build(candidate)?);
                    builds += 2;
                }
                compared.push((kept, candidate));
                let adopted = faster(&kept_times, &candidate_times, options.min_gain);
                let kept_ms = median(kept_times);
                let candidate_ms = median(candidate_times);
                log::info!(
                    "schedule tuning: [{}] {candidate_ms:.3} ms against [{}] {kept_ms:.3} ms{}",
                    candidate.label(),
                    kept.label(),
                    if adopted { ", kept" } else { "" }
                );
                record.push(ScheduleTrial {
                    candidate,
                    kept_ms: Some(kept_ms),
                    candidate_ms: Some(candidate_ms),
                    other_tree: false,
                    error: None,
                    adopted,
                });
                if adopted {
                    kept = candidate;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    Ok(TunedSchedule {
        schedule: without_defaults(kept, space),
        trials: record,
        builds,
        wall_ms: begin.elapsed().as_secs_f64() * 1e3,
    })
}

/// Whether a tuning runs unless asked otherwise (`--tune-schedule auto`): on GPUs, not on CPU
/// devices, where it takes minutes.
pub fn tunes_by_default(ctx: &GpuContext) -> bool {
    ctx.info.device_type != wgpu::DeviceType::Cpu
}

/// Tunes `updater`'s build schedule on `geometry` (whose CPU triangles are `triangles`) into
/// `tree`, after untimed builds for `warmup_ms` of wall-clock time (a GPU that idled needs some
/// before its timings mean anything), and sets the schedule kept. None where no tuning applies
/// (`TreeUpdater::tuning_space`).
pub fn tune_updater(
    ctx: &GpuContext,
    updater: &mut TreeUpdater,
    geometry: &Geometry,
    triangles: &[Triangle],
    tree: &mut Tree,
    options: &TuningOptions,
    warmup_ms: f64,
) -> Result<Option<TunedSchedule>> {
    let Some(space) = updater.tuning_space(ctx, geometry.triangle_count) else {
        return Ok(None);
    };
    let start = updater.build_schedule();
    let tuned = {
        let mut trials = DeviceTrials::new(ctx, updater, geometry, triangles, tree, start)?;
        let begin = Instant::now();
        while begin.elapsed().as_secs_f64() * 1e3 < warmup_ms {
            trials.time_build(start)?;
        }
        tune_schedule(&mut trials, start, &space, options)
    };
    // The schedule kept, or the one given where the tuning failed.
    let kept = tuned.as_ref().map_or(start, |t| t.schedule);
    updater.set_build_schedule(kept)?;
    tuned.map(Some)
}

/// Trials on the GPU: builds of `geometry` through `updater` (a GPU builder's, not a refit's)
/// into `tree`, each compared with the starting schedule's tree by their fingerprints
/// (`TreeFingerprint`, hashed on the GPU).
pub struct DeviceTrials<'a> {
    ctx: &'a GpuContext,
    updater: &'a mut TreeUpdater,
    geometry: &'a Geometry,
    triangles: &'a [Triangle],
    tree: &'a mut Tree,
    slab: ParamSlab,
    hasher: WordsHasher,
    reference: TreeFingerprint,
}

impl<'a> DeviceTrials<'a> {
    /// Builds once with `start` and keeps its tree's fingerprint as the reference.
    pub fn new(
        ctx: &'a GpuContext,
        updater: &'a mut TreeUpdater,
        geometry: &'a Geometry,
        triangles: &'a [Triangle],
        tree: &'a mut Tree,
        start: BuildSchedule,
    ) -> Result<Self> {
        let mut trials = Self {
            ctx,
            updater,
            geometry,
            triangles,
            tree,
            slab: ParamSlab::new(ctx),
            hasher: WordsHasher::new(ctx)?,
            reference: TreeFingerprint::default(),
        };
        trials.build(start, None)?;
        trials.reference = TreeFingerprint::of(ctx, &mut trials.hasher, trials.tree)?;
        Ok(trials)
    }

    fn build(&mut self, schedule: BuildSchedule, timer: Option<&mut GpuTimer>) -> Result<()> {
        self.updater.set_build_schedule(schedule)?;
        let mut rec = Recorder::new(self.ctx, &mut self.slab, timer);
        let result = self
            .updater
            .record(&mut rec, self.geometry, self.triangles, self.tree);
        rec.submit();
        result.map(drop)
    }
}

impl ScheduleTrials for DeviceTrials<'_> {
    fn builds_reference_tree(&mut self, schedule: BuildSchedule) -> Result<bool> {
        self.build(schedule, None)?;
        Ok(TreeFingerprint::of(self.ctx, &mut self.hasher, self.tree)? == self.reference)
    }

    fn time_build(&mut self, schedule: BuildSchedule) -> Result<f64> {
        let mut timer = GpuTimer::new(self.ctx, self.updater.pass_count());
        let start = Instant::now();
        self.build(schedule, Some(&mut timer))?;
        let stages = timer.read(self.ctx)?;
        let wall_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(stages
            .iter()
            .map(|s| s.ms)
            .sum::<Option<f64>>()
            .unwrap_or(wall_ms))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Trials whose build time is a function of the schedule (`cost`), whose tree differs for
    /// the schedules `other_tree` accepts, and which count the builds of each schedule.
    struct FakeTrials<C: Fn(BuildSchedule) -> f64, O: Fn(BuildSchedule) -> bool> {
        cost: C,
        other_tree: O,
        timed: Vec<BuildSchedule>,
    }

    impl<C: Fn(BuildSchedule) -> f64, O: Fn(BuildSchedule) -> bool> ScheduleTrials
        for FakeTrials<C, O>
    {
        fn builds_reference_tree(&mut self, schedule: BuildSchedule) -> Result<bool> {
            // 23 wide level dispatches stand for a schedule beyond the device's limits.
            if schedule.wide_level_dispatches == Some(23) {
                return Err(Error::InvalidArgument("beyond the device's limits".into()));
            }
            Ok(!(self.other_tree)(schedule))
        }

        fn time_build(&mut self, schedule: BuildSchedule) -> Result<f64> {
            self.timed.push(schedule);
            Ok((self.cost)(schedule))
        }
    }

    /// A treelet builder's wide-layout builds with the defaults 14 (level dispatches), 8 (sort
    /// tile) and 20 (wide level dispatches).
    const SPACE: TuningSpace = TuningSpace {
        round_levels: Some(14),
        phased: false,
        root_slots: RootSlots::Workgroup,
        round_levels_vary: false,
        overlap_reach: 6,
        subtree_width: 64,
        sort_tile_items: 8,
        wide_levels: Some(20),
    };

    /// A build time with one best value per dimension: overlap 6 (else subtrees of 6 levels, of
    /// width 128), the loop DP in the climb, teams below 1024 (phases: below 8192; in the climb
    /// below 5), 11 dispatched levels, a phase's root slots taken per root, tiles of 16 keys per
    /// invocation, 14 wide levels dispatched.
    fn cost(b: BuildSchedule) -> f64 {
        let s = b.rounds;
        let mut ms = 10.0;
        if s.root_slots == Some(RootSlots::Root) {
            ms -= 0.4;
        }
        if s.overlap.is_none() {
            ms += 3.0;
        }
        if s.subtree_levels() == 6 {
            ms -= 1.0;
            if s.subtree_width == Some(128) {
                ms -= 0.3;
            }
        }
        if s.team_below() == 1024 || s.team_below() == 8192 {
            ms -= 0.5;
        }
        if s.climb_team_below() == 5 {
            ms -= 0.3;
        }
        if s.climb_dp() == TreeletDp::Loop {
            ms -= 0.5;
        }
        if s.dp() == TreeletDp::Loop {
            ms += 0.1;
        }
        ms += f64::from(s.level_dispatches.unwrap_or(14).abs_diff(11)) * 0.2;
        ms += if b.sort_tile_items == Some(16) {
            0.0
        } else {
            0.4
        };
        ms + f64::from(b.wide_level_dispatches.unwrap_or(20).abs_diff(14)) * 0.05
    }

    fn tune(
        other_tree: impl Fn(BuildSchedule) -> bool,
        pins: SchedulePins,
        start: BuildSchedule,
        space: &TuningSpace,
    ) -> (TunedSchedule, Vec<BuildSchedule>) {
        let mut trials = FakeTrials {
            cost,
            other_tree,
            timed: Vec::new(),
        };
        let options = TuningOptions {
            pairs: 3,
            pins,
            ..TuningOptions::default()
        };
        let tuned = tune_schedule(&mut trials, start, space, &options).unwrap();
        (tuned, trials.timed)
    }

    #[test]
    fn the_descent_keeps_the_fastest_schedule() {
        let (tuned, timed) = tune(
            |_| false,
            SchedulePins::default(),
            BuildSchedule::default(),
            &SPACE,
        );
        let kept = tuned.schedule;
        assert_eq!(kept.rounds.overlap, Some(SPACE.overlap_reach));
        assert_eq!(kept.rounds.climb_dp(), TreeletDp::Loop);
        assert_eq!(kept.rounds.dp(), TreeletDp::Unrolled);
        assert_eq!(kept.rounds.level_dispatches, Some(11));
        assert_eq!(kept.sort_tile_items, Some(16));
        assert_eq!(kept.wide_level_dispatches, Some(14));
        // The kept schedule is labelled by what differs from the defaults.
        assert_eq!(
            kept.label(),
            "d=11 t=1024 climb-t=5 climb-dp=loop overlap=6 tile=16 wd=14",
            "{kept:?}"
        );
        // Every kept schedule beat the one before it by the margin.
        for t in tuned.trials.iter().filter(|t| t.adopted) {
            assert!(t.candidate_ms.unwrap() < t.kept_ms.unwrap() * 0.98);
        }
        // Teams were tried (and kept) before the overlap, which then took them.
        assert!(timed
            .iter()
            .any(|s| s.rounds.overlap.is_none() && s.rounds.team_below() == 1024));
        assert_eq!(kept.rounds.team_below(), 1024);
        // Subtrees were tried before the overlap was kept, never with it.
        assert!(timed.iter().any(|s| s.rounds.subtree_levels() == 6));
        assert!(timed
            .iter()
            .all(|s| s.rounds.overlap.is_none() || s.rounds.subtree_levels() == 0));
        assert_eq!(kept.rounds.subtree_levels(), 0);
        // Widths were tried with subtrees only.
        assert!(timed
            .iter()
            .all(|s| s.rounds.subtree_width.is_none() || s.rounds.subtree_levels() > 0));
        assert_eq!(tuned.builds as usize, timed.len() + tuned.trials.len());
    }

    /// Phased rounds: their team threshold, DP form and root slots are tried, and none of the
    /// bottom-up rounds' own dimensions (overlap, subtrees, the climb's, level dispatches).
    #[test]
    fn the_phased_rounds_tune_their_own_dimensions() {
        let space = TuningSpace {
            round_levels: None,
            phased: true,
            overlap_reach: 0,
            ..SPACE
        };
        let (tuned, timed) = tune(
            |_| false,
            SchedulePins::default(),
            BuildSchedule::default(),
            &space,
        );
        assert!(timed.iter().all(|s| {
            let r = s.rounds;
            r.overlap.is_none()
                && r.subtree_levels.is_none()
                && r.subtree_width.is_none()
                && r.climb_dp.is_none()
                && r.climb_team_below.is_none()
                && r.level_dispatches.is_none()
        }));
        assert!(timed.iter().any(|s| s.rounds.dp == Some(TreeletDp::Loop)));
        // The phases' own team thresholds, teams in every phase among them.
        assert!(timed.iter().any(|s| s.rounds.team_below == Some(u32::MAX)));
        assert!(!timed.iter().any(|s| s.rounds.team_below == Some(1024)));
        let kept = tuned.schedule.rounds;
        assert_eq!(kept.team_below(), 8192);
        assert_eq!(kept.root_slots, Some(RootSlots::Root));
        // `cost` rewards the loop form in the climb, whose form follows the DP's where unset: so
        // the loop DP is kept here, labelled without a climb's form.
        assert_eq!(kept.dp(), TreeletDp::Loop);
        assert_eq!(kept.climb_dp, None);
        // The device's own way is the default, so it is not kept as a setting.
        let start = BuildSchedule {
            rounds: RoundSchedule {
                root_slots: Some(RootSlots::Workgroup),
                ..RoundSchedule::default()
            },
            ..BuildSchedule::default()
        };
        assert_eq!(without_defaults(start, &space), BuildSchedule::default());
    }

    #[test]
    fn only_the_dimensions_of_the_space_are_tried() {
        // An LBVH in the binary layout: the sort tile alone.
        let space = TuningSpace {
            round_levels: None,
            phased: false,
            root_slots: RootSlots::Workgroup,
            round_levels_vary: false,
            overlap_reach: 0,
            subtree_width: 64,
            sort_tile_items: 8,
            wide_levels: None,
        };
        let (tuned, timed) = tune(
            |_| false,
            SchedulePins::default(),
            BuildSchedule::default(),
            &space,
        );
        assert!(timed
            .iter()
            .all(|s| s.rounds == RoundSchedule::default() && s.wide_level_dispatches.is_none()));
        // Tiles of 8 are the default: 16 (kept) and 32 are the alternatives, then the default
        // against 16 in the second descent (the pair 16 against 32 is not timed again).
        assert_eq!(tuned.trials.len(), 3);
        assert_eq!(tuned.schedule.sort_tile_items, Some(16));
    }

    /// Where the rounds' defaults differ (CPU devices), a count equal to round 1's default is a
    /// schedule of its own: not the default, not labelled as it, and not set back to it.
    #[test]
    fn a_count_is_the_default_only_where_every_round_has_it() {
        let explicit = BuildSchedule {
            rounds: RoundSchedule {
                level_dispatches: Some(14),
                ..RoundSchedule::default()
            },
            ..BuildSchedule::default()
        };
        let vary = TuningSpace {
            round_levels_vary: true,
            ..SPACE
        };
        assert!(same_in_effect(explicit, BuildSchedule::default(), &SPACE));
        assert_eq!(without_defaults(explicit, &SPACE), BuildSchedule::default());
        assert!(!same_in_effect(explicit, BuildSchedule::default(), &vary));
        assert_eq!(without_defaults(explicit, &vary), explicit);
        assert_eq!(without_defaults(explicit, &vary).label(), "d=14");
    }

    #[test]
    fn pinned_dimensions_keep_the_starting_values() {
        let start = BuildSchedule {
            rounds: RoundSchedule {
                overlap: None,
                level_dispatches: Some(14),
                ..RoundSchedule::default()
            },
            sort_tile_items: Some(32),
            wide_level_dispatches: None,
        };
        let pins = SchedulePins {
            overlap: true,
            level_dispatches: true,
            sort_tile_items: true,
            ..SchedulePins::default()
        };
        let (tuned, timed) = tune(|_| false, pins, start, &SPACE);
        assert!(timed.iter().all(|s| s.rounds.overlap.is_none()
            && s.rounds.level_dispatches == Some(14)
            && s.sort_tile_items == Some(32)));
        // Teams below 1024 pay, and without the overlap subtrees of 6 levels.
        assert_eq!(tuned.schedule.rounds.team_below(), 1024);
        assert_eq!(tuned.schedule.rounds.subtree_levels(), 6);
        assert_eq!(tuned.schedule.rounds.subtree_width, Some(128));
        assert_eq!(tuned.schedule.rounds.climb_dp(), TreeletDp::Loop);
        assert_eq!(tuned.schedule.rounds.climb_team_below(), 5);
        assert_eq!(tuned.schedule.wide_level_dispatches, Some(14));
    }

    #[test]
    fn a_schedule_with_another_tree_or_a_failed_build_is_never_timed_or_kept() {
        let (tuned, timed) = tune(
            |s| s.rounds.overlap.is_some(),
            SchedulePins::default(),
            BuildSchedule::default(),
            &SPACE,
        );
        assert_eq!(tuned.schedule.rounds.overlap, None);
        assert!(timed.iter().all(|s| s.rounds.overlap.is_none()));
        let refused: Vec<_> = tuned.trials.iter().filter(|t| t.other_tree).collect();
        assert_eq!(refused.len(), 1, "refused once, not retried");
        assert!(refused[0].candidate_ms.is_none() && !refused[0].adopted);
        assert!(refused[0].error.is_none());
        // A candidate whose build fails is refused the same way, and the tuning goes on.
        let failed: Vec<_> = tuned.trials.iter().filter(|t| t.error.is_some()).collect();
        assert_eq!(failed.len(), 1, "{failed:?}");
        assert_eq!(failed[0].candidate.wide_level_dispatches, Some(23));
        assert!(!failed[0].other_tree && failed[0].candidate_ms.is_none());
        assert!(timed.iter().all(|s| s.wide_level_dispatches != Some(23)));
        // The other dimensions still won.
        assert_eq!(tuned.schedule.rounds.team_below(), 1024);
    }

    #[test]
    fn a_candidate_must_win_the_pairs_not_one_lucky_build() {
        // Faster by 10 % in three pairs of five, slower in two: not kept (a noisy device).
        let kept = [10.0, 10.0, 10.0, 10.0, 10.0];
        assert!(!faster(&kept, &[9.0, 9.0, 9.0, 11.0, 12.0], 0.02));
        // Four of five and a median ratio of 0.9: kept, whatever the outlier.
        assert!(faster(&kept, &[9.0, 9.0, 9.0, 9.0, 30.0], 0.02));
        // All pairs, but by less than the margin: not kept.
        assert!(!faster(&kept, &[9.9; 5], 0.02));
        // A clock change in the middle hits both sides of its pairs.
        assert!(faster(
            &[10.0, 10.0, 5.0, 5.0, 5.0],
            &[9.0, 9.0, 4.5, 4.5, 4.5],
            0.02
        ));
        assert!(faster(&[10.0], &[9.0], 0.02));
    }

    #[test]
    fn gains_below_the_margin_are_not_kept() {
        let mut trials = FakeTrials {
            cost: |s: BuildSchedule| {
                if s.rounds.dp() == TreeletDp::Loop {
                    9.9
                } else {
                    10.0
                }
            },
            other_tree: |_| false,
            timed: Vec::new(),
        };
        let tuned = tune_schedule(
            &mut trials,
            BuildSchedule::default(),
            &SPACE,
            &TuningOptions::default(),
        )
        .unwrap();
        assert_eq!(tuned.schedule, BuildSchedule::default());
        assert!(tuned.trials.iter().all(|t| !t.adopted));
        assert!(tune_schedule(
            &mut trials,
            BuildSchedule::default(),
            &SPACE,
            &TuningOptions {
                pairs: 0,
                ..TuningOptions::default()
            }
        )
        .is_err());
    }
}
