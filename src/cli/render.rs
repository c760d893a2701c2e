//! `treelet render`: build a scene's BVH, path-trace it and write a PNG; with `--frames N`, render
//! N frames of an animated scene into a folder (`render_frames`).

use std::path::PathBuf;

use clap::Args;
use treelet::anim::load_still;
use treelet::bvh::treelet::RoundSchedule;
use treelet::bvh::wide::WideOptions;
use treelet::bvh::{Builder, UpdateMode};
use treelet::gpu::{GpuContext, Timing};
use treelet::trace::{save_png, PathTracer};
use treelet::{Error, Result};

use super::{parse_update_mode, render_frames, TraceArgs, TuneSchedule};

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub trace: TraceArgs,
    /// Output PNG file (default treelet.png); with --frames, the folder for frame_0000.png, …
    /// (default frames)
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// BVH builder: sweep, sbvh, lbvh, trbvh (default sweep); with --frames also refit and
    /// refit-trbvh (the first frame's tree, refitted every frame; default lbvh)
    #[arg(long, value_parser = parse_update_mode)]
    pub builder: Option<UpdateMode>,
    /// Render this many frames of an animated scene (see `treelet scenes`), one PNG each, with the
    /// per-frame pipeline: animate → build on the GPU → trace
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..))]
    pub frames: Option<u32>,
    /// With --frames: print one JSON object per frame (frame, t, build_ms, sah, rays, trace_ms,
    /// mrays_per_s, …)
    #[arg(long, requires = "frames")]
    pub json: bool,
    /// With --frames: tune a GPU builder's build schedule on the first frame before rendering
    /// (every schedule builds the same tree; see `bench --tune-schedule`): auto (on GPUs, the
    /// default), on or off
    #[arg(long, value_enum, requires = "frames")]
    pub tune_schedule: Option<TuneSchedule>,
}

pub fn run(gpu: &GpuContext, args: &RenderArgs) -> Result<()> {
    if let Some(frames) = args.frames {
        return render_frames::run(gpu, args, frames);
    }
    let builder = match args.builder {
        None => Builder::Sweep,
        Some(UpdateMode::Rebuild(builder)) => builder,
        Some(mode @ UpdateMode::Refit(_)) => {
            return Err(Error::InvalidArgument(format!(
                "--builder {} refits an animated scene's tree from frame to frame: use it with --frames",
                mode.name()
            )))
        }
    };
    let out = args.out.clone().unwrap_or_else(|| "treelet.png".into());
    let scene = load_still(&args.trace.scene)?;
    let params = args.trace.sah_params()?;
    log::info!("{}: {} triangles", scene.name, scene.triangles.len());
    let builders = args.trace.builder_variants(&[builder])?;
    let [builder] = builders[..] else {
        return Err(Error::InvalidArgument(
            "render takes one --treelet-size and one --rounds value".into(),
        ));
    };
    let layout = args.trace.single_layout()?;
    let (geometry, tree, report) = builder.build(
        gpu,
        &scene,
        &params,
        &Timing::quick(1),
        layout,
        WideOptions::collapse(args.trace.single_wide_collapse()?),
        RoundSchedule::default(),
        None,
    )?;
    let nodes = match &tree.wide {
        Some(wide) => format!("{} wide nodes", wide.counts(gpu)?.0),
        None => format!("{} nodes", tree.counts(gpu)?.0),
    };
    log::info!(
        "{} build: {:.2} ms, {nodes}",
        builder.label(),
        report.build_ms
    );
    let mut tracer = PathTracer::new(gpu, args.trace.render_settings(layout))?;
    let stats = tracer.trace(
        gpu,
        &geometry,
        &tree,
        &scene.camera,
        scene.sky,
        args.trace.spp,
    )?;
    let image = tracer.read_image(gpu)?;
    save_png(&image, &out)?;
    let mrays = stats
        .mrays_per_s()
        .map_or("n/a".to_string(), |m| format!("{m:.2}"));
    log::info!(
        "wrote {} ({}x{}, {} spp, {} rays, {mrays} Mrays/s on {})",
        out.display(),
        args.trace.width,
        args.trace.height,
        stats.samples,
        stats.rays,
        gpu.adapter_description()
    );
    Ok(())
}
