//! The viewer's "Quality–speed trade-off" window (Karras & Aila 2013, Figure 1, live): on request
//! it measures every builder configuration on the current scene (build time, SAH, Mrays/s from
//! the current camera at a fixed small image size) and plots effective Mrays/s against rays per
//! frame, with the best configuration for each range of rays per frame. Measuring runs on the UI
//! thread one configuration per frame (each takes from milliseconds to seconds); the window shows
//! which one is next. A scene change discards the measurements.

use std::collections::VecDeque;

use egui_plot::{HoverPosition, Line, Plot, PlotPoints};

use crate::bvh::{Builder, SahParams};
use crate::gpu::GpuContext;
use crate::scene::{Camera, Scene};
use crate::trace::{PathTracer, RenderSettings};
use crate::tradeoff::{
    best_ranges, configurations, effective_mrays, log_space, measure, rays_label, BestRange,
    MeasureSettings, Measurement, CURVE_POINTS, RAYS_RANGE,
};

/// Image size and samples per pixel of the throughput measurement.
const MEASURE_SIZE: (u32, u32) = (320, 240);
const MEASURE_SPP: u32 = 2;
/// Timed builds per GPU configuration and timed traces per configuration (medians are kept).
const MEASURE_REPEATS: u32 = 3;

/// What the trade-off study needs from the viewer each frame.
pub struct StudyScene<'a> {
    pub scene: &'a Scene,
    /// Changes on every scene load.
    pub scene_id: u64,
    pub camera: &'a Camera,
    pub max_depth: u32,
    pub sah: SahParams,
}

#[derive(Default)]
pub struct TradeoffPanel {
    /// The scene the measurements belong to.
    scene_id: Option<u64>,
    measurements: Vec<Measurement>,
    best: Vec<BestRange>,
    study: Option<Study>,
    /// Only one treelet setting instead of the sweep.
    quick: bool,
    start_requested: bool,
    error: Option<String>,
}

/// A study in progress: the configurations still to measure.
struct Study {
    queue: VecDeque<Builder>,
    total: usize,
    tracer: PathTracer,
    /// The camera when the study started (moving the view meanwhile does not change it).
    camera: Camera,
    settings: MeasureSettings,
}

impl TradeoffPanel {
    /// Draws the (initially collapsed) window.
    pub fn show(&mut self, ctx: &egui::Context) {
        egui::Window::new("Quality–speed trade-off")
            .default_open(false)
            .anchor(egui::Align2::RIGHT_TOP, [-8.0, 8.0])
            .default_width(460.0)
            .resizable(false)
            .show(ctx, |ui| self.contents(ui));
    }

    fn contents(&mut self, ui: &mut egui::Ui) {
        ui.label(format!(
            "Frame time = build + rays / throughput. Measures every builder configuration on \
             this scene ({}×{}, {MEASURE_SPP} spp from the current camera).",
            MEASURE_SIZE.0, MEASURE_SIZE.1
        ));
        ui.horizontal(|ui| {
            let idle = self.study.is_none();
            if ui
                .add_enabled(idle, egui::Button::new("Measure trade-off"))
                .clicked()
            {
                self.start_requested = true;
            }
            ui.add_enabled(idle, egui::Checkbox::new(&mut self.quick, "quick"))
                .on_hover_text("one trbvh setting (n=5, 1 round) and one split budget");
        });
        if let Some(study) = &self.study {
            ui.horizontal(|ui| {
                ui.spinner();
                let next = study.queue.front().map_or(String::new(), |b| b.label());
                ui.label(format!(
                    "measuring {}/{}: {next}… (the viewer pauses while it builds)",
                    study.total - study.queue.len() + 1,
                    study.total
                ));
            });
        }
        if let Some(error) = &self.error {
            ui.colored_label(egui::Color32::from_rgb(255, 90, 90), error);
        }
        if self.measurements.is_empty() {
            return;
        }
        self.plot(ui);
        ui.label(egui::RichText::new("best configuration by rays per frame").strong());
        for range in &self.best {
            let i = self
                .measurements
                .iter()
                .position(|m| m.label == range.label)
                .unwrap_or(0);
            let text = format!(
                "{} – {}: {}",
                rays_label(range.from_rays),
                rays_label(range.to_rays),
                range.label
            );
            Self::swatch(ui, i, text);
        }
        egui::CollapsingHeader::new("measurements").show(ui, |ui| {
            egui::Grid::new("tradeoff_measurements")
                .striped(true)
                .show(ui, |ui| {
                    for heading in ["configuration", "build ms", "SAH", "Mrays/s"] {
                        ui.strong(heading);
                    }
                    ui.end_row();
                    for (i, m) in self.measurements.iter().enumerate() {
                        let kind = if m.gpu { "" } else { " (CPU)" };
                        Self::swatch(ui, i, format!("{}{kind}", m.label));
                        ui.label(format!("{:.2}", m.build_ms));
                        ui.label(format!("{:.2}", m.sah));
                        ui.label(format!("{:.2}", m.mrays_per_s));
                        ui.end_row();
                    }
                });
        });
    }

    /// Effective Mrays/s against log10(rays per frame); the configurations that are best
    /// somewhere are drawn thicker. Hovering a line names it.
    fn plot(&self, ui: &mut egui::Ui) {
        let rays = log_space(RAYS_RANGE.0, RAYS_RANGE.1, CURVE_POINTS);
        Plot::new("tradeoff_plot")
            .height(260.0)
            .x_axis_label("rays per frame")
            .y_axis_label("effective Mrays/s")
            .x_axis_formatter(|mark, _| rays_label(10f64.powf(mark.value)))
            .label_formatter(|hover| match hover {
                HoverPosition::NearDataPoint {
                    plot_name,
                    position,
                    ..
                } => Some(format!(
                    "{plot_name}\n{} rays/frame: {:.2} Mrays/s",
                    rays_label(10f64.powf(position.x)),
                    position.y
                )),
                HoverPosition::Elsewhere { .. } => None,
            })
            .include_y(0.0)
            .allow_scroll(false)
            .show(ui, |plot| {
                for (i, m) in self.measurements.iter().enumerate() {
                    if !m.is_usable() {
                        continue;
                    }
                    let points: PlotPoints = rays
                        .iter()
                        .map(|&r| [r.log10(), effective_mrays(m, r)])
                        .collect();
                    let wins = self.best.iter().any(|b| b.label == m.label);
                    plot.line(
                        Line::new(m.label.clone(), points)
                            .color(color(i))
                            .width(if wins { 3.0 } else { 1.2 }),
                    );
                }
            });
    }

    /// A line-coloured square and a label.
    fn swatch(ui: &mut egui::Ui, i: usize, text: String) {
        ui.horizontal(|ui| {
            let (rect, _) = ui.allocate_exact_size(egui::vec2(10.0, 10.0), egui::Sense::hover());
            ui.painter().rect_filled(rect, 2.0, color(i));
            ui.label(text);
        });
    }

    /// Starts a requested study and measures the next configuration of a running one.
    pub fn step(&mut self, ctx: &GpuContext, current: &StudyScene) {
        if self.scene_id != Some(current.scene_id) {
            *self = Self {
                quick: self.quick,
                scene_id: Some(current.scene_id),
                ..Self::default()
            };
        }
        if std::mem::take(&mut self.start_requested) {
            self.start(ctx, current);
            return;
        }
        let Some(study) = self.study.as_mut() else {
            return;
        };
        let Some(builder) = study.queue.pop_front() else {
            self.study = None;
            return;
        };
        let measured = measure(
            ctx,
            current.scene,
            &study.camera,
            builder,
            &mut study.tracer,
            &study.settings,
        );
        match measured {
            Ok(m) => {
                self.measurements.push(m);
                self.best = best_ranges(&self.measurements, RAYS_RANGE.0, RAYS_RANGE.1);
            }
            Err(e) => self.error = Some(format!("{}: {e}", builder.label())),
        }
        if study.queue.is_empty() {
            self.study = None;
        }
    }

    fn start(&mut self, ctx: &GpuContext, current: &StudyScene) {
        self.measurements.clear();
        self.best.clear();
        self.error = None;
        let render = RenderSettings {
            width: MEASURE_SIZE.0,
            height: MEASURE_SIZE.1,
            max_depth: current.max_depth,
            ..RenderSettings::default()
        };
        match PathTracer::new(ctx, render) {
            Ok(tracer) => {
                let queue: VecDeque<Builder> = configurations(self.quick).into();
                self.study = Some(Study {
                    total: queue.len(),
                    queue,
                    tracer,
                    camera: *current.camera,
                    settings: MeasureSettings {
                        sah: current.sah,
                        repeats: MEASURE_REPEATS,
                        spp: MEASURE_SPP,
                    },
                });
            }
            Err(e) => self.error = Some(format!("cannot trace for the trade-off: {e}")),
        }
    }
}

/// The colour of measurement `i` in the plot and the tables: hues a golden angle apart, so colours
/// stay put while measurements arrive.
fn color(i: usize) -> egui::Color32 {
    let hue = (i as f32 * 0.618_034).fract();
    egui::ecolor::Hsva::new(hue, 0.75, 0.95, 1.0).into()
}
