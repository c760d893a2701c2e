//! The viewer's state and the work of one frame, in the order the design fixes:
//!
//! ```text
//! UI (panel, camera input) ─► apply changes ─► animate ─► build BVH ─► trace ─► (display)
//! ```
//!
//! Accumulation goes on while nothing changes and restarts on any change (camera, settings, scene,
//! window size, and every animated frame). Animated scenes (`crate::anim`) move their triangles on
//! the GPU in the animate step (`animated_scene`), then the tree is rebuilt (or refitted) in place.
//! With the wide layout setting every update also converts the tree (`tree.wide`, stage "wide")
//! and the tracer traces that; a layout change rebuilds the tree and recreates the tracer before
//! the frame's build, so the frame that first traces the wide layout has converted it.
//!
//! A frame is recorded, not waited for: animate, build, trace and tonemap go into one recording
//! and one submission. The frame's statistics (stage times, rays, tree size) and the trees' SAH
//! costs are read back without waiting and shown a frame or two late (`frame_readback`,
//! `tree_snapshot`). What still waits for the GPU, off the per-frame path: loading a scene (its
//! first build), deriving a refit's links once per topology, screenshots, and the trade-off
//! window's measurements. User errors (an unloadable file, a scene too large for the device) are
//! shown in the panel; the previous scene stays and the viewer keeps running. Displaying the
//! image and the panel is `window_app`'s part.
//!
//! On a GPU the build schedule of a GPU builder's rebuilds is tuned once its updater has run
//! `AUTO_TUNE_FRAMES` frames (the clocks are up by then; `bvh::tune_updater`, which waits for its
//! builds: about a hundred of them, a second or less), at once where `--tune-schedule on` asks, and again on the
//! panel's request; every schedule builds the same tree, so only the build times change. The
//! schedule a builder kept is used again by later updaters of its rebuilds (a switch back to the
//! builder, the companion rebuild beside a traced refit) without another tuning. Beside a traced
//! refit the tuning times the companion's rebuilds, the only ones in view.

use std::sync::Arc;
use std::time::Instant;

use super::animated_scene::AnimatedScene;
use super::camera_control::CameraInput;
use super::companion::Companion;
use super::display::PixelRect;
use super::frame_readback::{FrameReadback, FrameRecord, FrameResult};
use super::options::{default_update_mode, ViewerOptions};
use super::panel::{
    self, AnimationInfo, PanelActions, PanelControls, PanelInfo, ScheduleInfo, SAH_INTERVAL_S,
};
use super::playback::{ClockRequest, Playback};
use super::sah_reference::{ReferenceKey, SahReference};
use super::settings::ViewSettings;
use super::stats::{BuildTiming, FrameStats, TreeSah};
use super::tradeoff_panel::{StudyScene, TradeoffPanel};
use super::tree_snapshot::TreeSnapshot;
use crate::anim::{is_animation, load_animation};
use crate::bvh::wide::Layout;
use crate::bvh::{
    tune_updater, tunes_by_default, BuildSchedule, Builder, TreeUpdater, TunedSchedule,
    TuningOptions, UpdateMode,
};
use crate::device::{Geometry, Tree};
use crate::gpu::{GpuContext, ParamSlab, Recorder};
use crate::scene::{load_scene, Camera, Scene};
use crate::trace::{PathTracer, RenderSettings};
use crate::Result;

/// Frames a GPU builder's updater runs on a GPU before its build schedule is tuned.
const AUTO_TUNE_FRAMES: u64 = 120;

/// The current tree's SAH needs measuring: now (a new tree) or when the interval has passed
/// (the same tree rebuilt; animated scenes will change it between frames).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SahDue {
    No,
    Periodic,
    Now,
}

pub struct Viewer {
    scene: Arc<Scene>,
    /// Incremented on every scene load (keys the SAH reference).
    scene_id: u64,
    scene_radius: f32,
    geometry: Geometry,
    tree: Tree,
    /// (nodes, references) of the traced tree, as last read back.
    tree_counts: (u32, u32),
    /// (wide nodes, references) of its wide layout, as last read back (None: binary layout).
    wide_counts: Option<(u32, u32)>,
    updater: TreeUpdater,
    /// The tree no longer matches the settings or the geometry: build before tracing.
    tree_dirty: bool,
    sah_due: SahDue,
    tracer: Option<PathTracer>,
    camera: Camera,
    controls: PanelControls,
    /// The settings in effect (`controls.settings` is what the panel shows and edits).
    applied: ViewSettings,
    restart_accumulation: bool,
    /// A build or trace failed: stop both until something changes (the last image stays).
    halted: bool,
    image_rect: PixelRect,
    stats: FrameStats,
    reference: SahReference,
    error: Option<String>,
    screenshot_message: Option<String>,
    tradeoff: TradeoffPanel,
    /// The animation of an animated scene (None for static scenes).
    animated: Option<AnimatedScene>,
    /// The triangles or the tree changed since the rebuild-versus-refit comparison last ran.
    compare_due: bool,
    /// Parameters of the frame's recording.
    params: ParamSlab,
    /// The frames' statistics on their way back.
    frame_readback: FrameReadback,
    /// A copy of the traced tree on its way back for its SAH cost.
    sah_snapshot: Option<TreeSnapshot>,
    sah_pending: bool,
    /// The last schedule tuning of the current updater and the scene it ran on.
    tuned: Option<(TunedSchedule, String)>,
    /// The schedule each GPU builder kept at its last tuning: a new updater of that builder's
    /// rebuilds (the traced one, or the companion of a traced refit) starts from it.
    kept_schedules: Vec<(Builder, BuildSchedule)>,
    /// The frame at which the current updater's schedule is tuned (None: done, or not asked).
    auto_tune_at: Option<u64>,
    /// `ViewerOptions::tune_schedule`.
    tune_option: Option<bool>,
}

impl Viewer {
    /// Loads and builds the first scene; errors here end the program (bad command line).
    pub fn new(ctx: &GpuContext, options: &ViewerOptions) -> Result<Self> {
        let requested = options
            .builder
            .unwrap_or_else(|| default_update_mode(ctx.info.device_type));
        let settings = ViewSettings::new(mode_for_scene(&options.scene, requested));
        let mut updater = TreeUpdater::new(ctx, settings.builder, &settings.sah_params())?;
        updater.set_wide_collapse(settings.wide_collapse);
        updater.set_layout(ctx, settings.layout);
        let loaded = load_and_build(ctx, &options.scene, &mut updater)?;
        let mut viewer = Self {
            scene_radius: scene_radius(&loaded.scene),
            camera: loaded.scene.camera,
            scene: loaded.scene,
            scene_id: 0,
            geometry: loaded.geometry,
            tree_counts: loaded.tree.counts(ctx)?,
            wide_counts: loaded.tree.wide.as_ref().and_then(|w| w.counts(ctx).ok()),
            tree: loaded.tree,
            updater,
            tree_dirty: false,
            sah_due: SahDue::Now,
            tracer: None,
            controls: PanelControls {
                settings,
                obj_path: String::new(),
                playback: Playback::default(),
            },
            applied: settings,
            restart_accumulation: true,
            halted: false,
            image_rect: PixelRect::default(),
            stats: FrameStats::default(),
            reference: SahReference::default(),
            error: None,
            screenshot_message: None,
            tradeoff: TradeoffPanel::default(),
            animated: loaded.animated,
            compare_due: true,
            params: ParamSlab::new(ctx),
            frame_readback: FrameReadback::new(ctx),
            sah_snapshot: None,
            sah_pending: false,
            tuned: None,
            kept_schedules: Vec::new(),
            auto_tune_at: None,
            tune_option: options.tune_schedule,
        };
        viewer.new_updater(ctx);
        viewer.stats.build = Some(loaded.timing);
        viewer.request_reference();
        Ok(viewer)
    }

    /// Draws the panel and the image area into `ui` and reads the camera input; `target` is the
    /// render target's size in pixels. Returns the panel's actions for `update`.
    pub fn run_ui(
        &mut self,
        ui: &mut egui::Ui,
        adapter: &wgpu::AdapterInfo,
        target: (u32, u32),
    ) -> PanelActions {
        self.stats.tick(Instant::now());
        let (width, height) = self
            .tracer
            .as_ref()
            .map_or((0, 0), |t| (t.settings().width, t.settings().height));
        let info = PanelInfo {
            adapter,
            stats: &self.stats,
            scene_name: &self.scene.name,
            triangles: self.geometry.triangle_count,
            nodes: self.tree_counts.0,
            references: self.tree_counts.1,
            layout: self.traced_layout(),
            wide_collapse: self.applied.wide_collapse,
            wide_counts: self.wide_counts,
            samples: self.tracer.as_ref().map_or(0, |t| t.samples_done()),
            resolution: (width, height),
            reference: self.reference.state(),
            error: self.error.as_deref(),
            screenshot: self.screenshot_message.as_deref(),
            schedule: schedule_info(&self.updater, self.animated.as_ref(), self.tuned.as_ref()),
            animation: self.animated.as_ref().map(|a| AnimationInfo {
                clock: a.clock,
                stage: a.stage(),
                animate_ms: a.animate_time.as_ref().and_then(|s| s.ms),
                companion: a.companion_timing.as_ref(),
                history: &a.history,
            }),
        };
        let actions = panel::show(ui, &info, &mut self.controls);
        self.tradeoff.show(ui.ctx());
        egui::CentralPanel::no_frame().show(ui, |ui| {
            let (rect, response) =
                ui.allocate_exact_size(ui.available_size(), egui::Sense::click_and_drag());
            self.image_rect = PixelRect::from_points(rect, ui.ctx().pixels_per_point(), target);
            if CameraInput::read(ui, &response).apply(&mut self.camera, self.scene_radius) {
                self.controls.playback.follow_camera = false;
                self.something_changed();
            }
        });
        actions
    }

    /// Applies the panel's actions and settings, then records one frame (animate, build, trace,
    /// tonemap) and submits it; takes in the statistics of earlier frames that have arrived.
    pub fn update(&mut self, ctx: &GpuContext, actions: PanelActions) {
        self.reference.poll();
        self.take_readbacks(ctx);
        if let Some(name) = actions.load_scene {
            self.load(ctx, &name);
        }
        if actions.reset_camera {
            self.error = None;
            self.camera = self.scene.camera;
            self.something_changed();
        }
        self.apply_settings(ctx);
        let auto_tune = self.auto_tune_at.is_some_and(|at| self.stats.frames >= at);
        if actions.tune_schedule || auto_tune {
            self.tune_schedule(ctx);
        }
        self.fit_tracer(ctx);
        if self.halted {
            return;
        }
        let start = Instant::now();
        let mut record = FrameRecord::default();
        let mut timer = self.frame_readback.begin();
        let mut params = std::mem::replace(&mut self.params, ParamSlab::new(ctx));
        let mut rec = Recorder::new(ctx, &mut params, timer.as_mut());
        let outcome = self.record_frame(&mut rec, actions.clock, &mut record);
        record.wall_ms = start.elapsed().as_secs_f64() * 1e3;
        let counters = self.tracer.as_ref().map(|t| t.counters().clone());
        self.frame_readback
            .record(&mut rec, counters.as_ref(), &self.tree, record);
        rec.submit();
        self.params = params;
        self.frame_readback.submitted(timer);
        if let Some(animated) = &mut self.animated {
            animated.submitted();
        }
        if let Some(snapshot) = self.sah_snapshot.as_mut().filter(|_| self.sah_pending) {
            snapshot.submitted();
        }
        if let Err(e) = outcome {
            self.error = Some(e);
            self.halted = true;
        }
        let study = StudyScene {
            scene: &self.scene,
            scene_id: self.scene_id,
            camera: &self.camera,
            max_depth: self.applied.max_depth(),
            sah: self.applied.sah_params(),
        };
        self.tradeoff.step(ctx, &study);
    }

    /// The frame's work, in order, into `rec`: animate → build → compare → measure → trace →
    /// tonemap. Errors stop the frame with a message for the panel.
    fn record_frame(
        &mut self,
        rec: &mut Recorder<'_>,
        clock: ClockRequest,
        record: &mut FrameRecord,
    ) -> std::result::Result<(), String> {
        if self.animate(rec, clock, record)? {
            self.tree_dirty = true;
            self.restart_accumulation = true;
        }
        self.build(rec, record)?;
        self.compare(rec)?;
        self.measure_sah(rec);
        self.trace(rec, record)?;
        Ok(())
    }

    /// Takes in what the GPU has finished: frames' statistics, the comparison's SAH costs, the
    /// traced tree's SAH cost.
    fn take_readbacks(&mut self, ctx: &GpuContext) {
        // Non-blocking: runs the callbacks of readbacks that are done.
        let _ = ctx.device.poll(wgpu::PollType::Poll);
        for result in self.frame_readback.poll(ctx) {
            self.take_frame_result(result);
        }
        let params = self.applied.sah_params();
        if let Some(animated) = &mut self.animated {
            match animated.poll(&params) {
                Ok(Some(traced)) => {
                    self.stats.tree_sah = Some(TreeSah {
                        cost: traced.cost,
                        leaves: traced.leaves,
                        measured: Instant::now(),
                    });
                }
                Ok(None) => {}
                Err(e) => self.error = Some(format!("rebuild/refit comparison failed: {e}")),
            }
        }
        if self.sah_pending {
            if let Some(cost) = self.sah_snapshot.as_mut().and_then(|s| s.try_cost(&params)) {
                self.sah_pending = false;
                match cost {
                    Ok(c) => {
                        self.stats.tree_sah = Some(TreeSah {
                            cost: c.cost,
                            leaves: c.leaves,
                            measured: Instant::now(),
                        })
                    }
                    Err(e) => self.error = Some(format!("cannot read the tree back: {e}")),
                }
            }
        }
    }

    fn take_frame_result(&mut self, result: FrameResult) {
        if let Some(build) = result.build {
            self.stats.build = Some(build);
        }
        if let Some(trace) = result.trace {
            self.stats.trace = Some(trace);
        }
        if let Some(animated) = &mut self.animated {
            if let Some(time) = result.animate {
                animated.animate_time = Some(time);
            }
            if let Some(timing) = result.companion {
                animated.companion_timing = Some(timing);
            }
        }
        self.tree_counts = result.tree_counts;
        self.wide_counts = result.wide_counts;
        if result.wide_overflowed {
            self.error = Some("the wide conversion ran out of nodes".into());
            self.halted = true;
        }
        if result.overflows > 0 {
            self.error = Some(format!(
                "{} paths overflowed the traversal stack (tree deeper than the kernel supports)",
                result.overflows
            ));
            self.halted = true;
        }
    }

    /// The animation step of the frame: advances the clock of an animated scene and records the
    /// move of its triangles. Returns whether they moved (the tree is then rebuilt or refitted
    /// and accumulation restarts). Static scenes never move.
    fn animate(
        &mut self,
        rec: &mut Recorder<'_>,
        request: ClockRequest,
        record: &mut FrameRecord,
    ) -> std::result::Result<bool, String> {
        let Some(animated) = self.animated.as_mut() else {
            return Ok(false);
        };
        let dt = self
            .stats
            .history
            .back()
            .map_or(0.0, |ms| (ms * 1e-3) as f32);
        let playback = &mut self.controls.playback;
        let stepped = animated
            .step(rec, playback, request, dt, &self.geometry)
            .map_err(|e| format!("animation failed: {e}"))?;
        if stepped.looped {
            // Refits start over from the first frame of each loop.
            self.updater.reset();
        }
        if stepped.moved {
            if playback.follow_camera {
                self.camera = animated.camera();
            }
            self.compare_due = true;
            record.animated = true;
            record.animate_cpu = stepped.cpu_time;
        }
        Ok(stepped.moved)
    }

    /// Animated scenes with the comparison on: after the traced tree was updated, records the
    /// second tree's update and copies of both trees for the SAH plot.
    fn compare(&mut self, rec: &mut Recorder<'_>) -> std::result::Result<(), String> {
        let companion_schedule =
            Companion::mode_for(self.applied.builder).and_then(|mode| self.kept_schedule(mode));
        let Some(animated) = self.animated.as_mut() else {
            return Ok(());
        };
        if !self.controls.playback.compare {
            animated.drop_companion();
            return Ok(());
        }
        if !self.compare_due {
            return Ok(());
        }
        self.compare_due = false;
        let params = self.applied.sah_params();
        let recorded = animated.record_comparison(
            rec,
            self.applied.builder,
            companion_schedule,
            &self.geometry,
            &self.tree,
            &params,
        );
        if let Err(e) = recorded {
            self.controls.playback.compare = false;
            return Err(format!("rebuild/refit comparison failed: {e}"));
        }
        self.sah_due = SahDue::No;
        Ok(())
    }

    /// The tonemapped pixels and where to show them, once something has been traced at the
    /// image area's current size.
    pub fn image(&self) -> Option<(&wgpu::Buffer, PixelRect)> {
        self.displayable_tracer()
            .map(|tracer| (tracer.pixels(), self.image_rect))
    }

    fn displayable_tracer(&self) -> Option<&PathTracer> {
        self.tracer.as_ref().filter(|t| {
            let s = t.settings();
            t.samples_done() > 0
                && (s.width, s.height) == (self.image_rect.width, self.image_rect.height)
        })
    }

    /// The layout the tracer traces (the settings' before the first tracer exists).
    fn traced_layout(&self) -> Layout {
        self.tracer
            .as_ref()
            .map_or(self.applied.layout, |t| t.settings().layout)
    }

    /// One line on how the viewer ran: frame time, fps, ray throughput, accumulated samples.
    pub fn summary(&self) -> String {
        let frame = match (self.stats.frame_ms, self.stats.fps()) {
            (Some(ms), Some(fps)) => format!("{ms:.1} ms/frame ({fps:.2} fps)"),
            _ => "frame time n/a".into(),
        };
        let mrays = self
            .stats
            .trace
            .and_then(|t| t.mrays_per_s())
            .map_or("n/a".into(), |m| format!("{m:.2}"));
        let (spp, width, height) = self.tracer.as_ref().map_or((0, 0, 0), |t| {
            (t.samples_done(), t.settings().width, t.settings().height)
        });
        format!(
            "viewer: {} ({} layout) on {}: {} frames, {frame}, {mrays} Mrays/s, {spp} spp at \
             {width}x{height}",
            self.updater.mode().name(),
            self.traced_layout().name(),
            self.scene.name,
            self.stats.frames
        )
    }

    /// Reports the outcome of a screenshot in the panel.
    pub fn screenshot_done(&mut self, outcome: Result<String>) {
        match outcome {
            Ok(message) => self.screenshot_message = Some(message),
            Err(e) => self.error = Some(format!("screenshot failed: {e}")),
        }
    }

    fn something_changed(&mut self) {
        self.restart_accumulation = true;
        self.halted = false;
    }

    fn load(&mut self, ctx: &GpuContext, name: &str) {
        self.error = None;
        let mode = mode_for_scene(name, self.applied.builder);
        if mode != self.applied.builder {
            match TreeUpdater::new(ctx, mode, &self.applied.sah_params()) {
                Ok(mut updater) => {
                    updater.set_wide_collapse(self.applied.wide_collapse);
                    updater.set_layout(ctx, self.applied.layout);
                    self.updater = updater;
                    self.new_updater(ctx);
                    self.applied.select_builder(mode);
                    self.controls.settings.select_builder(mode);
                }
                Err(e) => {
                    self.error = Some(format!("cannot load '{name}': {e}"));
                    return;
                }
            }
        }
        match load_and_build(ctx, name, &mut self.updater) {
            Ok(loaded) => {
                log::info!(
                    "viewer: loaded {} ({} triangles)",
                    loaded.scene.name,
                    loaded.scene.triangles.len()
                );
                self.camera = loaded.scene.camera;
                self.scene_radius = scene_radius(&loaded.scene);
                self.scene = loaded.scene;
                self.scene_id += 1;
                self.tree_counts = loaded.tree.counts(ctx).unwrap_or_default();
                self.wide_counts = loaded.tree.wide.as_ref().and_then(|w| w.counts(ctx).ok());
                self.geometry = loaded.geometry;
                self.tree = loaded.tree;
                self.sah_pending = false;
                self.stats.build = Some(loaded.timing);
                self.stats.tree_sah = None;
                self.tree_dirty = false;
                self.sah_due = SahDue::Now;
                self.animated = loaded.animated;
                self.compare_due = true;
                self.controls.playback.follow_camera = true;
                self.request_reference();
                self.something_changed();
            }
            Err(e) => {
                log::warn!("viewer: cannot load '{name}': {e}");
                self.error = Some(format!("cannot load '{name}': {e}"));
            }
        }
    }

    fn apply_settings(&mut self, ctx: &GpuContext) {
        let wanted = self.controls.settings;
        if wanted == self.applied {
            return;
        }
        self.error = None;
        if wanted.builder != self.applied.builder {
            match TreeUpdater::new(ctx, wanted.builder, &wanted.sah_params()) {
                Ok(mut updater) => {
                    updater.set_wide_collapse(wanted.wide_collapse);
                    updater.set_layout(ctx, wanted.layout);
                    self.updater = updater;
                    self.new_updater(ctx);
                    self.tree_dirty = true;
                }
                Err(e) => {
                    self.error = Some(e.to_string());
                    self.controls.settings.builder = self.applied.builder;
                    return;
                }
            }
        }
        if wanted.max_leaf_size != self.applied.max_leaf_size {
            self.tree_dirty = true;
            self.updater.reset();
        }
        if wanted.layout != self.applied.layout {
            // The next update converts the tree (or drops its wide layout); `fit_tracer` makes a
            // tracer of the new layout, and this frame's build precedes its trace.
            self.updater.set_layout(ctx, wanted.layout);
            self.tree_dirty = true;
        }
        if wanted.wide_collapse != self.applied.wide_collapse {
            // Converted again by the next update (a binary layout keeps it for later).
            self.updater.set_wide_collapse(wanted.wide_collapse);
            self.tree_dirty = true;
        }
        self.applied = wanted;
        self.request_reference();
        self.something_changed();
    }

    /// A new updater: no tuning yet; one at its next frame where asked, or after
    /// `AUTO_TUNE_FRAMES` frames on a GPU by default, of the GPU rebuilds it brings: its own, or
    /// beside a refit the comparison's. None where that builder kept a schedule before (which the
    /// updater, or the comparison when it is made, takes), unless `--tune-schedule on`.
    fn new_updater(&mut self, ctx: &GpuContext) {
        self.tuned = None;
        let mode = self.updater.mode();
        let rebuilds = if mode.is_refit() {
            Companion::mode_for(mode)
        } else {
            Some(mode).filter(|_| self.updater.is_tunable())
        };
        let Some(rebuilds) = rebuilds else {
            self.auto_tune_at = None;
            return;
        };
        if let Some(schedule) = self.kept_schedule(rebuilds) {
            if !mode.is_refit() {
                if let Err(e) = self.updater.set_build_schedule(schedule) {
                    self.error = Some(format!("cannot use the tuned schedule: {e}"));
                }
            }
            if self.tune_option != Some(true) {
                self.auto_tune_at = None;
                return;
            }
        }
        let delay = match self.tune_option {
            Some(true) => Some(0),
            Some(false) => None,
            None => tunes_by_default(ctx).then_some(AUTO_TUNE_FRAMES),
        };
        self.auto_tune_at = delay.map(|d| self.stats.frames + d);
    }

    /// Tunes the build schedule on the current geometry (see the module header); a failure
    /// shows in the panel and keeps the schedule.
    fn tune_schedule(&mut self, ctx: &GpuContext) {
        let pending = self.auto_tune_at.take();
        let options = TuningOptions::default();
        let (mode, tuned) = if self.updater.is_tunable() {
            let tuned = tune_updater(
                ctx,
                &mut self.updater,
                &self.geometry,
                &self.scene.triangles,
                &mut self.tree,
                &options,
                0.0,
            );
            (self.updater.mode(), tuned)
        } else if let Some((updater, tree)) = self
            .animated
            .as_mut()
            .and_then(AnimatedScene::tunable_companion)
        {
            // A traced refit: the comparison's rebuilds (GPU-resident geometry, as it records).
            let tuned = tune_updater(ctx, updater, &self.geometry, &[], tree, &options, 0.0);
            (updater.mode(), tuned)
        } else {
            // Beside a refit, the comparison is made at its first frame: tune it then.
            self.auto_tune_at = pending.map(|at| at.max(self.stats.frames + 1));
            return;
        };
        match tuned {
            Ok(Some(tuned)) => {
                log::info!(
                    "viewer: schedule [{}] kept after {} builds in {:.0} ms",
                    tuned.schedule.label(),
                    tuned.builds,
                    tuned.wall_ms
                );
                if let UpdateMode::Rebuild(builder) = mode {
                    self.kept_schedules.retain(|(b, _)| *b != builder);
                    self.kept_schedules.push((builder, tuned.schedule));
                }
                self.tuned = Some((tuned, self.scene.name.clone()));
            }
            Ok(None) => {}
            Err(e) => self.error = Some(format!("schedule tuning failed: {e}")),
        }
        // The tuning's builds left the same tree; the next frame builds it as usual.
        self.tree_dirty = true;
    }

    /// The schedule kept for `mode`'s builder at its last tuning, for rebuilds.
    fn kept_schedule(&self, mode: UpdateMode) -> Option<BuildSchedule> {
        let UpdateMode::Rebuild(builder) = mode else {
            return None;
        };
        self.kept_schedules
            .iter()
            .find(|(b, _)| *b == builder)
            .map(|&(_, schedule)| schedule)
    }

    fn request_reference(&mut self) {
        let params = self.applied.sah_params();
        let key = ReferenceKey {
            scene_id: self.scene_id,
            max_leaf_size: params.max_leaf_size,
        };
        self.reference.request(key, &self.scene, params);
    }

    /// Makes the tracer match the image area's size, the bounce setting and the layout (a new
    /// tracer starts accumulating from zero).
    fn fit_tracer(&mut self, ctx: &GpuContext) {
        let rect = self.image_rect;
        if rect.is_empty() {
            return;
        }
        let wanted = RenderSettings {
            width: rect.width,
            height: rect.height,
            max_depth: self.applied.max_depth(),
            layout: self.applied.layout,
            ..RenderSettings::default()
        };
        if self.tracer.as_ref().is_some_and(|t| t.settings() == wanted) {
            return;
        }
        self.tracer = None;
        match PathTracer::new(ctx, wanted) {
            Ok(tracer) => {
                self.tracer = Some(tracer);
                self.something_changed();
            }
            Err(e) => {
                self.error = Some(format!(
                    "cannot trace at {}×{}: {e}",
                    rect.width, rect.height
                ));
                self.halted = true;
            }
        }
    }

    /// Records the tree's rebuild or refit when it is due.
    fn build(
        &mut self,
        rec: &mut Recorder<'_>,
        record: &mut FrameRecord,
    ) -> std::result::Result<(), String> {
        if !(self.tree_dirty || self.applied.rebuilds_every_frame()) {
            return Ok(());
        }
        self.updater.set_sah_params(self.applied.sah_params());
        let triangles = match &self.animated {
            // CPU reference builders are not offered for animated scenes (GPU modes only).
            Some(_) => Vec::new(),
            None => self.scene.triangles.clone(),
        };
        let built = self
            .updater
            .record(rec, &self.geometry, &triangles, &mut self.tree);
        // A failed update is tried again after the next change (not traced as it stands: a
        // wide-layout tracer needs the conversion).
        self.tree_dirty = built.is_err();
        match built {
            Ok(cpu_time) => {
                record.built = true;
                record.build_cpu = cpu_time;
                self.sah_due = if self.sah_due == SahDue::Now || !record.animated {
                    SahDue::Now
                } else {
                    self.sah_due.max_periodic()
                };
                Ok(())
            }
            Err(e) => Err(format!("{} build failed: {e}", self.updater.mode().name())),
        }
    }

    /// Records a copy of the tree for its SAH cost when it is new, or periodically while it is
    /// rebuilt (the copy is read a frame or two later; one at a time).
    fn measure_sah(&mut self, rec: &mut Recorder<'_>) {
        let due = match self.sah_due {
            SahDue::No => false,
            SahDue::Now => true,
            SahDue::Periodic => self
                .stats
                .tree_sah
                .is_none_or(|s| s.measured.elapsed().as_secs_f64() >= SAH_INTERVAL_S),
        };
        if !due || self.sah_pending {
            return;
        }
        self.sah_due = SahDue::No;
        self.sah_snapshot = Some(TreeSnapshot::record(
            rec,
            &self.tree,
            self.sah_snapshot.take(),
        ));
        self.sah_pending = true;
    }

    /// Records the frame's samples and the tonemap.
    fn trace(
        &mut self,
        rec: &mut Recorder<'_>,
        record: &mut FrameRecord,
    ) -> std::result::Result<(), String> {
        let Some(tracer) = self.tracer.as_mut() else {
            return Ok(());
        };
        if self.restart_accumulation {
            tracer.reset();
            self.restart_accumulation = false;
        }
        let recorded = tracer
            .record(
                rec,
                &self.geometry,
                &self.tree,
                &self.camera,
                self.scene.sky,
                self.applied.samples_per_frame,
            )
            .map_err(|e| format!("trace failed: {e}"))?;
        record.trace = Some(recorded);
        tracer.record_tonemap(rec);
        Ok(())
    }
}

/// The GPU rebuilds' schedule for the panel: the traced `updater`'s, or beside a traced refit the
/// comparison's; with the last tuning.
fn schedule_info<'a>(
    updater: &TreeUpdater,
    animated: Option<&AnimatedScene>,
    tuned: Option<&'a (TunedSchedule, String)>,
) -> Option<ScheduleInfo<'a>> {
    let (current, of_comparison) = if updater.is_tunable() {
        (updater.build_schedule(), false)
    } else {
        (animated?.companion_schedule()?, true)
    };
    Some(ScheduleInfo {
        current,
        of_comparison,
        tuned: tuned.map(|(t, scene)| (t, scene.as_str())),
    })
}

impl SahDue {
    /// `Periodic` unless a measurement is already due now.
    fn max_periodic(self) -> Self {
        match self {
            SahDue::Now => SahDue::Now,
            _ => SahDue::Periodic,
        }
    }
}

/// A freshly loaded scene, on the GPU with its first tree.
struct LoadedScene {
    /// A static scene, or an animated one at its start time.
    scene: Arc<Scene>,
    geometry: Geometry,
    tree: Tree,
    timing: BuildTiming,
    animated: Option<AnimatedScene>,
}

/// The tree update to use for scene `name`: animated scenes need a GPU mode (CPU reference builders
/// fall back to LBVH), static scenes have nothing to refit (a refit mode falls back to a rebuild
/// with its builder).
fn mode_for_scene(name: &str, mode: UpdateMode) -> UpdateMode {
    match (is_animation(name), mode) {
        (true, m) if !m.is_gpu() => UpdateMode::Rebuild(Builder::Lbvh),
        (false, UpdateMode::Refit(b)) => UpdateMode::Rebuild(b),
        (_, m) => m,
    }
}

/// Loads `name` (a static or an animated scene), uploads it and builds its first tree with
/// `updater` (waiting for it: loading is not on the per-frame path).
fn load_and_build(ctx: &GpuContext, name: &str, updater: &mut TreeUpdater) -> Result<LoadedScene> {
    let (scene, animated) = if is_animation(name) {
        let animation = load_animation(name)?;
        let scene = animation.scene_at(animation.time_range().start);
        (scene, Some(AnimatedScene::new(animation)))
    } else {
        (load_scene(name)?, None)
    };
    let scene = Arc::new(scene);
    let geometry = Geometry::upload(ctx, &scene)?;
    let mut tree = Tree::empty(ctx)?;
    let mut timer = crate::gpu::GpuTimer::new(ctx, updater.pass_count());
    let mut params = ParamSlab::new(ctx);
    let start = Instant::now();
    let mut rec = Recorder::new(ctx, &mut params, Some(&mut timer));
    updater.reset();
    let built = updater.record(&mut rec, &geometry, &scene.triangles, &mut tree);
    rec.submit();
    let cpu_time = built?;
    let mut stages = timer.read(ctx)?;
    stages.extend(cpu_time);
    Ok(LoadedScene {
        scene,
        geometry,
        tree,
        timing: BuildTiming::from_stages(stages, start.elapsed().as_secs_f64() * 1e3),
        animated,
    })
}

/// Half the diagonal of the scene's bounds (sets the fly speed).
fn scene_radius(scene: &Scene) -> f32 {
    let radius = 0.5 * scene.bounds().extent().length();
    if radius.is_finite() && radius > 0.0 {
        radius
    } else {
        1.0
    }
}
