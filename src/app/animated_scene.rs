//! An animated scene in the viewer: the animation, its clock, the time the GPU triangles show, the
//! last animate stage's time, and the rebuild-versus-refit comparison (the companion tree and the
//! SAH history of the plot). Each animated frame: advance the clock → animate the triangles on
//! the GPU → (the viewer updates the traced tree) → update the companion → measure both SAHs.
//! A new loop of the animation starts both refits over from its first frame.

use super::companion::Companion;
use super::frame_builder::BuildTiming;
use super::playback::{Clock, ClockRequest, Playback};
use super::sah_history::{SahHistory, SahSample};
use crate::anim::{AnimateStage, Animation, UpdateMode};
use crate::bvh::{sah_cost, SahParams};
use crate::gpu::{GpuContext, StageTime};
use crate::scene::Camera;
use crate::trace::GpuScene;
use crate::Result;

/// What one clock step did to the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Stepped {
    /// The triangles moved: the tree must be updated and accumulation restarted.
    pub moved: bool,
    /// The animation looped: refits start over from this frame.
    pub looped: bool,
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
        }
    }

    pub fn stage(&self) -> AnimateStage {
        self.animation.stage()
    }

    /// The animation's camera at the current time.
    pub fn camera(&self) -> Camera {
        self.animation.camera(self.clock.t())
    }

    /// Advances the clock and animates `scene`'s triangles to the new time when they show another.
    pub fn step(
        &mut self,
        ctx: &GpuContext,
        playback: &mut Playback,
        request: ClockRequest,
        dt: f32,
        scene: &mut GpuScene,
    ) -> Result<Stepped> {
        let looped = self.clock.advance(playback, request, dt);
        if looped {
            self.history.clear();
            if let Some(companion) = &mut self.companion {
                companion.reset_topology();
            }
        }
        let t = self.clock.t();
        if self.shown == Some(t) {
            return Ok(Stepped {
                moved: false,
                looped,
            });
        }
        self.animate_time = Some(self.animation.animate(ctx, t, scene)?);
        self.shown = Some(t);
        Ok(Stepped {
            moved: true,
            looped,
        })
    }

    /// After the traced tree was updated by `traced_mode` for the current triangles: updates the
    /// companion tree and records both trees' SAH cost at the current time. Returns the traced
    /// tree's SAH cost and leaf count.
    pub fn compare(
        &mut self,
        ctx: &GpuContext,
        traced_mode: UpdateMode,
        traced: &GpuScene,
        params: &SahParams,
    ) -> Result<(f32, usize)> {
        let bvh = traced.download_bvh(ctx)?;
        let traced_cost = sah_cost(&bvh, params);
        let Some(mode) = Companion::mode_for(traced_mode) else {
            self.drop_companion();
            return Ok((traced_cost, bvh.leaf_count()));
        };
        if self
            .companion
            .as_ref()
            .is_none_or(|c| c.mode() != mode || !c.shares(traced))
        {
            self.companion = Some(Companion::new(ctx, mode, traced, params)?);
            let (rebuild, refit) = if traced_mode.is_refit() {
                (mode, traced_mode)
            } else {
                (traced_mode, mode)
            };
            self.history = SahHistory::new(format!("rebuild ({})", rebuild.label()), refit.label());
        }
        let companion = self.companion.as_mut().expect("created above");
        self.companion_timing = Some(companion.update(ctx, params)?);
        let other = companion.sah(ctx, params)?;
        let (rebuild, refit) = if traced_mode.is_refit() {
            (other, traced_cost)
        } else {
            (traced_cost, other)
        };
        self.history.push(SahSample {
            t: self.clock.t(),
            rebuild,
            refit,
        });
        Ok((traced_cost, bvh.leaf_count()))
    }

    /// Stops comparing (the companion tree is freed, the plot kept).
    pub fn drop_companion(&mut self) {
        self.companion = None;
        self.companion_timing = None;
    }
}
