//! The viewer's state and the work of one frame, in the order the design fixes:
//!
//! ```text
//! UI (panel, camera input) ─► apply changes ─► animate ─► build BVH ─► trace ─► (display)
//! ```
//!
//! Accumulation goes on while nothing changes and restarts on any change (camera, settings, scene,
//! window size, and every animated frame). Animated scenes (`crate::anim`) move their triangles on
//! the GPU in the animate step (`animated_scene`), then the tree is rebuilt (or refitted) in place. User errors (an unloadable file, a scene too large for the device) are shown in
//! the panel; the previous scene stays and the viewer keeps running. Displaying the image and the
//! panel is `window_app`'s part.

use std::sync::Arc;
use std::time::Instant;

use super::animated_scene::AnimatedScene;
use super::camera_control::CameraInput;
use super::display::PixelRect;
use super::frame_builder::{BuildTiming, FrameBuilder};
use super::options::{default_update_mode, ViewerOptions};
use super::panel::{self, AnimationInfo, PanelActions, PanelControls, PanelInfo, SAH_INTERVAL_S};
use super::playback::{ClockRequest, Playback};
use super::sah_reference::{ReferenceKey, SahReference};
use super::settings::ViewSettings;
use super::stats::{FrameStats, TreeSah};
use super::tradeoff_panel::{StudyScene, TradeoffPanel};
use crate::anim::{is_animation, load_animation, UpdateMode};
use crate::bvh::{sah_cost, Builder};
use crate::gpu::GpuContext;
use crate::scene::{load_scene, Camera, Scene};
use crate::trace::{GpuScene, PathTracer, RenderSettings};
use crate::Result;

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
    gpu_scene: GpuScene,
    builder: FrameBuilder,
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
}

impl Viewer {
    /// Loads and builds the first scene; errors here end the program (bad command line).
    pub fn new(ctx: &GpuContext, options: &ViewerOptions) -> Result<Self> {
        let requested = options
            .builder
            .unwrap_or_else(|| default_update_mode(ctx.info.device_type));
        let settings = ViewSettings::new(mode_for_scene(&options.scene, requested));
        let mut builder = FrameBuilder::new(ctx, settings.builder)?;
        let loaded = load_and_build(ctx, &options.scene, &mut builder, &settings)?;
        let mut viewer = Self {
            scene_radius: scene_radius(&loaded.scene),
            camera: loaded.scene.camera,
            scene: loaded.scene,
            scene_id: 0,
            gpu_scene: loaded.gpu_scene,
            builder,
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
        };
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
            triangles: self.gpu_scene.triangle_count,
            nodes: self.gpu_scene.node_count,
            references: self.gpu_scene.prim_count,
            samples: self.tracer.as_ref().map_or(0, |t| t.samples_done()),
            resolution: (width, height),
            reference: self.reference.state(),
            error: self.error.as_deref(),
            screenshot: self.screenshot_message.as_deref(),
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

    /// Applies the panel's actions and settings, then animates, builds and traces one frame.
    pub fn update(&mut self, ctx: &GpuContext, actions: PanelActions) {
        self.reference.poll();
        if let Some(name) = actions.load_scene {
            self.load(ctx, &name);
        }
        if actions.reset_camera {
            self.error = None;
            self.camera = self.scene.camera;
            self.something_changed();
        }
        self.apply_settings(ctx);
        self.fit_tracer(ctx);
        if self.halted {
            return;
        }
        if self.animate(ctx, actions.clock) {
            self.tree_dirty = true;
            self.restart_accumulation = true;
        }
        self.build(ctx);
        self.compare(ctx);
        self.measure_sah(ctx);
        self.trace(ctx);
        let study = StudyScene {
            scene: &self.scene,
            scene_id: self.scene_id,
            camera: &self.camera,
            max_depth: self.applied.max_depth(),
            sah: self.applied.sah_params(),
        };
        self.tradeoff.step(ctx, &study);
    }

    /// The animation step of the frame loop: advances the clock of an animated scene and moves its
    /// triangles on the GPU. Returns whether they moved (the tree is then rebuilt or refitted and
    /// accumulation restarts). Static scenes never move.
    fn animate(&mut self, ctx: &GpuContext, request: ClockRequest) -> bool {
        let Some(animated) = self.animated.as_mut() else {
            return false;
        };
        let dt = self
            .stats
            .history
            .back()
            .map_or(0.0, |ms| (ms * 1e-3) as f32);
        let playback = &mut self.controls.playback;
        match animated.step(ctx, playback, request, dt, &mut self.gpu_scene) {
            Ok(stepped) => {
                if stepped.looped {
                    // Refits start over from the first frame of each loop.
                    self.builder.reset_topology();
                }
                if stepped.moved {
                    if playback.follow_camera {
                        self.camera = animated.camera();
                    }
                    self.compare_due = true;
                }
                stepped.moved
            }
            Err(e) => {
                self.error = Some(format!("animation failed: {e}"));
                self.halted = true;
                false
            }
        }
    }

    /// Animated scenes with the comparison on: after the traced tree was updated, updates the
    /// second tree and records both SAH costs for the plot (this also measures the traced tree).
    fn compare(&mut self, ctx: &GpuContext) {
        let Some(animated) = self.animated.as_mut() else {
            return;
        };
        if !self.controls.playback.compare {
            animated.drop_companion();
            return;
        }
        if !self.compare_due {
            return;
        }
        self.compare_due = false;
        let params = self.applied.sah_params();
        match animated.compare(ctx, self.applied.builder, &self.gpu_scene, &params) {
            Ok((cost, leaves)) => {
                self.stats.tree_sah = Some(TreeSah {
                    cost,
                    leaves,
                    measured: Instant::now(),
                });
                self.sah_due = SahDue::No;
            }
            Err(e) => {
                self.error = Some(format!("rebuild/refit comparison failed: {e}"));
                self.controls.playback.compare = false;
            }
        }
    }

    /// Records the tonemap of the accumulated image (for `image`) into `encoder`.
    pub fn record_tonemap(&self, ctx: &GpuContext, encoder: &mut wgpu::CommandEncoder) {
        if let Some(tracer) = self.displayable_tracer() {
            tracer.tonemap(ctx, encoder);
        }
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
            "viewer: {} on {}: {} frames, {frame}, {mrays} Mrays/s, {spp} spp at {width}x{height}",
            self.builder.builder().name(),
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
            match FrameBuilder::new(ctx, mode) {
                Ok(builder) => {
                    self.builder = builder;
                    self.applied.select_builder(mode);
                    self.controls.settings.select_builder(mode);
                }
                Err(e) => {
                    self.error = Some(format!("cannot load '{name}': {e}"));
                    return;
                }
            }
        }
        match load_and_build(ctx, name, &mut self.builder, &self.applied) {
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
                self.gpu_scene = loaded.gpu_scene;
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
            match FrameBuilder::new(ctx, wanted.builder) {
                Ok(builder) => {
                    self.builder = builder;
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
            self.builder.reset_topology();
        }
        self.applied = wanted;
        self.request_reference();
        self.something_changed();
    }

    fn request_reference(&mut self) {
        let params = self.applied.sah_params();
        let key = ReferenceKey {
            scene_id: self.scene_id,
            max_leaf_size: params.max_leaf_size,
        };
        self.reference.request(key, &self.scene, params);
    }

    /// Makes the tracer match the image area's size and the bounce setting (a new tracer starts
    /// accumulating from zero).
    fn fit_tracer(&mut self, ctx: &GpuContext) {
        let rect = self.image_rect;
        if rect.is_empty() {
            return;
        }
        let wanted = RenderSettings {
            width: rect.width,
            height: rect.height,
            max_depth: self.applied.max_depth(),
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

    fn build(&mut self, ctx: &GpuContext) {
        if !(self.tree_dirty || self.applied.rebuilds_every_frame()) {
            return;
        }
        let params = self.applied.sah_params();
        match self
            .builder
            .build(ctx, &self.scene, &params, &mut self.gpu_scene)
        {
            Ok(timing) => {
                self.stats.build = Some(timing);
                self.sah_due = if self.tree_dirty {
                    SahDue::Now
                } else {
                    self.sah_due.max_periodic()
                };
                self.tree_dirty = false;
            }
            Err(e) => {
                self.error = Some(format!(
                    "{} build failed: {e}",
                    self.builder.builder().name()
                ));
                self.tree_dirty = false;
                self.halted = true;
            }
        }
    }

    /// Downloads the tree and computes its SAH when it is new, or periodically while it is
    /// rebuilt (downloading it every frame would dominate the frame time on large scenes).
    fn measure_sah(&mut self, ctx: &GpuContext) {
        let due = match self.sah_due {
            SahDue::No => false,
            SahDue::Now => true,
            SahDue::Periodic => self
                .stats
                .tree_sah
                .is_none_or(|s| s.measured.elapsed().as_secs_f64() >= SAH_INTERVAL_S),
        };
        if !due {
            return;
        }
        self.sah_due = SahDue::No;
        match self.gpu_scene.download_bvh(ctx) {
            Ok(bvh) => {
                self.stats.tree_sah = Some(TreeSah {
                    cost: sah_cost(&bvh, &self.applied.sah_params()),
                    leaves: bvh.leaf_count(),
                    measured: Instant::now(),
                });
            }
            Err(e) => self.error = Some(format!("cannot read the tree back: {e}")),
        }
    }

    fn trace(&mut self, ctx: &GpuContext) {
        let Some(tracer) = self.tracer.as_mut() else {
            return;
        };
        if self.restart_accumulation {
            tracer.reset(ctx);
            self.restart_accumulation = false;
        }
        match tracer.trace(
            ctx,
            &self.gpu_scene,
            &self.camera,
            self.scene.sky,
            self.applied.samples_per_frame,
        ) {
            Ok(stats) => self.stats.trace = Some(stats),
            Err(e) => {
                self.error = Some(format!("trace failed: {e}"));
                self.halted = true;
            }
        }
    }
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
    gpu_scene: GpuScene,
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

/// Loads `name` (a static or an animated scene), uploads it and builds its tree with `builder`.
fn load_and_build(
    ctx: &GpuContext,
    name: &str,
    builder: &mut FrameBuilder,
    settings: &ViewSettings,
) -> Result<LoadedScene> {
    let (scene, animated) = if is_animation(name) {
        let animation = load_animation(name)?;
        let scene = animation.scene_at(animation.time_range().start);
        (scene, Some(AnimatedScene::new(animation)))
    } else {
        (load_scene(name)?, None)
    };
    let scene = Arc::new(scene);
    let mut gpu_scene = GpuScene::upload_geometry(ctx, &scene)?;
    let timing = builder.build(ctx, &scene, &settings.sah_params(), &mut gpu_scene)?;
    Ok(LoadedScene {
        scene,
        gpu_scene,
        timing,
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
