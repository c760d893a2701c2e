//! BART scenes as animations. The keyframe hierarchies (splined transforms of rigid parts,
//! morphing triangles) are evaluated on the CPU by `BartScene::evaluate` and uploaded every frame
//! with `queue.write_buffer`: the animate stage of these scenes is a CPU evaluation + upload,
//! while the BVH build stays on the GPU. The camera follows the file's `camera` animation.

use std::path::Path;
use std::time::Instant;

use glam::Vec3;

use super::{check_triangle_count, AnimateStage, Animation, TimeRange};
use crate::device::Geometry;
use crate::gpu::{Recorder, StageTime};
use crate::scene::{BartScene, Camera, Material, PointLight, Triangle};
use crate::{Error, Result};

/// A BART scene evaluated per frame on the CPU.
pub struct BartAnimation {
    name: String,
    scene: BartScene,
    /// The last evaluation (kept to reuse its allocation).
    scratch: Vec<Triangle>,
}

impl BartAnimation {
    /// Loads the AFF file at `path` (with its includes) as the animation `name`.
    pub fn load(name: &str, path: &Path) -> Result<Self> {
        let scene = BartScene::load(path)?;
        if scene.triangle_count() == 0 {
            return Err(Error::EmptyScene(name.to_owned()));
        }
        Ok(Self {
            name: name.to_owned(),
            scene,
            scratch: Vec::new(),
        })
    }
}

impl Animation for BartAnimation {
    fn name(&self) -> &str {
        &self.name
    }

    fn time_range(&self) -> TimeRange {
        let (start, end, frames) = self.scene.time_range();
        TimeRange::new(start, end, frames)
    }

    fn triangle_count(&self) -> usize {
        self.scene.triangle_count()
    }

    fn materials(&self) -> &[Material] {
        self.scene.materials()
    }

    fn camera(&self, t: f32) -> Camera {
        self.scene.camera(t)
    }

    fn sky(&self) -> Vec3 {
        self.scene.sky()
    }

    fn lights(&self) -> &[PointLight] {
        self.scene.lights()
    }

    fn stage(&self) -> AnimateStage {
        AnimateStage::CpuUpload
    }

    fn evaluate(&self, t: f32, out: &mut Vec<Triangle>) {
        self.scene.evaluate(t, out);
    }

    /// Evaluates on the CPU and uploads; the time is the wall-clock time of both (the copy to the
    /// GPU happens with the next submission, the build's).
    fn animate(
        &mut self,
        rec: &mut Recorder<'_>,
        t: f32,
        geometry: &Geometry,
    ) -> Result<Option<StageTime>> {
        check_triangle_count(self, geometry)?;
        let start = Instant::now();
        self.scene.evaluate(t, &mut self.scratch);
        geometry.write_triangles(rec.ctx, &self.scratch)?;
        Ok(Some(StageTime::cpu(
            "animate",
            start.elapsed().as_secs_f64() * 1e3,
        )))
    }
}
