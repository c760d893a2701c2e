//! `treelet tradeoff`: the quality–speed trade-off of Karras & Aila 2013, Figure 1, on one scene.
//! Measures every builder configuration (build time, SAH, diffuse Mrays/s; see
//! `treelet::tradeoff`), then writes `tradeoff-<scene>.csv` (one row per configuration),
//! `tradeoff-<scene>.json` (measurements, curve samples, best ranges) and two PNG charts
//! (`-throughput.png`: effective Mrays/s against rays per frame; `-pareto.png`: SAH against build
//! time), and prints which configuration is best for which rays per frame.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use treelet::anim::load_still;
use treelet::bvh::SahParams;
use treelet::gpu::GpuContext;
use treelet::trace::{PathTracer, RenderSettings};
use treelet::tradeoff::{
    best_ranges, configurations, effective_mrays, log_space, measure, median_of_passes,
    pareto_chart, pareto_front, throughput_chart, BestRange, MeasureSettings, Measurement,
    CHART_SIZE, CURVE_POINTS, RAYS_RANGE,
};
use treelet::{Error, Result};

use super::DEFAULT_SCENE;

#[derive(Args, Debug)]
pub struct TradeoffArgs {
    /// Scene name (see `treelet scenes`) or path to an OBJ file
    #[arg(long, default_value = DEFAULT_SCENE)]
    scene: String,
    /// Folder for the CSV, JSON and PNG files (created if missing)
    #[arg(long, default_value = ".")]
    out: PathBuf,
    /// Image width of the throughput measurement, in pixels
    #[arg(long, default_value_t = 320)]
    width: u32,
    /// Image height of the throughput measurement, in pixels
    #[arg(long, default_value_t = 240)]
    height: u32,
    /// Samples (paths) per pixel of the throughput measurement
    #[arg(long, default_value_t = 4)]
    spp: u32,
    /// Maximum rays per path (1 = primary rays only)
    #[arg(long, default_value_t = 4)]
    max_depth: u32,
    /// Maximum primitives per leaf
    #[arg(long, default_value_t = SahParams::default().max_leaf_size)]
    max_leaf_size: u32,
    /// Round-robin passes over all configurations, each one timed build and one timed trace per
    /// configuration (the medians are kept)
    #[arg(long, default_value_t = 3)]
    repeats: u32,
    /// One trbvh setting (n=5, 1 round) and one trbvh-split budget instead of the sweeps
    #[arg(long)]
    quick: bool,
}

#[derive(Serialize)]
struct Report<'a> {
    scene: &'a str,
    triangles: usize,
    adapter: String,
    width: u32,
    height: u32,
    spp: u32,
    max_depth: u32,
    max_leaf_size: u32,
    repeats: u32,
    measurements: &'a [Measurement],
    /// Labels on the SAH-vs-build-time Pareto front, by build time.
    pareto_front: Vec<&'a str>,
    curves: Curves<'a>,
    best_ranges: &'a [BestRange],
    /// The same among GPU builders only (the per-frame path).
    best_ranges_gpu_only: &'a [BestRange],
    charts: Charts,
}

/// Effective Mrays/s of every configuration at the sampled rays per frame.
#[derive(Serialize)]
struct Curves<'a> {
    rays: &'a [f64],
    series: Vec<Series<'a>>,
}

#[derive(Serialize)]
struct Series<'a> {
    label: &'a str,
    effective_mrays: Vec<f64>,
}

#[derive(Serialize)]
struct Charts {
    throughput: String,
    pareto: String,
    width: u32,
    height: u32,
}

pub fn run(gpu: &GpuContext, args: &TradeoffArgs) -> Result<()> {
    if args.spp == 0 || args.repeats == 0 {
        return Err(Error::InvalidArgument(
            "--spp and --repeats must be at least 1".into(),
        ));
    }
    if args.max_leaf_size == 0 {
        return Err(Error::InvalidArgument(
            "--max-leaf-size must be at least 1".into(),
        ));
    }
    let scene = load_still(&args.scene)?;
    let mut tracer = PathTracer::new(
        gpu,
        RenderSettings {
            width: args.width,
            height: args.height,
            max_depth: args.max_depth,
            ..RenderSettings::default()
        },
    )?;
    std::fs::create_dir_all(&args.out).map_err(|e| Error::Write {
        path: args.out.clone(),
        message: e.to_string(),
    })?;
    let settings = MeasureSettings {
        sah: SahParams {
            max_leaf_size: args.max_leaf_size,
            ..SahParams::default()
        },
        repeats: 1,
        spp: args.spp,
    };
    let configs = configurations(args.quick);
    let progress = ProgressBar::new(configs.len() as u64 * u64::from(args.repeats)).with_style(
        ProgressStyle::with_template("{spinner} [{bar:30}] {pos}/{len} {msg} ({elapsed})")
            .map_err(|e| Error::InvalidArgument(format!("progress bar template: {e}")))?
            .progress_chars("=> "),
    );
    // Round-robin passes: load from other processes that comes and goes hits every
    // configuration alike, and the medians drop the outliers.
    let mut passes: Vec<Vec<Measurement>> = vec![Vec::new(); configs.len()];
    for pass in 1..=args.repeats {
        for (builder, runs) in configs.iter().zip(&mut passes) {
            progress.set_message(format!(
                "{} (pass {pass}/{})",
                builder.label(),
                args.repeats
            ));
            runs.push(measure(
                gpu,
                &scene,
                &scene.camera,
                *builder,
                &mut tracer,
                &settings,
            )?);
            progress.inc(1);
        }
    }
    progress.finish_and_clear();
    let measurements: Vec<Measurement> = passes
        .iter()
        .filter_map(|runs| median_of_passes(runs))
        .collect();

    let (min_rays, max_rays) = RAYS_RANGE;
    let rays = log_space(min_rays, max_rays, CURVE_POINTS);
    let best = best_ranges(&measurements, min_rays, max_rays);
    // The per-frame path alone: GPU builders only.
    let gpu_measurements: Vec<Measurement> =
        measurements.iter().filter(|m| m.gpu).cloned().collect();
    let best_gpu = best_ranges(&gpu_measurements, min_rays, max_rays);
    let front = pareto_front(&measurements);
    let stem = format!("tradeoff-{}", file_tag(&scene.name));
    let out = |suffix: &str| args.out.join(format!("{stem}{suffix}"));
    let title = format!(
        "{} · {} triangles · {}",
        scene.name,
        scene.triangles.len(),
        gpu.info.name
    );
    let (throughput_png, pareto_png) = (out("-throughput.png"), out("-pareto.png"));
    throughput_chart(&throughput_png, &title, &measurements, &rays)?;
    pareto_chart(&pareto_png, &title, &measurements, &front)?;
    write_file(&out(".csv"), &csv(&measurements, &best))?;
    let report = Report {
        scene: &scene.name,
        triangles: scene.triangles.len(),
        adapter: gpu.adapter_description(),
        width: args.width,
        height: args.height,
        spp: args.spp,
        max_depth: args.max_depth,
        max_leaf_size: args.max_leaf_size,
        repeats: args.repeats,
        measurements: &measurements,
        pareto_front: front
            .iter()
            .map(|&i| measurements[i].label.as_str())
            .collect(),
        curves: Curves {
            rays: &rays,
            series: measurements
                .iter()
                .map(|m| Series {
                    label: &m.label,
                    effective_mrays: rays.iter().map(|&r| effective_mrays(m, r)).collect(),
                })
                .collect(),
        },
        best_ranges: &best,
        best_ranges_gpu_only: &best_gpu,
        charts: Charts {
            throughput: file_name(&throughput_png),
            pareto: file_name(&pareto_png),
            width: CHART_SIZE.0,
            height: CHART_SIZE.1,
        },
    };
    let json = serde_json::to_string_pretty(&report)
        .map_err(|e| Error::InvalidArgument(format!("cannot encode the report: {e}")))?;
    write_file(&out(".json"), &json)?;
    print_summary(&measurements, &best, &best_gpu);
    log::info!(
        "wrote {stem}.csv, {stem}.json, {stem}-throughput.png and {stem}-pareto.png to {}",
        args.out.display()
    );
    Ok(())
}

/// One row per configuration; the best-range columns are empty for configurations never best.
fn csv(measurements: &[Measurement], best: &[BestRange]) -> String {
    let mut text = String::from(
        "label,builder,treelet_size,rounds,build_ms,sah,mrays_per_s,best_from_rays,best_to_rays\n",
    );
    let opt = |v: Option<u32>| v.map_or(String::new(), |v| v.to_string());
    for m in measurements {
        let range = best.iter().find(|r| r.label == m.label);
        let (from, to) = range.map_or((String::new(), String::new()), |r| {
            (format!("{:.6e}", r.from_rays), format!("{:.6e}", r.to_rays))
        });
        // Labels and builder names hold no commas or quotes.
        let _ = writeln!(
            text,
            "{},{},{},{},{:.4},{:.4},{:.4},{from},{to}",
            m.label,
            m.builder,
            opt(m.treelet_size),
            opt(m.rounds),
            m.build_ms,
            m.sah,
            m.mrays_per_s
        );
    }
    text
}

fn print_summary(measurements: &[Measurement], best: &[BestRange], best_gpu: &[BestRange]) {
    println!(
        "{:<28} {:>12} {:>10} {:>10}",
        "configuration", "build ms", "SAH", "Mrays/s"
    );
    for m in measurements {
        let invalid = if m.valid { "" } else { "  (INVALID TREE)" };
        println!(
            "{:<28} {:>12.3} {:>10.3} {:>10.3}{invalid}",
            m.label, m.build_ms, m.sah, m.mrays_per_s
        );
    }
    for (title, ranges) in [
        ("best configuration by rays per frame:", best),
        ("best GPU configuration by rays per frame:", best_gpu),
    ] {
        println!("{title}");
        for r in ranges {
            println!(
                "  {:>10.3e} .. {:>10.3e} rays: {}",
                r.from_rays, r.to_rays, r.label
            );
        }
    }
}

/// A scene name made safe for a file name: "crytek_sponza" stays, "my scene!" → "my_scene_".
fn file_tag(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '-' || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect()
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map_or(String::new(), |n| n.to_string_lossy().into_owned())
}

fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::Write {
        path: path.to_path_buf(),
        message: e.to_string(),
    })
}
