//! The builders a user can choose by name, and one entry point that builds a scene's tree with any
//! of them into GPU buffers ready to trace, with timings.

use std::time::Instant;

use super::lbvh::LbvhBuilder;
use super::{build_sweep_sah, SahParams};
use crate::gpu::{GpuContext, StageTime};
use crate::scene::Scene;
use crate::trace::GpuScene;
use crate::{Error, Result};

/// A BVH construction method, selectable by name on the command line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// CPU full-sweep SAH (greedy top-down): the quality reference.
    Sweep,
    /// GPU LBVH (Karras 2012): Morton order, one primitive per leaf.
    Lbvh,
}

/// Build timings. For GPU builders `build_ms` is the sum of the GPU stage times (timestamp
/// queries; wall-clock time where the device has none); for CPU builders it is CPU time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildReport {
    pub build_ms: f64,
    pub wall_ms: f64,
    pub stages: Vec<StageTime>,
}

impl Builder {
    pub const ALL: &[Builder] = &[Builder::Sweep, Builder::Lbvh];

    pub fn name(self) -> &'static str {
        match self {
            Builder::Sweep => "sweep",
            Builder::Lbvh => "lbvh",
        }
    }

    /// Whether the builder runs on the GPU (the per-frame path) rather than as a CPU reference.
    pub fn is_gpu(self) -> bool {
        matches!(self, Builder::Lbvh)
    }

    pub fn parse(name: &str) -> Result<Self> {
        Self::ALL
            .iter()
            .copied()
            .find(|b| b.name() == name)
            .ok_or_else(|| {
                let known: Vec<_> = Self::ALL.iter().map(|b| b.name()).collect();
                Error::InvalidArgument(format!(
                    "unknown builder '{name}' (known: {})",
                    known.join(", ")
                ))
            })
    }

    /// Builds `scene`'s tree and returns the scene on the GPU ready to trace. GPU builders run one
    /// untimed warm-up build (pipeline compilation) and then `repeats` timed builds, reporting the
    /// one with the median time.
    pub fn build(
        self,
        ctx: &GpuContext,
        scene: &Scene,
        params: &SahParams,
        repeats: u32,
    ) -> Result<(GpuScene, BuildReport)> {
        match self {
            Builder::Sweep => {
                let start = Instant::now();
                let bvh = build_sweep_sah(&scene.triangles, params);
                let build_ms = start.elapsed().as_secs_f64() * 1e3;
                let gpu_scene = GpuScene::upload(ctx, scene, &bvh)?;
                let report = BuildReport {
                    build_ms,
                    wall_ms: build_ms,
                    stages: vec![StageTime {
                        label: "cpu sweep".into(),
                        ms: Some(build_ms),
                    }],
                };
                Ok((gpu_scene, report))
            }
            Builder::Lbvh => {
                let mut gpu_scene = GpuScene::upload_geometry(ctx, scene, 1, 1)?;
                let mut builder = LbvhBuilder::new(ctx);
                builder.build(ctx, &mut gpu_scene)?;
                let mut reports = Vec::new();
                for _ in 0..repeats.max(1) {
                    let start = Instant::now();
                    let stages = builder.build(ctx, &mut gpu_scene)?;
                    ctx.device
                        .poll(wgpu::PollType::wait_indefinitely())
                        .map_err(|e| Error::Gpu(format!("device poll failed: {e}")))?;
                    let wall_ms = start.elapsed().as_secs_f64() * 1e3;
                    let gpu_ms: Option<f64> = stages.iter().map(|s| s.ms).sum();
                    reports.push(BuildReport {
                        build_ms: gpu_ms.unwrap_or(wall_ms),
                        wall_ms,
                        stages,
                    });
                }
                reports.sort_by(|a, b| a.build_ms.total_cmp(&b.build_ms));
                let median = reports.swap_remove(reports.len() / 2);
                Ok((gpu_scene, median))
            }
        }
    }
}
