//! Scenes: triangles with material ids, materials (diffuse albedo + emission), point lights, a
//! camera and a sky.
//! Sources: OBJ files (`obj`), procedural built-ins (`procedural`; the stress scenes of the trace
//! issue's table, `stress`), looked up by name or path in `registry`. Every scene passes through
//! `sanitize` (the documented bad-geometry policy).

mod bart;
mod camera;
pub(crate) mod meshes;
mod obj;
mod procedural;
mod registry;
mod sanitize;
mod stress;

pub use bart::{BartScene, CONE_SIDES};
pub use camera::Camera;
pub use obj::load_obj;
pub use procedural::{cornell_box, tessellated_field};
pub use registry::{builtin_names, load_scene, shared_scenes_dir, SceneEntry, SCENES};
pub use sanitize::{sanitize, SanitizeReport};
pub use stress::{
    grass_blades, grass_blades_triangle_count, hairball, hairball_triangle_count,
    stacked_duplicates, stacked_duplicates_triangle_count, teapot_in_stadium,
    teapot_in_stadium_triangle_count,
};

use crate::geometry::Aabb;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// One triangle as the GPU reads it (48 bytes): three vertices and the material index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Triangle {
    pub v0: [f32; 3],
    pub material: u32,
    pub v1: [f32; 3],
    pub _pad1: u32,
    pub v2: [f32; 3],
    pub _pad2: u32,
}
const _: () = assert!(std::mem::size_of::<Triangle>() == 48);

impl Triangle {
    pub fn new(v0: Vec3, v1: Vec3, v2: Vec3, material: u32) -> Self {
        Self {
            v0: v0.to_array(),
            material,
            _pad1: 0,
            v1: v1.to_array(),
            v2: v2.to_array(),
            _pad2: 0,
        }
    }

    pub fn vertices(&self) -> [Vec3; 3] {
        [self.v0.into(), self.v1.into(), self.v2.into()]
    }

    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(&self.vertices())
    }

    pub fn area(&self) -> f32 {
        let [a, b, c] = self.vertices();
        0.5 * (b - a).cross(c - a).length()
    }
}

/// A diffuse material as the GPU reads it (32 bytes).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct Material {
    pub albedo: [f32; 3],
    pub _pad0: f32,
    pub emission: [f32; 3],
    pub _pad1: f32,
}
const _: () = assert!(std::mem::size_of::<Material>() == 32);

/// A point light as the GPU reads it (32 bytes). It lights diffuse surfaces with
/// `albedo · intensity · cos θ` and no distance falloff: the convention of the BART scenes'
/// Whitted-style lights (`l x y z r g b`), the only source of point lights.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable, PartialEq)]
pub struct PointLight {
    pub position: [f32; 3],
    pub _pad0: f32,
    pub intensity: [f32; 3],
    pub _pad1: f32,
}
const _: () = assert!(std::mem::size_of::<PointLight>() == 32);

impl PointLight {
    pub fn new(position: Vec3, intensity: Vec3) -> Self {
        Self {
            position: position.to_array(),
            _pad0: 0.0,
            intensity: intensity.to_array(),
            _pad1: 0.0,
        }
    }
}

impl Material {
    pub fn diffuse(albedo: Vec3) -> Self {
        Self::new(albedo, Vec3::ZERO)
    }

    pub fn new(albedo: Vec3, emission: Vec3) -> Self {
        Self {
            albedo: albedo.to_array(),
            _pad0: 0.0,
            emission: emission.to_array(),
            _pad1: 0.0,
        }
    }
}

/// A renderable scene. `triangles[i].material` indexes `materials`.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub triangles: Vec<Triangle>,
    pub materials: Vec<Material>,
    pub camera: Camera,
    /// Radiance of the sky seen by rays that leave the scene (zenith colour; the horizon is darker).
    pub sky: Vec3,
    /// Point lights (sampled with shadow rays at every path vertex); none for OBJ scenes.
    pub lights: Vec<PointLight>,
}

impl Scene {
    pub fn bounds(&self) -> Aabb {
        self.triangles
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()))
    }
}
