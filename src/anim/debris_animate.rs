//! The built-in "explosion" animation: a lumpy sphere of 81,920 triangles (an icosphere
//! subdivided 6 times, displaced) stands on a floor among a few crates, then bursts: every
//! triangle flies off on its own ballistic path, tumbling, and comes to rest on the floor. The
//! triangles' neighbourhoods change completely, which is the case that defeats refitting a tree
//! built for the intact mesh. the kernel `debris_animate` computes it each frame,
//! `debris_triangle` is its CPU twin.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::kernel::AnimationKernel;
use super::{check_triangle_count, AnimateStage, Animation, TimeRange};
use crate::device::Geometry;
use crate::gpu::{kernel, storage_buffer, Grid, Recorder, StageTime};
use crate::scene::meshes::{box_between, grid, icosphere};
use crate::scene::{Camera, Material, Triangle};
use crate::Result;

/// Where the intact mesh is centred, and its radius.
const CENTER: Vec3 = Vec3::new(0.0, 1.4, 0.0);
const RADIUS: f32 = 1.0;
/// Time of the burst.
const START: f32 = 1.0;
/// Height above the floor at which a fragment's centroid comes to rest (as in the kernel).
const REST_HEIGHT: f32 = 0.02;

/// The kernel's parameters (`DebrisParams` in `shaders/debris_animate.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct DebrisParams {
    count: u32,
    row_pitch: u32,
    _pad_a: [u32; 2],
    time: f32,
    start: f32,
    speed: f32,
    gravity: f32,
    center: [f32; 3],
    floor_y: f32,
    spin: f32,
    lift: f32,
    _pad: [u32; 2],
}

kernel!(pub DEBRIS_ANIMATE: DebrisParams = "debris_animate"::"main", [64, 1, 1],
    [ReadWrite, Read]);

fn hash(x: u32) -> u32 {
    let mut h = x.wrapping_mul(0x9E37_79B9);
    h ^= h >> 16;
    h = h.wrapping_mul(0x7FEB_352D);
    h ^= h >> 15;
    h = h.wrapping_mul(0x846C_A68B);
    h ^= h >> 16;
    h
}

fn unit(h: u32) -> f32 {
    (h >> 8) as f32 * (1.0 / 16_777_216.0)
}

fn rotate(v: Vec3, axis: Vec3, c: f32, s: f32) -> Vec3 {
    v * c + axis.cross(v) * s + axis * (axis.dot(v) * (1.0 - c))
}

/// CPU twin of `debris_animate.wgsl`: fragment `k` (intact: `rest`) at `params.time`.
fn debris_triangle(params: &DebrisParams, k: u32, rest: &Triangle) -> Triangle {
    let [a, b, c] = rest.vertices();
    let g = (a + b + c) / 3.0;
    let h1 = hash(k);
    let h2 = hash(h1 ^ 0x68E3_1DA4);
    let h3 = hash(h2 ^ 0xB529_7A4D);
    let h4 = hash(h3 ^ 0x1B56_C4E9);
    let away = g - Vec3::from(params.center);
    let dir = away / away.length().max(1e-6);
    let velocity =
        dir * (params.speed * (0.5 + unit(h1))) + Vec3::new(0.0, params.lift * unit(h2), 0.0);
    let drop = (g.y - (params.floor_y + REST_HEIGHT)).max(0.0);
    let landing = (velocity.y + (velocity.y * velocity.y + 2.0 * params.gravity * drop).sqrt())
        / params.gravity;
    let s = (params.time - params.start).max(0.0).min(landing);
    let offset = velocity * s + Vec3::new(0.0, -0.5 * params.gravity * s * s, 0.0);
    let axis = Vec3::new(unit(h2) - 0.5, 0.6, unit(h4) - 0.5).normalize();
    let angle = params.spin * (0.5 + unit(h3)) * s;
    let (cos, sin) = (angle.cos(), angle.sin());
    let center = g + offset;
    let place = |v: Vec3| center + rotate(v - g, axis, cos, sin);
    Triangle::new(place(a), place(b), place(c), rest.material)
}

/// A mesh that bursts into flying triangles.
pub struct Explosion {
    rest: Vec<Triangle>,
    static_triangles: Vec<Triangle>,
    materials: Vec<Material>,
    kernel: Option<AnimationKernel<DebrisParams>>,
}

impl Explosion {
    /// The default: an icosphere subdivided 6 times (81,920 triangles).
    pub fn standard() -> Self {
        Self::new(6)
    }

    /// A lumpy sphere of 20·4^`level` triangles that bursts.
    pub fn new(level: u32) -> Self {
        const FLOOR: u32 = 0;
        const CRATE: u32 = 1;
        const MESH: u32 = 2;
        let materials = vec![
            Material::diffuse(Vec3::new(0.5, 0.5, 0.48)),
            Material::diffuse(Vec3::new(0.6, 0.45, 0.3)),
            Material::diffuse(Vec3::new(0.85, 0.35, 0.1)),
            Material::diffuse(Vec3::new(0.9, 0.8, 0.3)),
            Material::diffuse(Vec3::new(0.3, 0.3, 0.35)),
        ];
        let lumpy = |p: Vec3| {
            let bump =
                1.0 + 0.12 * (5.0 * p.x + 1.0).sin() * (4.0 * p.y + 2.0).sin() * (6.0 * p.z).sin();
            CENTER + p * (RADIUS * bump)
        };
        let rest = icosphere(level)
            .into_iter()
            .map(|tri| {
                let band = ((tri[0].y + 1.0) * 2.5) as u32 % 3;
                let [a, b, c] = tri.map(lumpy);
                Triangle::new(a, b, c, MESH + band)
            })
            .collect();
        let mut static_triangles: Vec<Triangle> = grid(
            Vec3::new(-10.0, 0.0, -10.0),
            Vec3::Z * 20.0,
            Vec3::X * 20.0,
            8,
            8,
        )
        .into_iter()
        .map(|[a, b, c]| Triangle::new(a, b, c, FLOOR))
        .collect();
        for (x, z, size) in [
            (-3.0, -1.5, 0.7),
            (-3.6, -0.6, 0.5),
            (2.8, -2.2, 0.8),
            (3.4, 0.8, 0.45),
            (-1.2, -3.5, 0.6),
            (1.6, -3.8, 0.5),
        ] {
            static_triangles.extend(
                box_between(Vec3::new(x, 0.0, z), Vec3::new(x + size, size, z + size), 2)
                    .into_iter()
                    .map(|[a, b, c]| Triangle::new(a, b, c, CRATE)),
            );
        }
        Self {
            rest,
            static_triangles,
            materials,
            kernel: None,
        }
    }

    fn params(&self, time: f32) -> DebrisParams {
        DebrisParams {
            count: self.rest.len() as u32,
            row_pitch: 0,
            _pad_a: [0; 2],
            time,
            start: START,
            speed: 3.5,
            gravity: 9.81,
            center: CENTER.to_array(),
            floor_y: 0.0,
            spin: 6.0,
            lift: 3.0,
            _pad: [0; 2],
        }
    }
}

impl Animation for Explosion {
    fn name(&self) -> &str {
        "explosion"
    }

    fn time_range(&self) -> TimeRange {
        TimeRange::new(0.0, 4.0, 121)
    }

    fn triangle_count(&self) -> usize {
        self.rest.len() + self.static_triangles.len()
    }

    fn materials(&self) -> &[Material] {
        &self.materials
    }

    fn camera(&self, _t: f32) -> Camera {
        Camera {
            eye: Vec3::new(1.5, 4.0, 9.0),
            target: Vec3::new(0.0, 0.9, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 45.0,
        }
    }

    fn sky(&self) -> Vec3 {
        Vec3::ONE
    }

    fn stage(&self) -> AnimateStage {
        AnimateStage::GpuKernel
    }

    fn evaluate(&self, t: f32, out: &mut Vec<Triangle>) {
        let params = self.params(t);
        out.clear();
        out.extend(
            self.rest
                .iter()
                .enumerate()
                .map(|(k, r)| debris_triangle(&params, k as u32, r)),
        );
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
            let inputs = vec![storage_buffer(
                rec.ctx,
                "debris rest triangles",
                &self.rest,
            )?];
            self.kernel = Some(AnimationKernel::new(rec.ctx, &DEBRIS_ANIMATE, inputs));
        }
        let kernel = self.kernel.as_ref().expect("created above");
        let row_pitch = |grid: Grid| DebrisParams {
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
    fn intact_before_the_burst_scattered_and_landed_after() {
        let explosion = Explosion::new(2);
        let n = explosion.rest.len();
        let mut before = Vec::new();
        explosion.evaluate(0.5, &mut before);
        for (moved, rest) in before[..n].iter().zip(&explosion.rest) {
            for (p, q) in moved.vertices().iter().zip(rest.vertices()) {
                assert!(p.distance(q) < 1e-5, "moved before the burst: {p} vs {q}");
            }
        }
        let mut after = Vec::new();
        explosion.evaluate(4.0, &mut after);
        assert_eq!(after.len(), before.len());
        for (t, rest) in after[..n].iter().zip(&explosion.rest) {
            let [a, b, c] = t.vertices();
            let g = (a + b + c) / 3.0;
            assert!(
                (g.y - REST_HEIGHT).abs() < 1e-3,
                "fragment not on the floor: {g}"
            );
            // Rigid motion: every fragment keeps its shape.
            assert!((t.area() - rest.area()).abs() <= 1e-3 * rest.area());
        }
        let spread = after[..n]
            .iter()
            .map(|t| Vec3::from(t.v0).distance(CENTER))
            .fold(0.0f32, f32::max);
        assert!(spread > 2.0 * RADIUS, "fragments stayed close: {spread}");
    }
}
