//! Camera control in the image area: orbit around the target with the left mouse button, zoom with
//! the wheel, fly with W/A/S/D (forward, left, back, right) and Q/E (down, up) relative to the
//! view. The input is read from egui (so typing in a text field does not move the camera) and
//! applied to a `Camera` with the pure functions below.

use std::f32::consts::PI;

use glam::{Quat, Vec3};

use crate::scene::Camera;

/// Radians of orbit per point of mouse drag.
const ORBIT_PER_POINT: f32 = 0.008;
/// Zoom factor per point of wheel scroll (distance *= exp(-scroll * ZOOM_PER_POINT)).
const ZOOM_PER_POINT: f32 = 0.002;
/// Fly speed in scene radii per second.
const FLY_RADII_PER_SECOND: f32 = 0.5;
/// Closest the orbit gets to straight above or below the target (radians).
const MIN_POLAR: f32 = 0.01;

/// Camera input gathered over one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CameraInput {
    /// Mouse drag in points (x right, y down) while the left button is held over the image.
    pub drag: [f32; 2],
    /// Wheel scroll in points (positive = away from the user = zoom in).
    pub scroll: f32,
    /// Fly direction in view space: x right, y up, z forward; each -1, 0 or 1.
    pub fly: [f32; 3],
    /// Seconds since the last frame.
    pub dt: f32,
}

impl CameraInput {
    /// Reads the input of the image area (`response` covers it) for this frame.
    pub fn read(ui: &egui::Ui, response: &egui::Response) -> Self {
        let mut input = Self::default();
        if response.dragged_by(egui::PointerButton::Primary) {
            let d = response.drag_delta();
            input.drag = [d.x, d.y];
        }
        let keyboard_free = !ui.ctx().egui_wants_keyboard_input();
        ui.input(|i| {
            if response.hovered() {
                input.scroll = i.smooth_scroll_delta().y;
            }
            input.dt = i.stable_dt.min(0.25);
            if keyboard_free {
                let axis = |plus: egui::Key, minus: egui::Key| {
                    f32::from(u8::from(i.key_down(plus))) - f32::from(u8::from(i.key_down(minus)))
                };
                input.fly = [
                    axis(egui::Key::D, egui::Key::A),
                    axis(egui::Key::E, egui::Key::Q),
                    axis(egui::Key::W, egui::Key::S),
                ];
            }
        });
        input
    }

    /// Applies this input to `camera`; `scene_radius` sets the fly speed. Returns whether the
    /// camera moved.
    pub fn apply(&self, camera: &mut Camera, scene_radius: f32) -> bool {
        let before = *camera;
        if self.drag != [0.0, 0.0] {
            orbit(
                camera,
                -self.drag[0] * ORBIT_PER_POINT,
                self.drag[1] * ORBIT_PER_POINT,
            );
        }
        if self.scroll != 0.0 {
            zoom(camera, (-self.scroll * ZOOM_PER_POINT).exp());
        }
        if self.fly != [0.0; 3] {
            let step = FLY_RADII_PER_SECOND * scene_radius * self.dt;
            fly(camera, Vec3::from(self.fly) * step);
        }
        *camera != before
    }
}

/// Rotates the eye around the target: `yaw` around the camera's up axis, `pitch` towards the up
/// axis (positive = eye moves up). The distance to the target is kept; the eye never passes
/// over the poles.
pub fn orbit(camera: &mut Camera, yaw: f32, pitch: f32) {
    let up = camera.up.normalize_or(Vec3::Y);
    let offset = camera.eye - camera.target;
    let distance = offset.length();
    if !(distance > 0.0 && distance.is_finite()) {
        return;
    }
    let mut dir = offset / distance;
    let polar = dir.dot(up).clamp(-1.0, 1.0).acos();
    let new_polar = (polar - pitch).clamp(MIN_POLAR, PI - MIN_POLAR);
    let axis = up.cross(dir);
    let axis = if axis.length_squared() > 1e-12 {
        axis.normalize()
    } else {
        up.any_orthonormal_vector()
    };
    dir = Quat::from_axis_angle(axis, new_polar - polar) * dir;
    dir = Quat::from_axis_angle(up, yaw) * dir;
    camera.eye = camera.target + dir.normalize() * distance;
}

/// Scales the eye's distance to the target by `factor` (< 1 moves closer).
pub fn zoom(camera: &mut Camera, factor: f32) {
    let offset = (camera.eye - camera.target) * factor;
    if offset.length() > 1e-6 && offset.is_finite() {
        camera.eye = camera.target + offset;
    }
}

/// Moves eye and target together by `delta` given in view space (x right, y up, z forward).
pub fn fly(camera: &mut Camera, delta: Vec3) {
    let forward = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
    let right = forward.cross(camera.up).normalize_or(Vec3::X);
    let up = right.cross(forward);
    let world = right * delta.x + up * delta.y + forward * delta.z;
    camera.eye += world;
    camera.target += world;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera {
            eye: Vec3::new(0.0, 1.0, 5.0),
            target: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 45.0,
        }
    }

    #[test]
    fn orbit_keeps_target_and_distance() {
        let mut c = camera();
        orbit(&mut c, 0.7, 0.3);
        assert_eq!(c.target, camera().target);
        assert!(((c.eye - c.target).length() - 5.0).abs() < 1e-4);
        assert!(c.eye.y > 1.0, "positive pitch moves the eye up");
    }

    #[test]
    fn orbit_yaw_turns_around_up() {
        let mut c = camera();
        orbit(&mut c, PI / 2.0, 0.0);
        assert!(
            (c.eye - Vec3::new(5.0, 1.0, 0.0)).length() < 1e-4,
            "{}",
            c.eye
        );
    }

    #[test]
    fn orbit_stops_short_of_the_poles() {
        let mut c = camera();
        orbit(&mut c, 0.0, 10.0);
        let dir = (c.eye - c.target).normalize();
        assert!(dir.y < 1.0 && dir.y > 0.99);
        orbit(&mut c, 0.3, -0.2);
        assert!(c.eye.is_finite());
    }

    #[test]
    fn zoom_scales_distance() {
        let mut c = camera();
        zoom(&mut c, 0.5);
        assert!(((c.eye - c.target).length() - 2.5).abs() < 1e-5);
        zoom(&mut c, 0.0);
        assert!(
            (c.eye - c.target).length() > 0.0,
            "never collapses onto the target"
        );
    }

    #[test]
    fn fly_moves_relative_to_the_view() {
        let mut c = camera();
        fly(&mut c, Vec3::new(0.0, 0.0, 1.0));
        assert!((c.eye - Vec3::new(0.0, 1.0, 4.0)).length() < 1e-5);
        assert!((c.target - Vec3::new(0.0, 1.0, -1.0)).length() < 1e-5);
        fly(&mut c, Vec3::new(1.0, 1.0, 0.0));
        assert!((c.eye - Vec3::new(1.0, 2.0, 4.0)).length() < 1e-5);
    }

    #[test]
    fn input_without_motion_changes_nothing() {
        let mut c = camera();
        assert!(!CameraInput::default().apply(&mut c, 1.0));
        let drag = CameraInput {
            drag: [10.0, 0.0],
            ..Default::default()
        };
        assert!(drag.apply(&mut c, 1.0));
    }
}
