//! The egui side panel: device, performance (frame time plot, Mrays/s), scene and tree statistics,
//! per-stage build times, SAH against the CPU sweep reference, and the controls (scene, builder,
//! leaf size, samples per frame, bounces, per-frame rebuild, camera reset, screenshot). It only
//! edits `PanelControls` and returns `PanelActions`; the viewer applies them.

use egui::{Color32, RichText};

use super::sah_reference::ReferenceState;
use super::settings::ViewSettings;
use super::stats::FrameStats;
use crate::bvh::Builder;
use crate::scene::SCENES;

/// Width of the panel in points.
pub const PANEL_WIDTH: f32 = 330.0;
/// The current tree is downloaded for its SAH at most this often while it is rebuilt per frame.
pub const SAH_INTERVAL_S: f64 = 2.0;

const ERROR_RED: Color32 = Color32::from_rgb(255, 90, 90);

/// Read-only facts the panel shows.
pub struct PanelInfo<'a> {
    pub adapter: &'a wgpu::AdapterInfo,
    pub stats: &'a FrameStats,
    pub scene_name: &'a str,
    pub triangles: u32,
    pub nodes: u32,
    pub references: u32,
    pub samples: u32,
    pub resolution: (u32, u32),
    pub reference: ReferenceState,
    pub error: Option<&'a str>,
    pub screenshot: Option<&'a str>,
}

/// What the panel's widgets edit directly.
pub struct PanelControls {
    pub settings: ViewSettings,
    /// Contents of the "OBJ path" text field.
    pub obj_path: String,
}

/// What the user asked for this frame.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PanelActions {
    /// Load this scene (registry name or OBJ path).
    pub load_scene: Option<String>,
    pub reset_camera: bool,
    pub screenshot: bool,
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
                    bvh(ui, info, &mut controls.settings);
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
            for entry in SCENES {
                let picked = ui
                    .selectable_label(entry.name == info.scene_name, entry.name)
                    .on_hover_text(entry.description);
                if picked.clicked() && entry.name != info.scene_name {
                    actions.load_scene = Some(entry.name.to_string());
                }
            }
        });
    ui.horizontal(|ui| {
        let field = ui.add(
            egui::TextEdit::singleline(&mut controls.obj_path)
                .hint_text("path/to/scene.obj")
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
}

fn bvh(ui: &mut egui::Ui, info: &PanelInfo, settings: &mut ViewSettings) {
    section(ui, "BVH");
    let mut builder = settings.builder;
    egui::ComboBox::from_label("builder")
        .selected_text(builder.name())
        .show_ui(ui, |ui| {
            for &b in Builder::ALL {
                let kind = if b.is_gpu() { "GPU" } else { "CPU reference" };
                ui.selectable_value(&mut builder, b, format!("{} ({kind})", b.name()));
            }
        });
    settings.select_builder(builder);
    ui.add_enabled(
        settings.builder.is_gpu(),
        egui::Checkbox::new(&mut settings.rebuild_every_frame, "rebuild every frame"),
    )
    .on_disabled_hover_text("CPU builders build once per scene or setting change");
    ui.add(
        egui::Slider::new(&mut settings.max_leaf_size, 1..=ViewSettings::MAX_LEAF_SIZE)
            .text("max leaf size"),
    );
    build_times(ui, info.stats, settings.rebuilds_every_frame());
    sah(ui, info);
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
    ui.label(format!("build: {:.2} ms ({clock}, {when})", build.total_ms));
    let max_ms = build
        .stages
        .iter()
        .filter_map(|s| s.ms)
        .fold(0.0f64, f64::max);
    egui::Grid::new("stages")
        .num_columns(3)
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
