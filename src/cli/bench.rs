//! `treelet bench`: for each requested builder, build, validate, measure SAH and trace diffuse paths;
//! print one JSON object per line.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Args;
use serde::Serialize;
use treelet::bvh::{sah_cost, validate, validate_with_references, write_bvh, Builder};
use treelet::gpu::{aggregate_stages, GpuContext};
use treelet::scene::load_scene;
use treelet::trace::{PathTracer, TraceStats};
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
    /// Write each built tree to this file (format in the README; with several builders the
    /// builder label is added to the file name)
    #[arg(long)]
    export_bvh: Option<PathBuf>,
    /// Timed builds per GPU builder and timed traces per builder (the medians are reported)
    #[arg(long, default_value_t = 5)]
    repeats: u32,
}

#[derive(Serialize)]
struct BenchRecord {
    scene: String,
    builder: &'static str,
    treelet_size: Option<u32>,
    rounds: Option<u32>,
    split_budget: Option<f64>,
    adapter: String,
    triangles: usize,
    /// Triangle references in the leaves: the triangle count, plus the pieces of split
    /// triangles that ended up in different leaves (sbvh, trbvh-split).
    references: usize,
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
    let builders = args.trace.builder_variants(&args.builder);
    for &builder in &builders {
        let (gpu_scene, report) = builder.build(gpu, &scene, &params, args.repeats)?;
        let bvh = gpu_scene.download_bvh(gpu)?;
        let validation = if builder.duplicates_references() {
            validate_with_references(&bvh, &scene.triangles)
        } else {
            validate(&bvh, &scene.triangles)
        };
        if let Err(e) = &validation {
            log::error!("{} tree of {} is invalid: {e}", builder.label(), scene.name);
        }
        if let Some(path) = &args.export_bvh {
            let path = if builders.len() > 1 {
                labelled_path(path, &builder.label())
            } else {
                path.clone()
            };
            write_bvh(&path, &bvh, scene.triangles.len() as u32)?;
            log::info!("wrote {}", path.display());
        }
        let mut tracer = PathTracer::new(gpu, args.trace.render_settings())?;
        for _ in 0..args.warmup {
            tracer.trace(gpu, &gpu_scene, &scene.camera, scene.sky, 1)?;
        }
        let mut traces = Vec::new();
        for _ in 0..args.repeats.max(1) {
            tracer.reset(gpu);
            traces.push(tracer.trace(gpu, &gpu_scene, &scene.camera, scene.sky, args.trace.spp)?);
        }
        let stats = median_trace(traces);
        let record = BenchRecord {
            scene: scene.name.clone(),
            builder: builder.name(),
            treelet_size: builder.treelet_settings().map(|s| s.treelet_size),
            rounds: builder.treelet_settings().map(|s| s.rounds),
            split_budget: builder
                .treelet_settings()
                .map(|s| f64::from(s.split_percent) / 100.0),
            adapter: gpu.adapter_description(),
            triangles: scene.triangles.len(),
            references: bvh.prim_indices.len(),
            nodes: bvh.nodes.len(),
            leaves: bvh.leaf_count(),
            build_ms: report.build_ms,
            build_wall_ms: report.wall_ms,
            mtris_per_s: scene.triangles.len() as f64 / (report.build_ms * 1e3),
            stages_ms: aggregate_stages(report.stages)
                .into_iter()
                .map(|s| (s.label, s.ms))
                .collect(),
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

/// The trace of median throughput (GPU time where timestamps exist, wall-clock time otherwise).
fn median_trace(mut traces: Vec<TraceStats>) -> TraceStats {
    let key = |t: &TraceStats| {
        t.mrays_per_s()
            .unwrap_or(t.rays as f64 / t.wall_ms.max(1e-9))
    };
    traces.sort_by(|a, b| key(a).total_cmp(&key(b)));
    traces.swap_remove(traces.len() / 2)
}

/// `out.bvh` + "trbvh n=7 r=3" -> `out-trbvh-n7-r3.bvh`.
fn labelled_path(path: &Path, label: &str) -> PathBuf {
    let tag: String = label
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            '=' => None,
            c => Some(c),
        })
        .collect();
    let stem = path
        .file_stem()
        .map_or("tree".into(), |s| s.to_string_lossy());
    let ext = path
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    path.with_file_name(format!("{stem}-{tag}{ext}"))
}
