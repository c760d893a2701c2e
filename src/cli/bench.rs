//! `treelet bench`: for each requested builder, build, validate, measure SAH and trace diffuse paths;
//! print one JSON object per line.

use std::collections::BTreeMap;

use clap::Args;
use serde::Serialize;
use treelet::bvh::{sah_cost, validate, Builder};
use treelet::gpu::{GpuContext, StageTime};
use treelet::scene::load_scene;
use treelet::trace::PathTracer;
use treelet::Result;

use super::{parse_builder, TraceArgs};

#[derive(Args, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    trace: TraceArgs,
    /// BVH builders to measure (comma-separated)
    #[arg(long, default_value = "sweep", value_delimiter = ',', value_parser = parse_builder)]
    builder: Vec<Builder>,
    /// Print JSON lines (the default and only format for now; kept for scripts that pass it)
    #[arg(long)]
    json: bool,
    /// Untimed trace passes before measuring (the first dispatch compiles shaders)
    #[arg(long, default_value_t = 1)]
    warmup: u32,
    /// Timed builds per GPU builder (the median is reported)
    #[arg(long, default_value_t = 5)]
    repeats: u32,
}

#[derive(Serialize)]
struct BenchRecord {
    scene: String,
    builder: &'static str,
    adapter: String,
    triangles: usize,
    nodes: usize,
    leaves: usize,
    build_ms: f64,
    build_wall_ms: f64,
    mtris_per_s: f64,
    stages_ms: BTreeMap<String, Option<f64>>,
    sah: f32,
    valid: bool,
    width: u32,
    height: u32,
    spp: u32,
    max_depth: u32,
    rays: u64,
    trace_ms: Option<f64>,
    trace_wall_ms: f64,
    mrays_per_s: Option<f64>,
}

pub fn run(gpu: &GpuContext, args: &BenchArgs) -> Result<()> {
    let scene = load_scene(&args.trace.scene)?;
    let params = args.trace.sah_params()?;
    for &builder in &args.builder {
        let (gpu_scene, report) = builder.build(gpu, &scene, &params, args.repeats)?;
        let bvh = gpu_scene.download_bvh(gpu)?;
        let validation = validate(&bvh, &scene.triangles);
        if let Err(e) = &validation {
            log::error!("{} tree of {} is invalid: {e}", builder.name(), scene.name);
        }
        let mut tracer = PathTracer::new(gpu, args.trace.render_settings())?;
        for _ in 0..args.warmup {
            tracer.trace(gpu, &gpu_scene, &scene.camera, scene.sky, 1)?;
        }
        tracer.reset(gpu);
        let stats = tracer.trace(gpu, &gpu_scene, &scene.camera, scene.sky, args.trace.spp)?;
        let record = BenchRecord {
            scene: scene.name.clone(),
            builder: builder.name(),
            adapter: gpu.adapter_description(),
            triangles: scene.triangles.len(),
            nodes: bvh.nodes.len(),
            leaves: bvh.leaf_count(),
            build_ms: report.build_ms,
            build_wall_ms: report.wall_ms,
            mtris_per_s: scene.triangles.len() as f64 / (report.build_ms * 1e3),
            stages_ms: stage_totals(report.stages),
            sah: sah_cost(&bvh, &params),
            valid: validation.is_ok(),
            width: args.trace.width,
            height: args.trace.height,
            spp: stats.samples,
            max_depth: args.trace.max_depth,
            rays: stats.rays,
            trace_ms: stats.trace_ms,
            trace_wall_ms: stats.wall_ms,
            mrays_per_s: stats.mrays_per_s(),
        };
        println!(
            "{}",
            serde_json::to_string(&record).expect("record serializes")
        );
    }
    Ok(())
}

/// Stage times by label; passes with the same label (e.g. the sort's) are added up.
fn stage_totals(stages: Vec<StageTime>) -> BTreeMap<String, Option<f64>> {
    let mut totals: BTreeMap<String, Option<f64>> = BTreeMap::new();
    for stage in stages {
        let total = totals.entry(stage.label).or_insert(Some(0.0));
        *total = total.zip(stage.ms).map(|(a, b)| a + b);
    }
    totals
}
