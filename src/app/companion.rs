//! The second tree the viewer keeps next to the traced one for the rebuild-versus-refit SAH plot:
//! when the traced tree is rebuilt every frame by builder B, the companion is B's first-frame
//! tree refitted every frame, and when the traced tree is that refit, the companion is B's
//! rebuild. Both trees are built over the same geometry, in the same frame's recording; the
//! companion is never traced.

use crate::bvh::{BuildSchedule, SahParams, TreeUpdater, UpdateMode};
use crate::device::{Geometry, Tree};
use crate::gpu::{GpuContext, Recorder};
use crate::scene::Triangle;
use crate::Result;

pub struct Companion {
    updater: TreeUpdater,
    pub tree: Tree,
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

    /// A companion updated by `mode`.
    pub fn new(ctx: &GpuContext, mode: UpdateMode, params: &SahParams) -> Result<Self> {
        Ok(Self {
            updater: TreeUpdater::new(ctx, mode, params)?,
            tree: Tree::empty(ctx)?,
        })
    }

    pub fn mode(&self) -> UpdateMode {
        self.updater.mode()
    }

    /// How the companion's rebuilds spread over the device (see `TreeUpdater::set_build_schedule`).
    pub fn set_build_schedule(&mut self, schedule: BuildSchedule) -> Result<()> {
        self.updater.set_build_schedule(schedule)
    }

    /// The updater and tree of a companion that rebuilds with a GPU builder (beside a traced
    /// refit), for a schedule tuning; None for a refit companion.
    pub fn tunable(&mut self) -> Option<(&mut TreeUpdater, &mut Tree)> {
        self.updater
            .is_tunable()
            .then_some((&mut self.updater, &mut self.tree))
    }

    /// The build schedule of a companion's GPU rebuilds (None for a refit companion).
    pub fn build_schedule(&self) -> Option<BuildSchedule> {
        self.updater
            .is_tunable()
            .then(|| self.updater.build_schedule())
    }

    /// Records the rebuild or refit of the companion tree to the current triangles.
    pub fn record(
        &mut self,
        rec: &mut Recorder<'_>,
        geometry: &Geometry,
        triangles: &[Triangle],
        params: &SahParams,
    ) -> Result<()> {
        self.updater.set_sah_params(*params);
        self.updater
            .record(rec, geometry, triangles, &mut self.tree)
            .map(drop)
    }

    /// Refits: build a new tree to refit at the next update.
    pub fn reset_topology(&mut self) {
        self.updater.reset();
    }
}
