//! (Re)building the viewed scene's BVH. GPU builders rebuild in place (`GpuBuilder`: pipelines and
//! scratch reused, geometry already on the GPU): the per-frame path. CPU reference builders go
//! through `Builder::build` (build + upload) once per change.

use std::time::Instant;

use crate::bvh::{Builder, GpuBuilder, SahParams};
use crate::gpu::{aggregate_stages, GpuContext, StageTime};
use crate::scene::Scene;
use crate::trace::GpuScene;
use crate::Result;

/// One build's timings: per-stage GPU times (aggregated by label) and the total.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BuildTiming {
    pub stages: Vec<StageTime>,
    /// Sum of the stage times; wall-clock time where the device has no timestamps.
    pub total_ms: f64,
    /// Whether `total_ms` comes from GPU timestamps (false: wall clock or CPU time).
    pub timestamped: bool,
}

pub enum FrameBuilder {
    /// A GPU builder, rebuilding in place into the scene's node buffers.
    InPlace(Builder, GpuBuilder),
    /// A CPU reference builder, run through `Builder::build`.
    Full(Builder),
}

impl FrameBuilder {
    pub fn new(ctx: &GpuContext, builder: Builder) -> Result<Self> {
        if builder.is_gpu() {
            let gpu = GpuBuilder::new(ctx, builder, &SahParams::default())?;
            Ok(FrameBuilder::InPlace(builder, gpu))
        } else {
            Ok(FrameBuilder::Full(builder))
        }
    }

    pub fn builder(&self) -> Builder {
        match self {
            FrameBuilder::InPlace(builder, _) | FrameBuilder::Full(builder) => *builder,
        }
    }

    /// Builds the tree of `scene` into `gpu_scene`, which holds `scene`'s geometry (it is
    /// replaced whole by builders without an in-place path).
    pub fn build(
        &mut self,
        ctx: &GpuContext,
        scene: &Scene,
        params: &SahParams,
        gpu_scene: &mut GpuScene,
    ) -> Result<BuildTiming> {
        match self {
            FrameBuilder::InPlace(_, builder) => {
                let start = Instant::now();
                builder.set_sah_params(*params);
                let stages = builder.build(ctx, gpu_scene)?;
                let wall_ms = start.elapsed().as_secs_f64() * 1e3;
                let gpu_ms: Option<f64> = stages.iter().map(|s| s.ms).sum();
                Ok(BuildTiming {
                    stages: aggregate_stages(stages),
                    total_ms: gpu_ms.unwrap_or(wall_ms),
                    timestamped: gpu_ms.is_some(),
                })
            }
            FrameBuilder::Full(builder) => {
                let (built, report) = builder.build(ctx, scene, params, 1)?;
                *gpu_scene = built;
                let timestamped = builder.is_gpu() && report.stages.iter().all(|s| s.ms.is_some());
                Ok(BuildTiming {
                    stages: aggregate_stages(report.stages),
                    total_ms: report.build_ms,
                    timestamped,
                })
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::gpu::{aggregate_stages, StageTime};

    fn stage(label: &str, ms: Option<f64>) -> StageTime {
        StageTime {
            label: label.into(),
            ms,
        }
    }

    #[test]
    fn stages_with_one_label_add_up_in_first_seen_order() {
        let stages = vec![
            stage("bounds", Some(1.0)),
            stage("sort", Some(2.0)),
            stage("refit", None),
            stage("sort", Some(3.0)),
            stage("refit", Some(1.0)),
        ];
        assert_eq!(
            aggregate_stages(stages),
            vec![
                stage("bounds", Some(1.0)),
                stage("sort", Some(5.0)),
                stage("refit", None)
            ]
        );
    }
}
