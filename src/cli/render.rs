//! `treelet render`: build a scene's BVH, path-trace it and write a PNG.

use std::path::PathBuf;

use clap::Args;
use treelet::bvh::Builder;
use treelet::gpu::GpuContext;
use treelet::scene::load_scene;
use treelet::trace::PathTracer;
use treelet::{Error, Result};

use super::{parse_builder, TraceArgs};

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    trace: TraceArgs,
    /// Output PNG file
    #[arg(long, default_value = "treelet.png")]
    out: PathBuf,
    /// BVH builder
    #[arg(long, default_value = "sweep", value_parser = parse_builder)]
    builder: Builder,
}

pub fn run(gpu: &GpuContext, args: &RenderArgs) -> Result<()> {
    let scene = load_scene(&args.trace.scene)?;
    let params = args.trace.sah_params()?;
    log::info!("{}: {} triangles", scene.name, scene.triangles.len());
    let builders = args.trace.builder_variants(&[args.builder]);
    let [builder] = builders[..] else {
        return Err(Error::InvalidArgument(
            "render takes one --treelet-size and one --rounds value".into(),
        ));
    };
    let (gpu_scene, report) = builder.build(gpu, &scene, &params, 1)?;
    log::info!(
        "{} build: {:.2} ms, {} nodes",
        builder.label(),
        report.build_ms,
        gpu_scene.node_count
    );
    let mut tracer = PathTracer::new(gpu, args.trace.render_settings())?;
    let stats = tracer.trace(gpu, &gpu_scene, &scene.camera, scene.sky, args.trace.spp)?;
    let image = tracer.read_image(gpu)?;
    image.save(&args.out).map_err(|e| Error::Io {
        path: args.out.clone(),
        source: std::io::Error::other(e),
    })?;
    let mrays = stats
        .mrays_per_s()
        .map_or("n/a".to_string(), |m| format!("{m:.2}"));
    log::info!(
        "wrote {} ({}x{}, {} spp, {} rays, {mrays} Mrays/s on {})",
        args.out.display(),
        args.trace.width,
        args.trace.height,
        stats.samples,
        stats.rays,
        gpu.adapter_description()
    );
    Ok(())
}
