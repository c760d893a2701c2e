//! Build-schedule tuning. Every schedule of the treelet rounds (`RoundSchedule`: the rounds one
//! after another or overlapped, the lone DP's form in the dispatched levels and in the climb, the
//! team threshold, the levels given a dispatch) builds the same tree (tests/trbvh.rs), so a
//! schedule sets only the build's time, and which one is fastest depends on the device and the
//! tree. `tune_schedule` finds it where the build runs: a coordinate descent from a starting
//! schedule over the dimensions the caller left free; each alternative is first built once
//! (compiling its kernels) and refused unless its tree is the starting schedule's bit for bit (on
//! a device where it is not, a schedule has a bug: the tuner logs it and never keeps it), then
//! timed in alternation with the schedule kept so far (pairs of builds, so that a change of clocks
//! hits both) and kept when its median build is shorter by a margin. `DeviceTrials` runs the
//! trials on the GPU through a `TreeUpdater`. Not from the paper, whose schedule is one (§4): the
//! README's "Schedule tuning" says what it varies and why.

use std::time::Instant;

use super::treelet::{RoundSchedule, TreeletDp, MAX_LEVEL_DISPATCHES, OVERLAP_REACH};
use super::{Bvh, TreeUpdater};
use crate::device::{Geometry, Tree};
use crate::gpu::{GpuContext, GpuTimer, ParamSlab, Recorder};
use crate::scene::Triangle;
use crate::{Error, Result};

/// Team thresholds a tuning tries (treelets per level below which teams of 32 optimize them; 0:
/// never).
const TEAM_THRESHOLDS: [u32; 4] = [0, 4, 16, 256];
/// How far from the device's default the level dispatches a tuning tries lie.
const LEVEL_DISPATCH_STEP: u32 = 3;

/// The schedule dimensions a tuning leaves as the starting schedule has them (the user fixed
/// them).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SchedulePins {
    pub overlap: bool,
    pub dp: bool,
    pub climb_dp: bool,
    pub team_below: bool,
    pub level_dispatches: bool,
}

/// How a tuning measures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TuningOptions {
    /// Builds of each of the two schedules of a comparison (alternating), at least 1.
    pub pairs: u32,
    /// An alternative is kept when its median build is shorter than the kept schedule's by at
    /// least this fraction (the measurements' noise on a warm GPU is about 1 %).
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
    /// the one the starting schedule built, bit for bit.
    fn builds_reference_tree(&mut self, schedule: RoundSchedule) -> Result<bool>;
    /// Builds once with `schedule`: the build's time, ms.
    fn time_build(&mut self, schedule: RoundSchedule) -> Result<f64>;
}

/// One alternative a tuning tried against the schedule kept at the time.
#[derive(Clone, Debug, PartialEq)]
pub struct ScheduleTrial {
    pub candidate: RoundSchedule,
    /// Median builds, ms, of the kept schedule and of the candidate over the same pairs (None:
    /// the candidate built another tree and was not timed).
    pub kept_ms: Option<f64>,
    pub candidate_ms: Option<f64>,
    /// The candidate built another tree than the starting schedule.
    pub other_tree: bool,
    /// The candidate became the kept schedule.
    pub adopted: bool,
}

/// The outcome of a tuning: the schedule kept and every trial, in order.
#[derive(Clone, Debug, PartialEq)]
pub struct TunedSchedule {
    pub schedule: RoundSchedule,
    pub trials: Vec<ScheduleTrial>,
    /// Builds the tuning ran (untimed ones included) and its wall-clock time.
    pub builds: u32,
    pub wall_ms: f64,
}

/// A dimension of the schedule (a field of `RoundSchedule`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Dimension {
    Overlap,
    Dp,
    ClimbDp,
    TeamBelow,
    LevelDispatches,
}

impl Dimension {
    const ALL: [Dimension; 5] = [
        Dimension::Overlap,
        Dimension::Dp,
        Dimension::ClimbDp,
        Dimension::TeamBelow,
        Dimension::LevelDispatches,
    ];

    fn is_pinned(self, pins: &SchedulePins) -> bool {
        match self {
            Dimension::Overlap => pins.overlap,
            Dimension::Dp => pins.dp,
            Dimension::ClimbDp => pins.climb_dp,
            Dimension::TeamBelow => pins.team_below,
            Dimension::LevelDispatches => pins.level_dispatches,
        }
    }

    /// The schedules that differ from `kept` in this dimension alone and run differently;
    /// `default_levels` is the level dispatches the device would choose for the tree
    /// (`RoundSchedule::default_level_dispatches`).
    fn alternatives(self, kept: RoundSchedule, default_levels: u32) -> Vec<RoundSchedule> {
        let values: Vec<RoundSchedule> = match self {
            Dimension::Overlap => [None, Some(OVERLAP_REACH)]
                .map(|overlap| RoundSchedule { overlap, ..kept })
                .to_vec(),
            // The climb keeps its form (by default it follows the dispatched levels').
            Dimension::Dp => [TreeletDp::Unrolled, TreeletDp::Loop]
                .map(|dp| RoundSchedule {
                    dp: Some(dp),
                    climb_dp: Some(kept.climb_dp()),
                    ..kept
                })
                .to_vec(),
            Dimension::ClimbDp => [TreeletDp::Unrolled, TreeletDp::Loop]
                .map(|dp| RoundSchedule {
                    climb_dp: Some(dp),
                    ..kept
                })
                .to_vec(),
            // Teams do not apply to overlapped rounds.
            Dimension::TeamBelow if kept.overlap.is_some() => Vec::new(),
            Dimension::TeamBelow => TEAM_THRESHOLDS
                .map(|below| RoundSchedule {
                    team_below: Some(below),
                    ..kept
                })
                .to_vec(),
            Dimension::LevelDispatches => [
                None,
                Some(default_levels.saturating_sub(LEVEL_DISPATCH_STEP)),
                Some((default_levels + LEVEL_DISPATCH_STEP).min(MAX_LEVEL_DISPATCHES)),
            ]
            .map(|level_dispatches| RoundSchedule {
                level_dispatches,
                ..kept
            })
            .to_vec(),
        };
        let mut distinct: Vec<RoundSchedule> = Vec::new();
        for v in values {
            if !same_in_effect(v, kept, default_levels)
                && !distinct
                    .iter()
                    .any(|d| same_in_effect(*d, v, default_levels))
            {
                distinct.push(v);
            }
        }
        distinct
    }

    /// Whether `a` and `b` take the same value in this dimension.
    fn same_value(self, a: RoundSchedule, b: RoundSchedule, default_levels: u32) -> bool {
        match self {
            Dimension::Overlap => a.overlap == b.overlap,
            Dimension::Dp => a.dp() == b.dp(),
            Dimension::ClimbDp => a.climb_dp() == b.climb_dp(),
            Dimension::TeamBelow => a.team_below() == b.team_below(),
            Dimension::LevelDispatches => {
                a.level_dispatches.unwrap_or(default_levels)
                    == b.level_dispatches.unwrap_or(default_levels)
            }
        }
    }
}

/// Whether two schedules run the same way.
fn same_in_effect(a: RoundSchedule, b: RoundSchedule, default_levels: u32) -> bool {
    Dimension::ALL.iter().all(|d| {
        d.same_value(a, b, default_levels) || (*d == Dimension::TeamBelow && a.overlap.is_some())
    })
}

fn median(mut values: Vec<f64>) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Tunes the schedule from `start` (see the module header); `default_levels` is the level
/// dispatches the device would choose for the tree.
pub fn tune_schedule(
    trials: &mut impl ScheduleTrials,
    start: RoundSchedule,
    default_levels: u32,
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
    let mut refused: Vec<(Dimension, RoundSchedule)> = Vec::new();
    let mut compared: Vec<(RoundSchedule, RoundSchedule)> = Vec::new();
    for _ in 0..options.max_descents {
        let mut changed = false;
        for dimension in Dimension::ALL
            .into_iter()
            .filter(|d| !d.is_pinned(&options.pins))
        {
            for candidate in dimension.alternatives(kept, default_levels) {
                let was_refused = refused
                    .iter()
                    .any(|(d, r)| *d == dimension && d.same_value(*r, candidate, default_levels));
                let was_compared = compared.iter().any(|(k, c)| {
                    same_in_effect(*k, kept, default_levels)
                        && same_in_effect(*c, candidate, default_levels)
                });
                if was_refused || was_compared {
                    continue;
                }
                builds += 1;
                if !trials.builds_reference_tree(candidate)? {
                    log::warn!(
                        "schedule [{}] built another tree than [{}]: a kernel or device bug, or \
                         for overlapped rounds a tree where the reach does not keep the rounds' \
                         trees (README, \"Rounds can overlap\"); not used",
                        candidate.label(),
                        start.label()
                    );
                    refused.push((dimension, candidate));
                    record.push(ScheduleTrial {
                        candidate,
                        kept_ms: None,
                        candidate_ms: None,
                        other_tree: true,
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
                let kept_ms = median(kept_times);
                let candidate_ms = median(candidate_times);
                let adopted = candidate_ms < kept_ms * (1.0 - options.min_gain);
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
        schedule: kept,
        trials: record,
        builds,
        wall_ms: begin.elapsed().as_secs_f64() * 1e3,
    })
}

/// Trials on the GPU: builds of `geometry` through `updater` (a trbvh or trbvh-split one) into
/// `tree`, the starting schedule's tree read back once as the reference.
pub struct DeviceTrials<'a> {
    ctx: &'a GpuContext,
    updater: &'a mut TreeUpdater,
    geometry: &'a Geometry,
    triangles: &'a [Triangle],
    tree: &'a mut Tree,
    slab: ParamSlab,
    reference: Bvh,
}

impl<'a> DeviceTrials<'a> {
    /// Builds once with `start` and reads the tree back as the reference.
    pub fn new(
        ctx: &'a GpuContext,
        updater: &'a mut TreeUpdater,
        geometry: &'a Geometry,
        triangles: &'a [Triangle],
        tree: &'a mut Tree,
        start: RoundSchedule,
    ) -> Result<Self> {
        let mut trials = Self {
            ctx,
            updater,
            geometry,
            triangles,
            tree,
            slab: ParamSlab::new(ctx),
            reference: Bvh::default(),
        };
        trials.build(start, None)?;
        trials.reference = trials.tree.download(ctx)?;
        Ok(trials)
    }

    fn build(&mut self, schedule: RoundSchedule, timer: Option<&mut GpuTimer>) -> Result<()> {
        self.updater.set_round_schedule(schedule);
        let mut rec = Recorder::new(self.ctx, &mut self.slab, timer);
        let result = self
            .updater
            .record(&mut rec, self.geometry, self.triangles, self.tree);
        rec.submit();
        result.map(drop)
    }
}

impl ScheduleTrials for DeviceTrials<'_> {
    fn builds_reference_tree(&mut self, schedule: RoundSchedule) -> Result<bool> {
        self.build(schedule, None)?;
        Ok(self.tree.download(self.ctx)? == self.reference)
    }

    fn time_build(&mut self, schedule: RoundSchedule) -> Result<f64> {
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
    struct FakeTrials<C: Fn(RoundSchedule) -> f64, O: Fn(RoundSchedule) -> bool> {
        cost: C,
        other_tree: O,
        timed: Vec<RoundSchedule>,
    }

    impl<C: Fn(RoundSchedule) -> f64, O: Fn(RoundSchedule) -> bool> ScheduleTrials
        for FakeTrials<C, O>
    {
        fn builds_reference_tree(&mut self, schedule: RoundSchedule) -> Result<bool> {
            Ok(!(self.other_tree)(schedule))
        }

        fn time_build(&mut self, schedule: RoundSchedule) -> Result<f64> {
            self.timed.push(schedule);
            Ok((self.cost)(schedule))
        }
    }

    /// A build time with one best value per dimension: overlap 6, the loop DP in the climb,
    /// teams below 16 (no teams apply with the overlap), 11 dispatched levels.
    fn cost(s: RoundSchedule) -> f64 {
        let mut ms = 10.0;
        if s.overlap.is_none() {
            ms += 3.0 + if s.team_below() == 16 { -1.0 } else { 0.0 };
        }
        if s.climb_dp() == TreeletDp::Loop {
            ms -= 0.5;
        }
        if s.dp() == TreeletDp::Loop {
            ms += 0.1;
        }
        ms + f64::from(s.level_dispatches.unwrap_or(14).abs_diff(11)) * 0.2
    }

    fn tune(
        other_tree: impl Fn(RoundSchedule) -> bool,
        pins: SchedulePins,
        start: RoundSchedule,
    ) -> (TunedSchedule, Vec<RoundSchedule>) {
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
        let tuned = tune_schedule(&mut trials, start, 14, &options).unwrap();
        (tuned, trials.timed)
    }

    #[test]
    fn the_descent_keeps_the_fastest_schedule() {
        let (tuned, timed) = tune(|_| false, SchedulePins::default(), RoundSchedule::default());
        assert_eq!(tuned.schedule.overlap, Some(OVERLAP_REACH));
        assert_eq!(tuned.schedule.climb_dp(), TreeletDp::Loop);
        assert_eq!(tuned.schedule.dp(), TreeletDp::Unrolled);
        assert_eq!(tuned.schedule.level_dispatches, Some(11));
        // Every kept schedule beat the one before it by the margin.
        for t in tuned.trials.iter().filter(|t| t.adopted) {
            assert!(t.candidate_ms.unwrap() < t.kept_ms.unwrap() * 0.98);
        }
        // Teams were never timed once the rounds overlapped (they do not apply).
        assert!(timed
            .iter()
            .all(|s| s.overlap.is_none() || s.team_below.is_none()));
        assert_eq!(tuned.builds as usize, timed.len() + tuned.trials.len());
    }

    #[test]
    fn pinned_dimensions_keep_the_starting_values() {
        let start = RoundSchedule {
            overlap: None,
            level_dispatches: Some(14),
            ..RoundSchedule::default()
        };
        let pins = SchedulePins {
            overlap: true,
            level_dispatches: true,
            ..SchedulePins::default()
        };
        let (tuned, timed) = tune(|_| false, pins, start);
        assert!(timed
            .iter()
            .all(|s| s.overlap.is_none() && s.level_dispatches == Some(14)));
        // Without the overlap, teams below 16 pay.
        assert_eq!(tuned.schedule.team_below(), 16);
        assert_eq!(tuned.schedule.climb_dp(), TreeletDp::Loop);
    }

    #[test]
    fn a_schedule_with_another_tree_is_never_timed_or_kept() {
        let (tuned, timed) = tune(
            |s| s.overlap.is_some(),
            SchedulePins::default(),
            RoundSchedule::default(),
        );
        assert_eq!(tuned.schedule.overlap, None);
        assert!(timed.iter().all(|s| s.overlap.is_none()));
        let refused: Vec<_> = tuned.trials.iter().filter(|t| t.other_tree).collect();
        assert_eq!(refused.len(), 1, "refused once, not retried");
        assert!(refused[0].candidate_ms.is_none() && !refused[0].adopted);
        // The next best dimension still won.
        assert_eq!(tuned.schedule.team_below(), 16);
    }

    #[test]
    fn gains_below_the_margin_are_not_kept() {
        let mut trials = FakeTrials {
            cost: |s: RoundSchedule| if s.dp() == TreeletDp::Loop { 9.9 } else { 10.0 },
            other_tree: |_| false,
            timed: Vec::new(),
        };
        let tuned = tune_schedule(
            &mut trials,
            RoundSchedule::default(),
            14,
            &TuningOptions::default(),
        )
        .unwrap();
        assert_eq!(tuned.schedule, RoundSchedule::default());
        assert!(tuned.trials.iter().all(|t| !t.adopted));
        assert!(tune_schedule(
            &mut trials,
            RoundSchedule::default(),
            14,
            &TuningOptions {
                pairs: 0,
                ..TuningOptions::default()
            }
        )
        .is_err());
    }
}
