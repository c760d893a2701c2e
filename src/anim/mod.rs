//! Animated scenes, rebuilt every frame: a scene source that produces its triangles for any time t
//! with FIXED topology (the same count, order and materials every frame), and updates the
//! triangles of a `device::Geometry` in place. The per-frame pipeline is animate → build the BVH
//! on the GPU (any GPU builder, or a refit: `bvh::TreeUpdater`) → trace, recorded into one
//! recording.
//!
//! Sources:
//! * built-in procedural animations, computed by one GPU kernel each per frame
//!   (`shaders/<data>_animate.wgsl`), each with a CPU twin (`Animation::evaluate`) that tests compare
//!   the GPU output with: a waving flag (`cloth`), rigid bodies moving through a static room
//!   (`bodies`) and an exploding mesh whose triangles fly apart (`debris`, the case that defeats
//!   refitting);
//! * BART scenes (`bart`): the keyframe hierarchies are evaluated on the CPU
//!   (`BartScene::evaluate`) and uploaded every frame with `queue.write_buffer` — the animate
//!   stage is a CPU evaluation + upload, while the BVH build stays on the GPU;
//! * OBJ sequences (`obj_sequence`): a folder of frame OBJs with identical topology, interpolated
//!   linearly between frames on the CPU and uploaded.
//!
//! `registry` names them all; `kernel` runs the animation kernels, `scene::meshes` makes the
//! procedural geometry, `time_range` is the time axis.

mod bart;
mod bodies_animate;
mod cloth_animate;
mod debris_animate;
mod kernel;
mod obj_sequence;
mod registry;
mod time_range;

pub use bart::BartAnimation;
pub use bodies_animate::{RigidBodies, BODIES_ANIMATE};
pub use cloth_animate::{Flag, CLOTH_ANIMATE};
pub use debris_animate::{Explosion, DEBRIS_ANIMATE};
pub use obj_sequence::ObjSequence;
pub use registry::{
    animation_names, is_animation, load_animation, load_still, AnimationEntry, AnimationSource,
    ANIMATIONS, DEFAULT_ANIMATION,
};
pub use time_range::TimeRange;

use glam::Vec3;

use crate::device::Geometry;
use crate::gpu::{Recorder, StageTime};
use crate::scene::{Camera, Material, PointLight, Scene, Triangle};
use crate::{Error, Result};

/// Where an animation's per-frame triangles are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AnimateStage {
    /// A compute kernel writes the triangle buffer on the GPU.
    GpuKernel,
    /// The triangles are computed on the CPU and uploaded with `queue.write_buffer`.
    CpuUpload,
}

impl AnimateStage {
    pub fn describe(self) -> &'static str {
        match self {
            AnimateStage::GpuKernel => "GPU kernel",
            AnimateStage::CpuUpload => "CPU evaluation + upload",
        }
    }
}

/// A scene whose triangles move with time, with fixed topology.
///
/// Contract: `evaluate(t)` always writes `triangle_count()` triangles in the same order with the
/// same materials; `animate(ctx, t, scene)` leaves in `scene.triangles` what `evaluate(t)` writes
/// (within float rounding of the GPU's transcendental functions), provided `scene` was uploaded
/// from `scene_at(t0)` for some t0 (static parts are uploaded once and never rewritten).
pub trait Animation {
    fn name(&self) -> &str;

    fn time_range(&self) -> TimeRange;

    /// Triangles in every frame.
    fn triangle_count(&self) -> usize;

    /// The materials the triangles' `material` fields index (the same at every time).
    fn materials(&self) -> &[Material];

    /// The camera at time `t` (fixed for the procedural animations; BART scenes animate it).
    fn camera(&self, t: f32) -> Camera;

    /// Radiance of the sky (see `Scene::sky`).
    fn sky(&self) -> Vec3;

    /// Point lights (see `Scene::lights`); fixed over time.
    fn lights(&self) -> &[PointLight] {
        &[]
    }

    /// Where `animate` computes the triangles.
    fn stage(&self) -> AnimateStage;

    /// Writes the triangles at time `t` into `out` (cleared first), on the CPU: the CPU twin of
    /// the GPU kernel for procedural animations, the per-frame path for the others.
    fn evaluate(&self, t: f32, out: &mut Vec<Triangle>);

    /// Updates `geometry`'s triangles to time `t`: GPU kernels record a pass "animate" into
    /// `rec` (timestamped when it has a timer) and return None; CPU evaluations write the
    /// triangles (landing before the recording's submission) and return their wall-clock time.
    fn animate(
        &mut self,
        rec: &mut Recorder<'_>,
        t: f32,
        geometry: &Geometry,
    ) -> Result<Option<StageTime>>;

    /// The whole scene at time `t`, on the CPU (first upload, CPU reference builders, tests).
    fn scene_at(&self, t: f32) -> Scene {
        let mut triangles = Vec::with_capacity(self.triangle_count());
        self.evaluate(t, &mut triangles);
        Scene {
            name: self.name().to_owned(),
            triangles,
            materials: self.materials().to_vec(),
            camera: self.camera(t),
            sky: self.sky(),
            lights: self.lights().to_vec(),
        }
    }
}

/// Checks that `geometry` holds as many triangles as `animation` produces (fixed topology).
fn check_triangle_count(animation: &dyn Animation, geometry: &Geometry) -> Result<()> {
    let expected = animation.triangle_count();
    if geometry.triangle_count as usize != expected {
        return Err(Error::InvalidArgument(format!(
            "animation '{}' has {expected} triangles, but the geometry holds {}",
            animation.name(),
            geometry.triangle_count
        )));
    }
    Ok(())
}
