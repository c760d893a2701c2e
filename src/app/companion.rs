//! The second tree the viewer keeps next to the traced one for the rebuild-versus-refit SAH plot:
//! when the traced tree is rebuilt every frame by builder B, the companion is B's first-frame
//! tree refitted every frame, and when the traced tree is that refit, the companion is B's
//! rebuild. Both trees read the same triangle buffer (the companion's `GpuScene` shares it), so
//! each animated frame is animated once and updated twice; the companion is never traced.

use super::frame_builder::BuildTiming;
use crate::anim::{TreeUpdater, UpdateMode};
use crate::bvh::{sah_cost, SahParams};
use crate::gpu::{storage_buffer_zeroed, GpuContext};
use crate::trace::GpuScene;
use crate::Result;

pub struct Companion {
    mode: UpdateMode,
    updater: TreeUpdater,
    scene: GpuScene,
}

impl Companion {
    /// The companion's mode for a traced tree updated by `traced`: the other of rebuild and refit,
    /// with the same builder. None for CPU reference builders (not offered for animated scenes).
    pub fn mode_for(traced: UpdateMode) -> Option<UpdateMode> {
        match traced {
            UpdateMode::Rebuild(b) if b.is_gpu() => Some(UpdateMode::Refit(b)),
            UpdateMode::Rebuild(_) => None,
            UpdateMode::Refit(b) => Some(UpdateMode::Rebuild(b)),
        }
    }

    /// A companion updated by `mode`, over the triangles of `traced`.
    pub fn new(
        ctx: &GpuContext,
        mode: UpdateMode,
        traced: &GpuScene,
        params: &SahParams,
    ) -> Result<Self> {
        let scene = GpuScene {
            triangles: traced.triangles.clone(),
            materials: traced.materials.clone(),
            lights: traced.lights.clone(),
            light_count: traced.light_count,
            nodes: storage_buffer_zeroed(ctx, "companion nodes", 32)?,
            prim_indices: storage_buffer_zeroed(ctx, "companion prim indices", 4)?,
            triangle_count: traced.triangle_count,
            node_count: 0,
            prim_count: 0,
        };
        Ok(Self {
            mode,
            updater: TreeUpdater::new(ctx, mode, params)?,
            scene,
        })
    }

    pub fn mode(&self) -> UpdateMode {
        self.mode
    }

    /// Whether the companion reads `traced`'s triangles.
    pub fn shares(&self, traced: &GpuScene) -> bool {
        self.scene.triangles == traced.triangles
    }

    /// Rebuilds or refits the companion tree to the current triangles.
    pub fn update(&mut self, ctx: &GpuContext, params: &SahParams) -> Result<BuildTiming> {
        let start = std::time::Instant::now();
        self.updater.set_sah_params(*params);
        let stages = self.updater.update(ctx, &mut self.scene)?;
        Ok(BuildTiming::from_stages(
            stages,
            start.elapsed().as_secs_f64() * 1e3,
        ))
    }

    /// Refits: build a new tree to refit at the next update.
    pub fn reset_topology(&mut self) {
        self.updater.reset();
    }

    /// The companion tree's SAH cost (downloads the tree).
    pub fn sah(&self, ctx: &GpuContext, params: &SahParams) -> Result<f32> {
        Ok(sah_cost(&self.scene.download_bvh(ctx)?, params))
    }
}
