//! The egui side panel: device, performance (frame time plot, Mrays/s), scene and tree statistics,
//! animation playback (play/pause/step/speed/seek, animate time, the SAH-over-time plot of rebuild
//! versus refit), the traced node layout and its size, a GPU builder's build schedule and its last
//! tuning, per-stage build times, SAH against the CPU sweep reference, and the controls (scene,
//! builder or refit, node layout, leaf size, schedule tuning, samples per frame, bounces,
//! per-frame rebuild, camera reset, screenshot). It only edits `PanelControls`
//! and returns `PanelActions`; the viewer applies them.

use egui::{Color32, RichText};

use super::playback::{Clock, ClockRequest, Playback};
use super::sah_history::SahHistory;
use super::sah_reference::ReferenceState;
use super::settings::ViewSettings;
use super::stats::BuildTiming;
use super::stats::FrameStats;
use crate::anim::{AnimateStage, ANIMATIONS};
use crate::bvh::treelet::TreeletSettings;
use crate::bvh::wide::{Layout, WideCollapse, WideNode, WIDTH};
use crate::bvh::{BuildSchedule, Builder, BvhNode, TunedSchedule, UpdateMode};
use crate::scene::{Triangle, SCENES};

/// Width of the panel in points.
pub const PANEL_WIDTH: f32 = 330.0;
/// The current tree is downloaded for its SAH at most this often while it is rebuilt per frame.
pub const SAH_INTERVAL_S: f64 = 2.0;

const ERROR_RED: Color32 = Color32::from_rgb(255, 90, 90);
/// Colours of the rebuild and the refit curve of the SAH plot.
const REBUILD_COLOUR: Color32 = Color32::from_rgb(240, 140, 80);
const REFIT_COLOUR: Color32 = Color32::from_rgb(100, 160, 240);

/// Read-only facts the panel shows.
pub struct PanelInfo<'a> {
    pub adapter: &'a wgpu::AdapterInfo,
    pub stats: &'a FrameStats,
    pub scene_name: &'a str,
    pub triangles: u32,
    pub nodes: u32,
    pub references: u32,
    /// The layout the tracer traces, and the wide layout's collapse.
    pub layout: Layout,
    pub wide_collapse: WideCollapse,
    /// (wide nodes, references) of the tree's wide layout, when it has one.
    pub wide_counts: Option<(u32, u32)>,
    pub samples: u32,
    pub resolution: (u32, u32),
    pub reference: ReferenceState,
    pub error: Option<&'a str>,
    pub screenshot: Option<&'a str>,
    /// The animation of an animated scene.
    pub animation: Option<AnimationInfo<'a>>,
    /// A GPU builder's build schedule: the traced tree's rebuilds, or beside a traced refit the
    /// comparison's rebuilds (None for CPU builders, and refits without that comparison).
    pub schedule: Option<ScheduleInfo<'a>>,
}

/// The build schedule in use, and the last tuning with the scene it ran on.
pub struct ScheduleInfo<'a> {
    pub current: BuildSchedule,
    /// The schedule is the comparison's rebuilds' (the traced tree is a refit).
    pub of_comparison: bool,
    pub tuned: Option<(&'a TunedSchedule, &'a str)>,
}

/// Read-only facts about the animation of an animated scene.
pub struct AnimationInfo<'a> {
    pub clock: Clock,
    pub stage: AnimateStage,
    /// The last animate stage.
    pub animate_ms: Option<f64>,
    /// The last update of the comparison tree.
    pub companion: Option<&'a BuildTiming>,
    pub history: &'a SahHistory,
}

/// What the panel's widgets edit directly.
pub struct PanelControls {
    pub settings: ViewSettings,
    /// Contents of the "OBJ path" text field.
    pub obj_path: String,
    pub playback: Playback,
}

/// What the user asked for this frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PanelActions {
    /// Load this scene (registry name or OBJ path).
    pub load_scene: Option<String>,
    pub reset_camera: bool,
    pub screenshot: bool,
    /// Animation clock: single step or seek.
    pub clock: ClockRequest,
    /// Tune the GPU builder's build schedule now.
    pub tune_schedule: bool,
}

/// Draws the panel at the left of `ui`.
pub fn show(ui: &mut egui::Ui, info: &PanelInfo, controls: &mut PanelControls) -> PanelActions {
    let mut actions = PanelActions::default();
    egui::Panel::left("treelet_panel")
        .resizable(false)
        .exact_size(PANEL_WIDTH)
        .show(ui, |ui| {
            ui.heading("treelet");
            // Outside the scroll area: an error stays in sight wherever the panel is scrolled.
            if let Some(error) = info.error {
                ui.colored_label(ERROR_RED, error);
            }
            egui::ScrollArea::vertical()
                .auto_shrink([false, false])
                .show(ui, |ui| {
                    device(ui, info);
                    performance(ui, info);
                    scene(ui, info, controls, &mut actions);
                    if let Some(animation) = &info.animation {
                        self::animation(ui, animation, &mut controls.playback, &mut actions);
                    }
                    bvh(ui, info, &mut controls.settings, &mut actions);
                    render(ui, &mut controls.settings, &mut actions, info);
                });
        });
    actions
}

fn section(ui: &mut egui::Ui, title: &str) {
    ui.add_space(6.0);
    ui.separator();
    ui.label(RichText::new(title).strong());
}

fn device(ui: &mut egui::Ui, info: &PanelInfo) {
    section(ui, "Device");
    let a = info.adapter;
    ui.label(&a.name);
    ui.label(format!("{:?} · {:?}", a.backend, a.device_type));
    ui.label(format!("driver: {} {}", a.driver, a.driver_info));
}

fn performance(ui: &mut egui::Ui, info: &PanelInfo) {
    section(ui, "Performance");
    let stats = info.stats;
    match (stats.frame_ms, stats.fps()) {
        (Some(ms), Some(fps)) => ui.label(format!("frame: {ms:.1} ms ({fps:.1} fps)")),
        _ => ui.label("frame: measuring…"),
    };
    frame_plot(ui, stats);
    match stats.trace {
        Some(trace) => {
            let mrays = trace
                .mrays_per_s()
                .map_or("n/a (no timestamps)".into(), |m| format!("{m:.1} Mrays/s"));
            let trace_ms = trace
                .trace_ms
                .map_or("n/a".into(), |ms| format!("{ms:.1} ms"));
            ui.label(format!("trace: {mrays}"));
            ui.label(format!(
                "  {} rays in {trace_ms} (GPU), {:.1} ms wall",
                trace.rays, trace.wall_ms
            ));
        }
        None => {
            ui.label("trace: –");
        }
    }
    let collapse = match info.layout {
        Layout::Binary => String::new(),
        Layout::Wide => format!(", {} collapse", info.wide_collapse.name()),
    };
    ui.label(format!(
        "layout: {} ({}{collapse})",
        info.layout.name(),
        layout_detail(info.layout)
    ));
    ui.label(format!(
        "accumulated: {} spp at {}×{}",
        info.samples, info.resolution.0, info.resolution.1
    ));
}

fn frame_plot(ui: &mut egui::Ui, stats: &FrameStats) {
    let points: egui_plot::PlotPoints = stats
        .history
        .iter()
        .enumerate()
        .map(|(i, &ms)| [i as f64, ms])
        .collect();
    egui_plot::Plot::new("frame_times")
        .height(64.0)
        .show_axes([false, true])
        .allow_zoom(false)
        .allow_drag(false)
        .allow_scroll(false)
        .allow_boxed_zoom(false)
        .allow_double_click_reset(false)
        .include_y(0.0)
        .include_x(0.0)
        .include_x(super::stats::HISTORY as f64)
        .y_axis_label("ms")
        .show(ui, |plot| {
            plot.line(egui_plot::Line::new("frame time", points))
        });
}

fn scene(
    ui: &mut egui::Ui,
    info: &PanelInfo,
    controls: &mut PanelControls,
    actions: &mut PanelActions,
) {
    section(ui, "Scene");
    egui::ComboBox::from_id_salt("scene")
        .width(PANEL_WIDTH - 40.0)
        .selected_text(info.scene_name)
        .show_ui(ui, |ui| {
            let animated = ANIMATIONS.iter().map(|e| (e.name, e.description, true));
            let entries = SCENES.iter().map(|e| (e.name, e.description, false));
            for (name, description, is_animated) in animated.chain(entries) {
                let label = if is_animated {
                    format!("{name} (animated)")
                } else {
                    name.to_string()
                };
                let picked = ui
                    .selectable_label(name == info.scene_name, label)
                    .on_hover_text(description);
                if picked.clicked() && name != info.scene_name {
                    actions.load_scene = Some(name.to_string());
                }
            }
        });
    ui.horizontal(|ui| {
        let field = ui.add(
            egui::TextEdit::singleline(&mut controls.obj_path)
                .hint_text("path/to/scene.obj or frames folder")
                .desired_width(PANEL_WIDTH - 90.0),
        );
        let entered = field.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        if (ui.button("Open").clicked() || entered) && !controls.obj_path.trim().is_empty() {
            actions.load_scene = Some(controls.obj_path.trim().to_string());
        }
    });
    ui.label(format!(
        "{} triangles · {} nodes · {} references",
        info.triangles, info.nodes, info.references
    ));
    if let Some(sah) = info.stats.tree_sah {
        ui.label(format!("{} leaves", sah.leaves));
    }
    tree_size(ui, info);
}

/// The traced tree's bytes (nodes and references); with the wide layout, against the binary
/// tree it was converted from.
fn tree_size(ui: &mut egui::Ui, info: &PanelInfo) {
    let bytes = |nodes: u32, node_bytes: usize, references: u32| {
        u64::from(nodes) * node_bytes as u64 + 4 * u64::from(references)
    };
    let binary = bytes(info.nodes, std::mem::size_of::<BvhNode>(), info.references);
    match (info.layout, info.wide_counts) {
        (Layout::Wide, Some((nodes, references))) => {
            let wide = bytes(nodes, std::mem::size_of::<WideNode>(), references);
            ui.label(format!("wide: {nodes} nodes · {references} references"));
            let ratio = if binary > 0 {
                format!(" ({:.2}× binary)", wide as f64 / binary as f64)
            } else {
                String::new()
            };
            ui.label(format!(
                "tree: {}{ratio}; binary {}",
                size_text(wide),
                size_text(binary)
            ));
            let copies = u64::from(references) * std::mem::size_of::<Triangle>() as u64;
            ui.label(format!(
                "leaf triangles: {} (copied in leaf order)",
                size_text(copies)
            ));
        }
        (Layout::Wide, None) => {
            ui.label("wide: converting…");
        }
        (Layout::Binary, _) => {
            ui.label(format!("tree: {}", size_text(binary)));
        }
    }
}

/// `bytes` in KiB below a MiB, else in MiB.
fn size_text(bytes: u64) -> String {
    if bytes < 1 << 20 {
        format!("{:.1} KiB", bytes as f64 / 1024.0)
    } else {
        format!("{:.2} MiB", bytes as f64 / f64::from(1 << 20))
    }
}

/// The order of a treelet builder's rounds (none for other builders): the paper's bottom-up
/// rounds or the phased ones (`TreeletSettings::PHASED`), with the builder's split budget kept.
fn treelet_order(ui: &mut egui::Ui, settings: &mut ViewSettings) {
    let Some(current) = settings.builder.builder().treelet_settings() else {
        return;
    };
    let orders = [
        ("bottom-up (the paper's)", TreeletSettings::BALANCED),
        ("phased (14 steps)", TreeletSettings::PHASED),
    ];
    let mut selected = TreeletSettings {
        split_percent: 0,
        ..current
    };
    let shown = orders
        .iter()
        .find(|(_, order)| *order == selected)
        .map_or("other (command line)", |(name, _)| name);
    egui::ComboBox::from_label("treelet order")
        .selected_text(shown)
        .show_ui(ui, |ui| {
            for (name, order) in orders {
                ui.selectable_value(&mut selected, order, name);
            }
        })
        .response
        .on_hover_text(
            "The treelet rounds: the paper's 3 rounds bottom-up, a step per treelet level \
             (57-108 on the shared scenes), or 6, 4 and 4 phases by depth, 14 steps of many \
             treelets each, another tree within 0.9 % of the paper's SAH \
             (README, \"Phased rounds\")",
        );
    settings.select_builder(settings.builder.with_treelet_settings(TreeletSettings {
        split_percent: current.split_percent,
        ..selected
    }));
}

/// What a layout's nodes are, for the panel.
fn layout_detail(layout: Layout) -> String {
    match layout {
        Layout::Binary => format!("2-wide, {} B nodes", std::mem::size_of::<BvhNode>()),
        Layout::Wide => format!("{WIDTH}-wide, {} B nodes", std::mem::size_of::<WideNode>()),
    }
}

fn bvh(
    ui: &mut egui::Ui,
    info: &PanelInfo,
    settings: &mut ViewSettings,
    actions: &mut PanelActions,
) {
    section(ui, "BVH");
    let mut builder = settings.builder;
    // Animated scenes: GPU rebuilds and the refits (CPU builders would need CPU triangles).
    let modes: Vec<UpdateMode> = if info.animation.is_some() {
        UpdateMode::all()
            .into_iter()
            .filter(|m| m.is_gpu())
            .collect()
    } else {
        Builder::ALL
            .iter()
            .map(|&b| UpdateMode::Rebuild(b))
            .collect()
    };
    egui::ComboBox::from_label("builder")
        .selected_text(builder.name())
        .show_ui(ui, |ui| {
            for m in modes {
                let kind = if m.is_refit() {
                    "GPU refit of the first frame's tree"
                } else if m.is_gpu() {
                    "GPU"
                } else {
                    "CPU reference"
                };
                ui.selectable_value(&mut builder, m, format!("{} ({kind})", m.name()));
            }
        });
    settings.select_builder(builder);
    treelet_order(ui, settings);
    egui::ComboBox::from_label("layout")
        .selected_text(settings.layout.name())
        .show_ui(ui, |ui| {
            for &layout in Layout::ALL {
                ui.selectable_value(
                    &mut settings.layout,
                    layout,
                    format!("{} ({})", layout.name(), layout_detail(layout)),
                );
            }
        })
        .response
        .on_hover_text(
            "The node layout traced: the builder's binary tree, or that tree converted on the \
             GPU after every update into the compressed 8-wide layout (Ylitie et al. 2017; \
             stage \"wide\" among the build times)",
        );
    ui.add_enabled_ui(settings.layout == Layout::Wide, |ui| {
        egui::ComboBox::from_label("wide collapse")
            .selected_text(settings.wide_collapse.name())
            .show_ui(ui, |ui| {
                for &collapse in WideCollapse::ALL {
                    ui.selectable_value(&mut settings.wide_collapse, collapse, collapse.name());
                }
            })
            .response
            .on_hover_text(
                "How the conversion picks a wide node's children: greedy (open the largest \
                 child until 8 slots are taken) or optimal (Ylitie et al.'s SAH-optimal \
                 dynamic program, two more GPU passes: fewer wide nodes, a lower wide SAH)",
            );
    });
    ui.add_enabled(
        settings.builder.is_gpu(),
        egui::Checkbox::new(&mut settings.rebuild_every_frame, "rebuild every frame"),
    )
    .on_disabled_hover_text("CPU builders build once per scene or setting change");
    ui.add(
        egui::Slider::new(&mut settings.max_leaf_size, 1..=ViewSettings::MAX_LEAF_SIZE)
            .text("max leaf size"),
    );
    if let Some(schedule) = &info.schedule {
        self::schedule(ui, schedule, actions);
    }
    build_times(ui, info.stats, settings.rebuilds_every_frame());
    sah(ui, info);
}

/// The build schedule, its last tuning and the button that tunes it.
fn schedule(ui: &mut egui::Ui, info: &ScheduleInfo, actions: &mut PanelActions) {
    let whose = if info.of_comparison {
        "comparison rebuild's schedule"
    } else {
        "schedule"
    };
    ui.label(format!("{whose}: {}", info.current.label()));
    if let Some((tuned, scene)) = info.tuned {
        let start_ms = tuned.trials.first().and_then(|t| t.kept_ms);
        let kept_ms = tuned
            .trials
            .iter()
            .rev()
            .find(|t| t.adopted)
            .and_then(|t| t.candidate_ms)
            .or(start_ms);
        let mut text = format!(
            "tuned on {scene}: {} trials, {} builds",
            tuned.trials.len(),
            tuned.builds
        );
        if let (Some(start), Some(kept)) = (start_ms, kept_ms) {
            text += &format!(", {start:.2} ms to {kept:.2} ms");
        }
        ui.label(text);
        let other_tree = tuned.trials.iter().filter(|t| t.other_tree).count();
        if other_tree > 0 {
            ui.colored_label(
                ERROR_RED,
                format!("{other_tree} schedules built another tree (a device bug; not used)"),
            );
        }
        let failed = tuned.trials.iter().filter(|t| t.error.is_some()).count();
        if failed > 0 {
            ui.label(format!("{failed} schedules failed to build (not used)"));
        }
    }
    let tune = ui.button("Tune schedule").on_hover_text(
        "Time the build's schedules on this device and scene and keep the fastest (treelet \
         rounds overlapped, one after another or their lowest levels per subtree, DP forms, teams, \
         dispatched levels; the sort's \
         tile; the wide conversion's dispatched levels): every schedule builds the same tree, \
         which the tuning checks. Waits for about a hundred \
         builds (on a GPU a second or less; on a CPU device up to minutes); on a GPU it runs \
         once by itself a few seconds after a GPU builder starts",
    );
    if tune.clicked() {
        actions.tune_schedule = true;
    }
}

fn animation(
    ui: &mut egui::Ui,
    info: &AnimationInfo,
    playback: &mut Playback,
    actions: &mut PanelActions,
) {
    section(ui, "Animation");
    let clock = info.clock;
    let range = clock.range;
    ui.label(format!(
        "t = {:.2} in {:.2}..{:.2} · frame {} of {}",
        clock.t(),
        range.start,
        range.end,
        range.frame_at(clock.t()),
        range.frames
    ));
    ui.horizontal(|ui| {
        let play = if playback.playing { "Pause" } else { "Play" };
        if ui.button(play).clicked() {
            playback.playing = !playback.playing;
        }
        if ui.button("Step").clicked() {
            actions.clock.step = true;
        }
    });
    let speed_unit = if playback.real_time {
        "× real time"
    } else {
        "frames per frame"
    };
    ui.add(
        egui::Slider::new(
            &mut playback.speed,
            Playback::MIN_SPEED..=Playback::MAX_SPEED,
        )
        .logarithmic(true)
        .text(speed_unit),
    );
    let mut t = clock.t();
    if ui
        .add(egui::Slider::new(&mut t, range.start..=range.end).text("time"))
        .changed()
    {
        actions.clock.seek = Some(t);
    }
    ui.checkbox(&mut playback.real_time, "real time")
        .on_hover_text("Off: every displayed frame advances one animation frame (× speed)");
    ui.checkbox(&mut playback.follow_camera, "animated camera")
        .on_hover_text("Moving the camera turns this off");
    let animate = info
        .animate_ms
        .map_or("–".into(), |ms| format!("{ms:.2} ms"));
    ui.label(format!("animate: {animate} ({})", info.stage.describe()));
    ui.checkbox(&mut playback.compare, "compare rebuild and refit")
        .on_hover_text(
            "Keeps a second tree (the refit when the traced tree is rebuilt, the rebuild when it \
             is refitted), updates it every animated frame and downloads both trees for their SAH \
             (the plot). Refits start from the first frame of each loop.",
        );
    if let Some(timing) = info.companion {
        ui.label(format!("second tree: {:.2} ms", timing.total_ms));
    }
    let (rebuild, refit) = info.history.series();
    let (rebuild_label, refit_label) = &info.history.labels;
    // The data changes every frame: set the y range from it (auto bounds lag a frame behind).
    let top = rebuild
        .iter()
        .chain(&refit)
        .map(|p| p[1])
        .fold(1.0, f64::max);
    egui_plot::Plot::new("sah_over_time")
        .height(130.0)
        .allow_zoom(false)
        .allow_drag(false)
        .allow_scroll(false)
        .include_x(f64::from(range.start))
        .include_x(f64::from(range.end))
        .include_y(0.0)
        .include_y(top * 1.05)
        .x_axis_label("t")
        .y_axis_label("SAH")
        .show(ui, |plot| {
            plot.line(
                egui_plot::Line::new(rebuild_label.as_str(), egui_plot::PlotPoints::from(rebuild))
                    .color(REBUILD_COLOUR),
            );
            plot.line(
                egui_plot::Line::new(refit_label.as_str(), egui_plot::PlotPoints::from(refit))
                    .color(REFIT_COLOUR),
            );
        });
    // The legend, below the plot (inside it would hide the curves).
    let last = info.history.last();
    ui.colored_label(
        REBUILD_COLOUR,
        format!(
            "— {rebuild_label}{}",
            last.map_or(String::new(), |s| format!(": {:.1}", s.rebuild))
        ),
    );
    ui.colored_label(
        REFIT_COLOUR,
        format!(
            "— {refit_label}{}",
            last.map_or(String::new(), |s| format!(": {:.1}", s.refit))
        ),
    );
}

fn build_times(ui: &mut egui::Ui, stats: &FrameStats, per_frame: bool) {
    let Some(build) = &stats.build else {
        ui.label("build: –");
        return;
    };
    let clock = if build.timestamped { "GPU" } else { "wall" };
    let when = if per_frame {
        "every frame"
    } else {
        "last build"
    };
    let dispatches: u32 = build.stages.iter().map(|s| s.dispatches).sum();
    ui.label(format!(
        "build: {:.2} ms ({clock}, {when}) · {dispatches} dispatches",
        build.total_ms
    ))
    .on_hover_text("A real GPU pays a fixed few µs per compute dispatch besides its work");
    let max_ms = build
        .stages
        .iter()
        .filter_map(|s| s.ms)
        .fold(0.0f64, f64::max);
    egui::Grid::new("stages")
        .num_columns(4)
        .striped(true)
        .show(ui, |ui| {
            for stage in &build.stages {
                ui.label(&stage.label);
                match stage.ms {
                    Some(ms) => {
                        ui.label(format!("{ms:.3} ms"));
                        let fraction = if max_ms > 0.0 { ms / max_ms } else { 0.0 };
                        bar(ui, fraction as f32);
                    }
                    None => {
                        ui.label("n/a");
                        ui.label("");
                    }
                }
                if stage.dispatches > 0 {
                    ui.label(format!("{}×", stage.dispatches));
                } else {
                    ui.label("");
                }
                ui.end_row();
            }
        });
}

fn bar(ui: &mut egui::Ui, fraction: f32) {
    let (rect, _) = ui.allocate_exact_size(egui::vec2(100.0, 10.0), egui::Sense::hover());
    let filled = egui::Rect::from_min_size(
        rect.min,
        egui::vec2(rect.width() * fraction.clamp(0.0, 1.0), rect.height()),
    );
    ui.painter()
        .rect_filled(filled, 2.0, Color32::from_rgb(90, 150, 230));
}

fn sah(ui: &mut egui::Ui, info: &PanelInfo) {
    let current = info.stats.tree_sah;
    match current {
        Some(sah) => ui.label(format!(
            "SAH: {:.2} (measured {:.1} s ago)",
            sah.cost,
            sah.measured.elapsed().as_secs_f64()
        )),
        None => ui.label("SAH: measuring…"),
    }
    .on_hover_text(format!(
        "The tree is downloaded to compute its SAH when it changes, and at most every \
         {SAH_INTERVAL_S} s while it is rebuilt every frame (downloading it each frame would \
         dominate the frame time)."
    ));
    ui.weak(format!(
        "(tree downloaded on change, at most every {SAH_INTERVAL_S} s)"
    ));
    match info.reference {
        ReferenceState::Computing => {
            ui.label("sweep SAH reference: computing…");
        }
        ReferenceState::Failed => {
            ui.colored_label(
                Color32::from_rgb(255, 90, 90),
                "sweep SAH reference: failed",
            );
        }
        ReferenceState::Ready(reference) => {
            ui.label(format!("sweep SAH reference: {reference:.2}"));
            if let Some(sah) = current {
                if reference > 0.0 {
                    ui.label(format!(
                        "ratio to sweep: {:.3}×",
                        f64::from(sah.cost) / f64::from(reference)
                    ));
                }
            }
        }
    }
}

fn render(
    ui: &mut egui::Ui,
    settings: &mut ViewSettings,
    actions: &mut PanelActions,
    info: &PanelInfo,
) {
    section(ui, "Render");
    ui.add(
        egui::Slider::new(
            &mut settings.samples_per_frame,
            1..=ViewSettings::MAX_SAMPLES_PER_FRAME,
        )
        .text("samples / frame"),
    );
    ui.add(
        egui::Slider::new(&mut settings.max_bounces, 0..=ViewSettings::MAX_BOUNCES)
            .text("max bounces"),
    );
    section(ui, "Camera");
    ui.horizontal(|ui| {
        if ui.button("Reset").clicked() {
            actions.reset_camera = true;
        }
        ui.weak("drag: orbit · wheel: zoom");
    });
    ui.weak("W/A/S/D: fly · Q/E: down/up");
    section(ui, "Screenshot");
    if ui.button("Screenshot").clicked() {
        actions.screenshot = true;
    }
    if let Some(message) = info.screenshot {
        ui.label(message);
    }
}
