//! The built-in "bodies" animation: three dozen rigid bodies (icospheres and boxes, 36,864
//! triangles) orbiting, bouncing and spinning through a static room with pillars (about 4,400
//! triangles). the kernel `bodies_animate` moves the bodies' rest-pose triangles every frame;
//! `body_triangle` is its CPU twin.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::kernel::AnimationKernel;
use super::{check_triangle_count, AnimateStage, Animation, TimeRange};
use crate::device::Geometry;
use crate::gpu::{kernel, storage_buffer, Grid, Recorder, StageTime};
use crate::scene::meshes::{box_between, cube, grid, icosphere};
use crate::scene::{Camera, Material, Triangle};
use crate::Result;

/// Number of moving bodies (even ones are icospheres, odd ones boxes).
const BODIES: u32 = 36;
/// Half the side of the square room.
const ROOM_HALF: f32 = 8.0;
const WALL_HEIGHT: f32 = 3.0;
/// Material of the first body colour (four follow each other).
const BODY_MATERIAL: u32 = 3;

/// The kernel's parameters (`BodiesParams` in `shaders/bodies_animate.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct BodiesParams {
    count: u32,
    row_pitch: u32,
    _pad_a: [u32; 2],
    time: f32,
    _pad: [u32; 3],
}

kernel!(pub BODIES_ANIMATE: BodiesParams = "bodies_animate"::"main", [64, 1, 1],
    [ReadWrite, Read, Read]);

/// Motion of one body (`BodyMotion` in the kernel).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct BodyMotion {
    center: [f32; 3],
    orbit_radius: f32,
    orbit_speed: f32,
    phase: f32,
    bounce_height: f32,
    bounce_rate: f32,
    axis: [f32; 3],
    spin_rate: f32,
}
const _: () = assert!(std::mem::size_of::<BodyMotion>() == 48);

/// A triangle in its body's frame (`RestTriangle` in the kernel).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct RestTriangle {
    v0: [f32; 3],
    body: u32,
    v1: [f32; 3],
    material: u32,
    v2: [f32; 3],
    _pad: u32,
}
const _: () = assert!(std::mem::size_of::<RestTriangle>() == 48);

/// Rodrigues' rotation of `v` about the unit `axis` by the angle with cosine `c` and sine `s`.
fn rotate(v: Vec3, axis: Vec3, c: f32, s: f32) -> Vec3 {
    v * c + axis.cross(v) * s + axis * (axis.dot(v) * (1.0 - c))
}

/// CPU twin of `bodies_animate.wgsl`: `rest` moved by its body's motion at time `t`.
fn body_triangle(rest: &RestTriangle, bodies: &[BodyMotion], t: f32) -> Triangle {
    let m = &bodies[rest.body as usize];
    let angle = m.phase + m.orbit_speed * t;
    let position = Vec3::new(
        m.center[0] + m.orbit_radius * angle.cos(),
        m.center[1] + m.bounce_height * (m.bounce_rate * t + m.phase).sin().abs(),
        m.center[2] + m.orbit_radius * angle.sin(),
    );
    let spin = m.spin_rate * t + m.phase;
    let (c, s) = (spin.cos(), spin.sin());
    let axis = Vec3::from(m.axis);
    let place = |v: [f32; 3]| position + rotate(Vec3::from(v), axis, c, s);
    Triangle::new(
        place(rest.v0),
        place(rest.v1),
        place(rest.v2),
        rest.material,
    )
}

/// A deterministic pseudo-random number in [0, 1) for body `k` and `salt` (scene setup only).
fn unit(k: u32, salt: u32) -> f32 {
    let mut h = k.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7FEB_352D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846C_A68B);
    h ^= h >> 16;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Bodies moving through a room.
pub struct RigidBodies {
    bodies: Vec<BodyMotion>,
    rest: Vec<RestTriangle>,
    static_triangles: Vec<Triangle>,
    materials: Vec<Material>,
    kernel: Option<AnimationKernel<BodiesParams>>,
}

impl RigidBodies {
    /// The room with `BODIES` bodies.
    pub fn standard() -> Self {
        Self::new(BODIES, 3, 8)
    }

    /// `bodies` bodies: icospheres subdivided `sphere_level` times and boxes with faces cut into
    /// `box_cells` × `box_cells` cells.
    pub fn new(bodies: u32, sphere_level: u32, box_cells: u32) -> Self {
        const FLOOR: u32 = 0;
        const WALL: u32 = 1;
        const PILLAR: u32 = 2;
        let materials = vec![
            Material::diffuse(Vec3::new(0.55, 0.55, 0.52)),
            Material::diffuse(Vec3::new(0.8, 0.75, 0.65)),
            Material::diffuse(Vec3::new(0.4, 0.42, 0.45)),
            Material::diffuse(Vec3::new(0.8, 0.25, 0.15)),
            Material::diffuse(Vec3::new(0.2, 0.45, 0.8)),
            Material::diffuse(Vec3::new(0.9, 0.75, 0.2)),
            Material::diffuse(Vec3::new(0.25, 0.65, 0.3)),
        ];
        let sphere = icosphere(sphere_level);
        let boxy = cube(box_cells.max(1));
        let mut motions = Vec::with_capacity(bodies as usize);
        let mut rest = Vec::new();
        for k in 0..bodies {
            let size = 0.35 + 0.25 * unit(k, 1);
            let axis =
                Vec3::new(unit(k, 2) - 0.5, unit(k, 3) - 0.5 + 0.3, unit(k, 4) - 0.5).normalize();
            let sphere_body = k % 2 == 0;
            // Lowest point over all rotations: the sphere's radius, the box's half diagonal.
            let reach = if sphere_body {
                size
            } else {
                size * 3f32.sqrt()
            };
            let direction = if sphere_body { 1.0 } else { -1.0 };
            motions.push(BodyMotion {
                center: [unit(k, 5) - 0.5, reach * 1.02, unit(k, 6) - 0.5],
                orbit_radius: 1.5 + 4.5 * k as f32 / bodies as f32,
                orbit_speed: direction * (0.3 + 0.6 * unit(k, 7)),
                phase: std::f32::consts::TAU * unit(k, 8),
                bounce_height: 0.3 + 2.0 * unit(k, 9),
                bounce_rate: 1.5 + 2.5 * unit(k, 10),
                axis: axis.to_array(),
                spin_rate: 0.5 + 2.5 * unit(k, 11),
            });
            let shape = if sphere_body { &sphere } else { &boxy };
            let material = BODY_MATERIAL + k % 4;
            rest.extend(shape.iter().map(|[a, b, c]| RestTriangle {
                v0: (*a * size).to_array(),
                body: k,
                v1: (*b * size).to_array(),
                material,
                v2: (*c * size).to_array(),
                _pad: 0,
            }));
        }
        let h = ROOM_HALF;
        let mut room: Vec<(u32, [Vec3; 3])> = Vec::new();
        let mut add = |material: u32, triangles: Vec<[Vec3; 3]>| {
            room.extend(triangles.into_iter().map(|t| (material, t)));
        };
        add(
            FLOOR,
            grid(
                Vec3::new(-h, 0.0, -h),
                Vec3::Z * 2.0 * h,
                Vec3::X * 2.0 * h,
                40,
                40,
            ),
        );
        // Back (-z), left (-x) and right (+x) walls, facing in; the front is open for the camera.
        let up = Vec3::Y * WALL_HEIGHT;
        add(
            WALL,
            grid(Vec3::new(-h, 0.0, -h), Vec3::X * 2.0 * h, up, 16, 4),
        );
        add(
            WALL,
            grid(Vec3::new(-h, 0.0, h), Vec3::NEG_Z * 2.0 * h, up, 16, 4),
        );
        add(
            WALL,
            grid(Vec3::new(h, 0.0, -h), Vec3::Z * 2.0 * h, up, 16, 4),
        );
        for (x, z) in [(-7.0, -7.0), (7.0, -7.0), (-7.0, 7.0), (7.0, 7.0)] {
            add(
                PILLAR,
                box_between(
                    Vec3::new(x - 0.3, 0.0, z - 0.3),
                    Vec3::new(x + 0.3, WALL_HEIGHT, z + 0.3),
                    4,
                ),
            );
        }
        let static_triangles = room
            .into_iter()
            .map(|(material, [a, b, c])| Triangle::new(a, b, c, material))
            .collect();
        Self {
            bodies: motions,
            rest,
            static_triangles,
            materials,
            kernel: None,
        }
    }

    fn params(&self, time: f32) -> BodiesParams {
        BodiesParams {
            count: self.rest.len() as u32,
            row_pitch: 0,
            _pad_a: [0; 2],
            time,
            _pad: [0; 3],
        }
    }
}

impl Animation for RigidBodies {
    fn name(&self) -> &str {
        "bodies"
    }

    fn time_range(&self) -> TimeRange {
        TimeRange::new(0.0, 12.0, 361)
    }

    fn triangle_count(&self) -> usize {
        self.rest.len() + self.static_triangles.len()
    }

    fn materials(&self) -> &[Material] {
        &self.materials
    }

    fn camera(&self, _t: f32) -> Camera {
        Camera {
            eye: Vec3::new(0.0, 8.5, 16.0),
            target: Vec3::new(0.0, 0.8, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 50.0,
        }
    }

    fn sky(&self) -> Vec3 {
        Vec3::ONE
    }

    fn stage(&self) -> AnimateStage {
        AnimateStage::GpuKernel
    }

    fn evaluate(&self, t: f32, out: &mut Vec<Triangle>) {
        out.clear();
        out.extend(self.rest.iter().map(|r| body_triangle(r, &self.bodies, t)));
        out.extend_from_slice(&self.static_triangles);
    }

    fn animate(
        &mut self,
        rec: &mut Recorder<'_>,
        t: f32,
        geometry: &Geometry,
    ) -> Result<Option<StageTime>> {
        check_triangle_count(self, geometry)?;
        let params = self.params(t);
        if self.kernel.is_none() {
            let inputs = vec![
                storage_buffer(rec.ctx, "body motions", &self.bodies)?,
                storage_buffer(rec.ctx, "body rest triangles", &self.rest)?,
            ];
            self.kernel = Some(AnimationKernel::new(rec.ctx, &BODIES_ANIMATE, inputs));
        }
        let kernel = self.kernel.as_ref().expect("created above");
        let row_pitch = |grid: Grid| BodiesParams {
            row_pitch: grid.row_pitch,
            ..params
        };
        kernel.record(rec, params.count, row_pitch, &geometry.triangles);
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bodies_stay_in_the_room_above_the_floor() {
        let bodies = RigidBodies::standard();
        assert_eq!(bodies.rest.len(), 18 * 1280 + 18 * 768);
        let mut out = Vec::new();
        for frame in [0, 50, 200, 360] {
            bodies.evaluate(bodies.time_range().frame_time(frame), &mut out);
            assert_eq!(out.len(), bodies.triangle_count());
            for t in &out[..bodies.rest.len()] {
                for v in t.vertices() {
                    assert!(v.y > -1e-3, "below the floor: {v}");
                    assert!(v.x.abs() < ROOM_HALF && v.z.abs() < ROOM_HALF, "{v}");
                }
            }
        }
    }
}
