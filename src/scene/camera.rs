//! A pinhole camera (eye, target, up, vertical field of view) and the framing of a scene's bounds.

use crate::geometry::Aabb;
use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub eye: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    pub fov_y_degrees: f32,
}

impl Camera {
    /// A camera that looks at the whole box from the front (+z), slightly above its centre.
    pub fn framing(bounds: &Aabb) -> Self {
        let center = bounds.centroid();
        let radius = (0.5 * bounds.extent().length()).max(1e-6);
        let fov_y_degrees = 45.0f32;
        let distance = radius / (0.5 * fov_y_degrees.to_radians()).sin();
        let dir = Vec3::new(0.3, 0.35, 1.0).normalize();
        Self {
            eye: center + dir * distance,
            target: center,
            up: Vec3::Y,
            fov_y_degrees,
        }
    }
}
