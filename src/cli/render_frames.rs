//! `treelet render --scene <animated> --frames N --out <dir>`: the viewer's per-frame pipeline,
//! headless. Frame f at the animation's time of frame f (looping): animate (a GPU kernel, or a CPU
//! evaluation + upload for BART scenes and OBJ sequences) → update the BVH on the GPU (a rebuild
//! with `--builder lbvh|trbvh`, or `refit`/`refit-trbvh`: the first frame's tree refitted) → trace
//! `--spp` samples from the animation's camera → `<dir>/frame_0000.png`, …. CPU reference builders
//! (`sweep`, `sbvh`) rebuild every frame from the CPU-evaluated triangles instead.
//!
//! The tree of every frame is read back for its SAH cost (not part of any timing). `--json`
//! prints one JSON object per frame on stdout; a progress bar runs on stderr (when it is a
//! terminal).

use std::collections::BTreeMap;
use std::path::Path;
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use treelet::anim::{load_animation, TreeUpdater, UpdateMode};
use treelet::bvh::{sah_cost, Builder};
use treelet::gpu::{aggregate_stages, GpuContext, StageTime, Timing};
use treelet::trace::{save_png, GpuScene, PathTracer};
use treelet::{Error, Result};

use super::render::RenderArgs;

/// One frame's measurements (one JSON line with `--json`).
#[derive(Serialize)]
struct FrameRecord {
    scene: String,
    builder: String,
    frame: u32,
    t: f32,
    triangles: u32,
    nodes: u32,
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
    let mut gpu_scene = GpuScene::upload_geometry(gpu, &first)?;
    let mut updater = if mode.is_gpu() {
        Some(TreeUpdater::new(gpu, mode, &params)?)
    } else {
        None
    };
    let mut tracer = PathTracer::new(gpu, args.trace.render_settings())?;
    let bar = ProgressBar::new(u64::from(frames));
    if let Ok(style) = ProgressStyle::with_template("{bar:30} {pos}/{len} frames {msg}") {
        bar.set_style(style);
    }
    for frame in 0..frames {
        let t = range.frame_time(frame);
        let (animate_ms, build_ms, stages) = match updater.as_mut() {
            Some(updater) => {
                let animate = animation.animate(gpu, t, &mut gpu_scene)?;
                let start = Instant::now();
                let stages = updater.update(gpu, &mut gpu_scene)?;
                let build_ms = gpu_build_ms(&stages, elapsed_ms(start));
                (animate.ms, build_ms, stages)
            }
            None => {
                let start = Instant::now();
                let scene = animation.scene_at(t);
                let animate_ms = elapsed_ms(start);
                let (built, report) =
                    mode.builder()
                        .build(gpu, &scene, &params, &Timing::quick(1))?;
                gpu_scene = built;
                (Some(animate_ms), report.build_ms, report.stages)
            }
        };
        let sah = sah_cost(&gpu_scene.download_bvh(gpu)?, &params);
        tracer.reset(gpu);
        let stats = tracer.trace(
            gpu,
            &gpu_scene,
            &animation.camera(t),
            animation.sky(),
            args.trace.spp,
        )?;
        save_frame(&tracer, gpu, &out_dir.join(format!("frame_{frame:04}.png")))?;
        let record = FrameRecord {
            scene: animation.name().to_owned(),
            builder: mode.name().to_owned(),
            frame,
            t,
            triangles: gpu_scene.triangle_count,
            nodes: gpu_scene.node_count,
            animate_ms,
            build_ms,
            stages_ms: aggregate_stages(stages)
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

fn save_frame(tracer: &PathTracer, gpu: &GpuContext, path: &Path) -> Result<()> {
    save_png(&tracer.read_image(gpu)?, path)
}
