//! Measuring one builder configuration for the trade-off study, the way `treelet bench` does:
//! build (GPU builders: one warm-up build, then the median of `repeats` timed builds, GPU
//! timestamps; CPU builders: CPU time of one build), validate, SAH, then trace diffuse paths with
//! the caller's tracer: a warm-up trace, then the median throughput of `repeats` timed traces. Every configuration traces the same camera, image
//! size and sample count from the same seeds.

use super::Measurement;
use crate::bvh::{sah_cost, validate, validate_with_references, Builder, SahParams};
use crate::gpu::GpuContext;
use crate::scene::{Camera, Scene};
use crate::trace::PathTracer;
use crate::{Error, Result};

/// What every configuration of one study shares.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasureSettings {
    pub sah: SahParams,
    /// Timed builds per GPU builder and timed traces per configuration (medians are kept).
    pub repeats: u32,
    /// Samples per pixel of the timed trace.
    pub spp: u32,
}

/// Builds `scene` with `builder` and traces it with `tracer` from `camera`.
pub fn measure(
    ctx: &GpuContext,
    scene: &Scene,
    camera: &Camera,
    builder: Builder,
    tracer: &mut PathTracer,
    settings: &MeasureSettings,
) -> Result<Measurement> {
    if settings.spp == 0 || settings.repeats == 0 {
        return Err(Error::InvalidArgument(format!(
            "samples per pixel ({}) and build repeats ({}) must be at least 1",
            settings.spp, settings.repeats
        )));
    }
    let (gpu_scene, report) = builder.build(ctx, scene, &settings.sah, settings.repeats)?;
    let bvh = gpu_scene.download_bvh(ctx)?;
    let validation = if builder.duplicates_references() {
        validate_with_references(&bvh, &scene.triangles)
    } else {
        validate(&bvh, &scene.triangles)
    };
    let valid = match validation {
        Ok(_) => true,
        Err(e) => {
            log::error!("{} tree of {} is invalid: {e}", builder.label(), scene.name);
            false
        }
    };
    // Warm-up: the first dispatch on a new tree pays for caches and (once) pipeline compilation.
    tracer.reset(ctx);
    tracer.trace(ctx, &gpu_scene, camera, scene.sky, 1)?;
    let mut throughputs = Vec::with_capacity(settings.repeats as usize);
    for _ in 0..settings.repeats {
        // From the same seeds every time: the same paths.
        tracer.reset(ctx);
        let stats = tracer.trace(ctx, &gpu_scene, camera, scene.sky, settings.spp)?;
        // Without timestamp queries, wall-clock time stands in for GPU time.
        throughputs.push(
            stats
                .mrays_per_s()
                .unwrap_or_else(|| stats.rays as f64 / (stats.wall_ms.max(1e-6) * 1e3)),
        );
    }
    throughputs.sort_by(f64::total_cmp);
    let mrays_per_s = throughputs[throughputs.len() / 2];
    let treelets = builder.treelet_settings();
    Ok(Measurement {
        label: builder.label(),
        builder: builder.name().to_string(),
        treelet_size: treelets.map(|s| s.treelet_size),
        rounds: treelets.map(|s| s.rounds),
        gpu: builder.is_gpu(),
        build_ms: report.build_ms,
        sah: f64::from(sah_cost(&bvh, &settings.sah)),
        mrays_per_s,
        valid,
    })
}
