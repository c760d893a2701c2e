//! An animated scene in the viewer: the animation, its clock, the time the GPU triangles show, the
//! last animate stage's time, and the rebuild-versus-refit comparison (the companion tree and the
//! SAH history of the plot). Each animated frame records: advance the clock → animate the
//! triangles on the GPU → (the viewer updates the traced tree) → update the companion → copy
//! both trees; their SAH costs join the plot when the copies arrive, a frame or two later.
//! A new loop of the animation starts both refits over from its first frame.

use super::companion::Companion;
use super::playback::{Clock, ClockRequest, Playback};
use super::sah_history::{SahHistory, SahSample};
use super::stats::BuildTiming;
use super::tree_snapshot::{SnapshotCost, TreeSnapshot};
use crate::anim::{AnimateStage, Animation};
use crate::bvh::{BuildSchedule, SahParams, TreeUpdater, UpdateMode};
use crate::device::{Geometry, Tree};
use crate::gpu::{Recorder, StageTime};
use crate::scene::Camera;
use crate::Result;

/// What one clock step did to the scene.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Stepped {
    /// The triangles moved: the tree must be updated and accumulation restarted.
    pub moved: bool,
    /// The animation looped: refits start over from this frame.
    pub looped: bool,
    /// A CPU evaluation's time (GPU kernels are timestamped in the recording).
    pub cpu_time: Option<StageTime>,
}

/// The label prefix of the companion's build passes in the frame's recording.
pub const COMPANION_PREFIX: &str = "companion ";

/// Both trees of one animated frame, being read back for the plot.
struct PendingSample {
    t: f32,
    traced_is_refit: bool,
    traced: TreeSnapshot,
    companion: TreeSnapshot,
    traced_cost: Option<SnapshotCost>,
    companion_cost: Option<SnapshotCost>,
}

pub struct AnimatedScene {
    animation: Box<dyn Animation>,
    pub clock: Clock,
    /// The time the GPU triangles show (None until the first animate after loading).
    shown: Option<f32>,
    pub animate_time: Option<StageTime>,
    companion: Option<Companion>,
    pub companion_timing: Option<BuildTiming>,
    pub history: SahHistory,
    pending: Option<PendingSample>,
    /// Snapshots whose reads finished, kept for reuse.
    spare: Vec<TreeSnapshot>,
}

impl AnimatedScene {
    pub fn new(animation: Box<dyn Animation>) -> Self {
        Self {
            clock: Clock::new(animation.time_range()),
            animation,
            shown: None,
            animate_time: None,
            companion: None,
            companion_timing: None,
            history: SahHistory::default(),
            pending: None,
            spare: Vec::new(),
        }
    }

    pub fn stage(&self) -> AnimateStage {
        self.animation.stage()
    }

    /// The animation's camera at the current time.
    pub fn camera(&self) -> Camera {
        self.animation.camera(self.clock.t())
    }

    /// Advances the clock and records the animation of `geometry`'s triangles to the new time
    /// when they show another.
    pub fn step(
        &mut self,
        rec: &mut Recorder<'_>,
        playback: &mut Playback,
        request: ClockRequest,
        dt: f32,
        geometry: &Geometry,
    ) -> Result<Stepped> {
        let looped = self.clock.advance(playback, request, dt);
        if looped {
            self.history.clear();
            self.pending = None;
            if let Some(companion) = &mut self.companion {
                companion.reset_topology();
            }
        }
        let t = self.clock.t();
        if self.shown == Some(t) {
            return Ok(Stepped {
                moved: false,
                looped,
                cpu_time: None,
            });
        }
        let cpu_time = self.animation.animate(rec, t, geometry)?;
        self.shown = Some(t);
        Ok(Stepped {
            moved: true,
            looped,
            cpu_time,
        })
    }

    /// The companion's updater and tree where it rebuilds with a GPU builder (a traced refit's
    /// comparison), for a schedule tuning.
    pub fn tunable_companion(&mut self) -> Option<(&mut TreeUpdater, &mut Tree)> {
        self.companion.as_mut().and_then(Companion::tunable)
    }

    /// The build schedule of the companion's GPU rebuilds, where it has them.
    pub fn companion_schedule(&self) -> Option<BuildSchedule> {
        self.companion.as_ref().and_then(Companion::build_schedule)
    }

    /// After the traced tree was updated by `traced_mode` in `rec`: records the companion
    /// tree's update and copies of both trees, for the plot (`poll`). Skipped while the previous
    /// frame's copies are still in flight. A new companion's rebuilds take `schedule` (the one
    /// its builder kept at a tuning) where given.
    pub fn record_comparison(
        &mut self,
        rec: &mut Recorder<'_>,
        traced_mode: UpdateMode,
        schedule: Option<BuildSchedule>,
        geometry: &Geometry,
        traced: &Tree,
        params: &SahParams,
    ) -> Result<()> {
        let Some(mode) = Companion::mode_for(traced_mode) else {
            self.drop_companion();
            return Ok(());
        };
        if self.pending.is_some() {
            return Ok(());
        }
        if self.companion.as_ref().is_none_or(|c| c.mode() != mode) {
            let mut companion = Companion::new(rec.ctx, mode, params)?;
            if let Some(schedule) = schedule {
                companion.set_build_schedule(schedule)?;
            }
            self.companion = Some(companion);
            let (rebuild, refit) = if traced_mode.is_refit() {
                (mode, traced_mode)
            } else {
                (traced_mode, mode)
            };
            self.history = SahHistory::new(format!("rebuild ({})", rebuild.label()), refit.label());
        }
        let companion = self.companion.as_mut().expect("created above");
        rec.set_pass_prefix(COMPANION_PREFIX);
        let recorded = companion.record(rec, geometry, &[], params);
        rec.set_pass_prefix("");
        recorded?;
        let traced_copy = TreeSnapshot::record(rec, traced, self.spare.pop());
        let companion_copy = TreeSnapshot::record(rec, &companion.tree, self.spare.pop());
        self.pending = Some(PendingSample {
            t: self.clock.t(),
            traced_is_refit: traced_mode.is_refit(),
            traced: traced_copy,
            companion: companion_copy,
            traced_cost: None,
            companion_cost: None,
        });
        Ok(())
    }

    /// After the frame was submitted: starts reading the copies.
    pub fn submitted(&mut self) {
        if let Some(p) = &mut self.pending {
            p.traced.submitted();
            p.companion.submitted();
        }
    }

    /// Adds the plot sample of a finished comparison; returns the traced tree's cost.
    pub fn poll(&mut self, params: &SahParams) -> Result<Option<SnapshotCost>> {
        let Some(p) = &mut self.pending else {
            return Ok(None);
        };
        if p.traced_cost.is_none() {
            p.traced_cost = p.traced.try_cost(params).transpose()?;
        }
        if p.companion_cost.is_none() {
            p.companion_cost = p.companion.try_cost(params).transpose()?;
        }
        let (Some(traced), Some(other)) = (p.traced_cost, p.companion_cost) else {
            return Ok(None);
        };
        let p = self.pending.take().expect("checked above");
        let (rebuild, refit) = if p.traced_is_refit {
            (other.cost, traced.cost)
        } else {
            (traced.cost, other.cost)
        };
        self.history.push(SahSample {
            t: p.t,
            rebuild,
            refit,
        });
        self.spare.extend([p.traced, p.companion]);
        Ok(Some(traced))
    }

    /// Stops comparing (the companion tree is freed, the plot kept).
    pub fn drop_companion(&mut self) {
        self.companion = None;
        self.companion_timing = None;
        self.pending = None;
    }
}
