//! The builders a user can choose by name, and one entry point that builds a scene's tree with any
//! of them into GPU buffers ready to trace, with timings.

use std::time::Instant;

use super::lbvh::LbvhBuilder;
use super::treelet::{TrbvhBuilder, TreeletSettings};
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
    /// GPU TRBVH (Karras & Aila 2013): LBVH + treelet restructuring rounds + leaf collapse.
    Trbvh(TreeletSettings),
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
    pub const ALL: &[Builder] = &[
        Builder::Sweep,
        Builder::Lbvh,
        Builder::Trbvh(TreeletSettings::BALANCED),
    ];

    pub fn name(self) -> &'static str {
        match self {
            Builder::Sweep => "sweep",
            Builder::Lbvh => "lbvh",
            Builder::Trbvh(_) => "trbvh",
        }
    }

    /// Whether the builder runs on the GPU (the per-frame path) rather than as a CPU reference.
    pub fn is_gpu(self) -> bool {
        matches!(self, Builder::Lbvh | Builder::Trbvh(_))
    }

    /// The same builder with other treelet settings (no effect on builders without treelets).
    pub fn with_treelet_settings(self, settings: TreeletSettings) -> Self {
        match self {
            Builder::Trbvh(_) => Builder::Trbvh(settings),
            other => other,
        }
    }

    /// "trbvh n=7 r=3" style label for reports.
    pub fn label(self) -> String {
        match self {
            Builder::Trbvh(s) => format!("trbvh n={} r={}", s.treelet_size, s.rounds),
            other => other.name().to_string(),
        }
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
            Builder::Lbvh | Builder::Trbvh(_) => {
                let mut gpu_scene = GpuScene::upload_geometry(ctx, scene, 1, 1)?;
                let mut builder = GpuBuilder::new(ctx, self, params)?;
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

/// A GPU builder ready to rebuild a scene's tree every frame.
pub enum GpuBuilder {
    Lbvh(Box<LbvhBuilder>),
    Trbvh(Box<TrbvhBuilder>),
}

impl GpuBuilder {
    /// Pipelines for `builder`, which must be a GPU builder.
    pub fn new(ctx: &GpuContext, builder: Builder, params: &SahParams) -> Result<Self> {
        match builder {
            Builder::Lbvh => Ok(Self::Lbvh(Box::new(LbvhBuilder::new(ctx)))),
            Builder::Trbvh(settings) => Ok(Self::Trbvh(Box::new(TrbvhBuilder::new(
                ctx, settings, *params,
            )?))),
            Builder::Sweep => Err(Error::InvalidArgument(
                "sweep is a CPU reference builder, not a GPU builder".into(),
            )),
        }
    }

    /// SAH parameters for the next builds (the treelet builder's cost model and max leaf size).
    pub fn set_sah_params(&mut self, params: SahParams) {
        if let Self::Trbvh(b) = self {
            b.sah = params;
        }
    }

    /// Rebuilds the scene's tree in place; returns the per-stage GPU times.
    pub fn build(&mut self, ctx: &GpuContext, scene: &mut GpuScene) -> Result<Vec<StageTime>> {
        match self {
            Self::Lbvh(b) => b.build(ctx, scene),
            Self::Trbvh(b) => b.build(ctx, scene),
        }
    }
}
