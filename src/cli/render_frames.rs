//! `treelet render --scene <animated> --frames N --out <dir>`: the viewer's per-frame pipeline,
//! headless. Frame f at the animation's time of frame f (looping): animate (a GPU kernel, or a CPU
//! evaluation + upload for BART scenes and OBJ sequences) → update the BVH on the GPU (a rebuild
//! with `--builder lbvh|trbvh`, or `refit`/`refit-trbvh`: the first frame's tree refitted) → trace
//! `--spp` samples from the animation's camera → `<dir>/frame_0000.png`, …. CPU reference builders
//! (`sweep`, `sbvh`) rebuild every frame from the CPU-evaluated triangles instead.
//!
//! On a GPU (or with `--tune-schedule on`) a GPU builder's build schedule is tuned on the first
//! frame before the frames are rendered (`bvh::tune_updater`; the trees stay the same).
//!
//! Each frame is one recording and one submission (animate → build → trace → tonemap), as in the
//! viewer; then its image is read back for the PNG and its tree for its SAH cost (not part of any
//! timing). `--json`
//! prints one JSON object per frame on stdout; a progress bar runs on stderr (when it is a
//! terminal).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use treelet::anim::load_animation;
use treelet::bvh::{
    sah_cost, tune_updater, tunes_by_default, Builder, TreeUpdater, TuningOptions, UpdateMode,
};
use treelet::device::{Geometry, Tree};
use treelet::gpu::{aggregate_stages, GpuContext, GpuTimer, ParamSlab, Recorder, StageTime};
use treelet::trace::{save_png, PathTracer};
use treelet::{Error, Result};

use super::render::RenderArgs;

/// One frame's measurements (one JSON line with `--json`).
#[derive(Serialize)]
struct FrameRecord {
    scene: String,
    builder: String,
    /// The node layout traced (binary, or wide converted from it as a build stage).
    layout: &'static str,
    frame: u32,
    t: f32,
    triangles: u32,
    nodes: u32,
    /// GPU builders: the build schedule (as `bench` labels it; tuned on the first frame unless
    /// `--tune-schedule off` or a CPU device).
    schedule: Option<String>,
    /// GPU time of the animation kernel, or wall-clock time of the CPU evaluation (+ upload).
    animate_ms: Option<f64>,
    /// Sum of the GPU stage times (wall clock where the device has no timestamps; CPU time for
    /// CPU builders).
    build_ms: f64,
    stages_ms: BTreeMap<String, Option<f64>>,
    sah: f32,
    spp: u32,
    rays: u64,
    trace_ms: Option<f64>,
    mrays_per_s: Option<f64>,
}

/// Build time of GPU `stages`: their sum, or `wall_ms` where the device has no timestamps.
fn gpu_build_ms(stages: &[StageTime], wall_ms: f64) -> f64 {
    let gpu_ms: Option<f64> = stages.iter().map(|s| s.ms).sum();
    gpu_ms.unwrap_or(wall_ms)
}

fn elapsed_ms(start: Instant) -> f64 {
    start.elapsed().as_secs_f64() * 1e3
}

pub fn run(gpu: &GpuContext, args: &RenderArgs, frames: u32) -> Result<()> {
    let mut animation = load_animation(&args.trace.scene)?;
    let params = args.trace.sah_params()?;
    let mode = args.builder.unwrap_or(UpdateMode::Rebuild(Builder::Lbvh));
    let [builder] = args.trace.builder_variants(&[mode.builder()])?[..] else {
        return Err(Error::InvalidArgument(
            "render takes one --treelet-size, --rounds and --split-budget value".into(),
        ));
    };
    let mode = match mode {
        UpdateMode::Rebuild(_) => UpdateMode::Rebuild(builder),
        UpdateMode::Refit(_) => UpdateMode::Refit(builder),
    };
    let out_dir = args.out.clone().unwrap_or_else(|| "frames".into());
    std::fs::create_dir_all(&out_dir).map_err(|e| Error::Write {
        path: out_dir.clone(),
        message: e.to_string(),
    })?;
    let range = animation.time_range();
    let first = animation.scene_at(range.start);
    log::info!(
        "{}: {} triangles, t = {}..{} in {} frames; animate: {}; tree: {}",
        animation.name(),
        first.triangles.len(),
        range.start,
        range.end,
        range.frames,
        animation.stage().describe(),
        mode.label()
    );
    let geometry = Geometry::upload(gpu, &first)?;
    let mut tree = Tree::empty(gpu)?;
    let layout = args.trace.single_layout()?;
    let mut updater = TreeUpdater::new(gpu, mode, &params)?;
    updater.set_wide_collapse(args.trace.single_wide_collapse()?);
    updater.set_layout(gpu, layout);
    let forced = args.tune_schedule.and_then(|t| t.forced());
    if forced == Some(true) && !updater.is_tunable() {
        return Err(Error::InvalidArgument(format!(
            "--tune-schedule on does not apply to {}: only GPU rebuilds have a build schedule",
            mode.name()
        )));
    }
    let tune = forced.unwrap_or_else(|| tunes_by_default(gpu));
    if tune {
        // The first frame's geometry, after half a second of builds (GPU clocks).
        if let Some(tuned) = tune_updater(
            gpu,
            &mut updater,
            &geometry,
            &first.triangles,
            &mut tree,
            &TuningOptions::default(),
            500.0,
        )? {
            log::info!(
                "schedule [{}] kept after {} builds in {:.0} ms",
                tuned.schedule.label(),
                tuned.builds,
                tuned.wall_ms
            );
        }
    }
    let schedule = updater
        .is_tunable()
        .then(|| updater.build_schedule().label());
    let mut tracer = PathTracer::new(gpu, args.trace.render_settings(layout))?;
    let mut slab = ParamSlab::new(gpu);
    let bar = ProgressBar::new(u64::from(frames));
    if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} frames {msg}") {
        bar.set_style(style);
    }
    for frame in 0..frames {
        let t = range.frame_time(frame);
        // The frame in one recording and one submission: animate → build → trace → tonemap.
        let start = Instant::now();
        let mut timer = GpuTimer::new(gpu, updater.pass_count() + 3);
        let mut rec = Recorder::new(gpu, &mut slab, Some(&mut timer));
        let animate_cpu = animation.animate(&mut rec, t, &geometry)?;
        // CPU reference builders build from the frame's triangles on the CPU.
        let triangles = if mode.is_gpu() {
            Vec::new()
        } else {
            animation.scene_at(t).triangles
        };
        let build_cpu = updater.record(&mut rec, &geometry, &triangles, &mut tree)?;
        tracer.reset();
        let recorded = tracer.record(
            &mut rec,
            &geometry,
            &tree,
            &animation.camera(t),
            animation.sky(),
            args.trace.spp,
        )?;
        tracer.record_tonemap(&mut rec);
        rec.submit();
        let stages = timer.read(gpu)?;
        let wall_ms = elapsed_ms(start);
        let stage = |name: &str| stages.iter().find(|s| s.label == name).and_then(|s| s.ms);
        let animate_ms = animate_cpu.and_then(|s| s.ms).or_else(|| stage("animate"));
        let mut build_stages: Vec<StageTime> = stages
            .iter()
            .filter(|s| !matches!(s.label.as_str(), "animate" | "trace" | "tonemap"))
            .cloned()
            .collect();
        build_stages.extend(build_cpu);
        let build_ms = gpu_build_ms(&build_stages, wall_ms);
        let stats = tracer.read_stats(gpu, recorded, stage("trace"), wall_ms)?;
        // Outside the frame's timings: the tree for its SAH cost and the image.
        let bvh = tree.download(gpu)?;
        let sah = sah_cost(&bvh, &params);
        save_frame(
            &mut tracer,
            gpu,
            &out_dir.join(format!("frame_{frame:04}.png")),
        )?;
        let record = FrameRecord {
            scene: animation.name().to_owned(),
            builder: mode.name().to_owned(),
            layout: layout.name(),
            schedule: schedule.clone(),
            frame,
            t,
            triangles: geometry.triangle_count,
            nodes: bvh.nodes.len() as u32,
            animate_ms,
            build_ms,
            stages_ms: aggregate_stages(build_stages)
                .into_iter()
                .map(|s| (s.label, s.ms))
                .collect(),
            sah,
            spp: stats.samples,
            rays: stats.rays,
            trace_ms: stats.trace_ms,
            mrays_per_s: stats.mrays_per_s(),
        };
        if args.json {
            let line = serde_json::to_string(&record).expect("record serializes");
            bar.suspend(|| println!("{line}"));
        }
        let mrays = record
            .mrays_per_s
            .map_or("n/a".into(), |m| format!("{m:.2}"));
        bar.set_message(format!(
            "t = {t:.2}: build {build_ms:.1} ms, SAH {sah:.1}, {mrays} Mrays/s"
        ));
        bar.inc(1);
    }
    bar.finish_and_clear();
    log::info!(
        "wrote {frames} frames to {} ({}x{}, {} spp, on {})",
        out_dir.display(),
        args.trace.width,
        args.trace.height,
        args.trace.spp,
        gpu.adapter_description()
    );
    Ok(())
}

fn save_frame(tracer: &mut PathTracer, gpu: &GpuContext, path: &Path) -> Result<()> {
    save_png(&tracer.read_image(gpu)?, path)
}
