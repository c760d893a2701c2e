//! (Re)building the viewed scene's BVH. GPU builders rebuild in place (`TreeUpdater`: pipelines
//! and scratch reused, geometry already on the GPU): the per-frame path; the refit modes build the
//! first frame's tree and then only refit its boxes. CPU reference builders go through
//! `Builder::build` (build + upload) once per change.

use std::time::Instant;

use crate::anim::{TreeUpdater, UpdateMode};
use crate::bvh::{Builder, SahParams};
use crate::gpu::{aggregate_stages, GpuContext, StageTime, Timing};
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

impl BuildTiming {
    /// The timing of GPU `stages` that took `wall_ms` on the wall clock.
    pub fn from_stages(stages: Vec<StageTime>, wall_ms: f64) -> Self {
        let gpu_ms: Option<f64> = stages.iter().map(|s| s.ms).sum();
        Self {
            stages: aggregate_stages(stages),
            total_ms: gpu_ms.unwrap_or(wall_ms),
            timestamped: gpu_ms.is_some(),
        }
    }
}

pub enum FrameBuilder {
    /// A GPU rebuild or refit, in place in the scene's node buffers.
    InPlace(UpdateMode, TreeUpdater),
    /// A CPU reference builder, run through `Builder::build`.
    Full(Builder),
}

impl FrameBuilder {
    pub fn new(ctx: &GpuContext, mode: UpdateMode) -> Result<Self> {
        if mode.is_gpu() {
            let updater = TreeUpdater::new(ctx, mode, &SahParams::default())?;
            Ok(FrameBuilder::InPlace(mode, updater))
        } else {
            Ok(FrameBuilder::Full(mode.builder()))
        }
    }

    pub fn builder(&self) -> UpdateMode {
        match self {
            FrameBuilder::InPlace(mode, _) => *mode,
            FrameBuilder::Full(builder) => UpdateMode::Rebuild(*builder),
        }
    }

    /// Refit modes: build a new tree at the next build (after a setting changed).
    pub fn reset_topology(&mut self) {
        if let FrameBuilder::InPlace(_, updater) = self {
            updater.reset();
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
            FrameBuilder::InPlace(_, updater) => {
                let start = Instant::now();
                updater.set_sah_params(*params);
                let stages = updater.update(ctx, gpu_scene)?;
                Ok(BuildTiming::from_stages(
                    stages,
                    start.elapsed().as_secs_f64() * 1e3,
                ))
            }
            FrameBuilder::Full(builder) => {
                let (built, report) = builder.build(ctx, scene, params, &Timing::quick(1))?;
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
