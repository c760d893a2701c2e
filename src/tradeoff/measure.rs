//! Measuring one builder configuration for the trade-off study, the way `treelet bench` does:
//! build (GPU builders: one warm-up build, on a GPU a tuning of the build schedule as `bench` does
//! by default, then the median of `repeats` timed builds, GPU timestamps; CPU builders: CPU time
//! of one build), validate, SAH, then trace diffuse paths with
//! the caller's tracer: a warm-up trace, then the median throughput of `repeats` timed traces.
//! Every configuration traces the same camera, image size and sample count from the same seeds.
//! Studies on a shared machine measure all configurations in several round-robin passes and keep
//! the medians (`median_of_passes`), so load that comes and goes affects all of them alike.

use super::Measurement;
use crate::bvh::treelet::RoundSchedule;
use crate::bvh::wide::{Layout, WideOptions};
use crate::bvh::{
    sah_cost, tunes_by_default, validate, validate_with_references, Builder, SahParams,
    TuningOptions,
};
use crate::gpu::{GpuContext, Timing};
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
    let (geometry, tree, report) = builder.build(
        ctx,
        scene,
        &settings.sah,
        &Timing::quick(settings.repeats),
        Layout::Binary,
        WideOptions::default(),
        RoundSchedule::default(),
        tunes_by_default(ctx).then(TuningOptions::default).as_ref(),
    )?;
    let bvh = tree.download(ctx)?;
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
    tracer.reset();
    tracer.trace(ctx, &geometry, &tree, camera, scene.sky, 1)?;
    let mut throughputs = Vec::with_capacity(settings.repeats as usize);
    for _ in 0..settings.repeats {
        // From the same seeds every time: the same paths.
        tracer.reset();
        let stats = tracer.trace(ctx, &geometry, &tree, camera, scene.sky, settings.spp)?;
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

/// One measurement from several passes over the same configuration: the median build time and
/// the median throughput; label and SAH from the first pass (trees are deterministic); valid only
/// if every pass was. `None` for no passes.
pub fn median_of_passes(passes: &[Measurement]) -> Option<Measurement> {
    let first = passes.first()?;
    let median = |get: fn(&Measurement) -> f64| {
        let mut values: Vec<f64> = passes.iter().map(get).collect();
        values.sort_by(f64::total_cmp);
        values[values.len() / 2]
    };
    Some(Measurement {
        build_ms: median(|m| m.build_ms),
        mrays_per_s: median(|m| m.mrays_per_s),
        valid: passes.iter().all(|m| m.valid),
        ..first.clone()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn passes_combine_into_medians() {
        let pass = |build_ms, mrays_per_s, valid| Measurement {
            label: "lbvh".into(),
            builder: "lbvh".into(),
            treelet_size: None,
            rounds: None,
            gpu: true,
            build_ms,
            sah: 50.0,
            mrays_per_s,
            valid,
        };
        let combined = median_of_passes(&[
            pass(9.0, 1.0, true),
            pass(1.0, 3.0, true),
            pass(5.0, 2.0, false),
        ])
        .unwrap();
        assert_eq!((combined.build_ms, combined.mrays_per_s), (5.0, 2.0));
        assert!(!combined.valid);
        assert_eq!(combined.sah, 50.0);
        assert!(median_of_passes(&[]).is_none());
    }
}
