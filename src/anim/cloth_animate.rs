//! The built-in "flag" animation: a cloth flag waving on a pole above a ground plane. The flag is
//! a deforming grid (`cols` × `rows` cells, two triangles each; 32,000 triangles by default) whose
//! vertices follow travelling waves that grow away from the pole; the kernel
//! `cloth_animate` computes it every frame, `flag_triangle` is its CPU twin. The pole and the ground are static.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::kernel::AnimationKernel;
use super::{check_triangle_count, AnimateStage, Animation, TimeRange};
use crate::device::Geometry;
use crate::gpu::{kernel, Grid, Recorder, StageTime};
use crate::scene::meshes::{box_between, grid, icosphere};
use crate::scene::{Camera, Material, Triangle};
use crate::Result;

/// Size of the flag in scene units, and where its lower corner at the pole is.
const WIDTH: f32 = 3.0;
const HEIGHT: f32 = 2.0;
const ORIGIN: Vec3 = Vec3::new(0.06, 2.6, 0.0);
/// Largest sideways displacement at the free end.
const AMPLITUDE: f32 = 0.35;
/// Material of the flag's first stripe (three stripes follow each other).
const FLAG_MATERIAL: u32 = 2;

/// The kernel's parameters (`FlagParams` in `shaders/cloth_animate.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
pub struct FlagParams {
    count: u32,
    row_pitch: u32,
    _pad_a: [u32; 2],
    time: f32,
    width: f32,
    height: f32,
    amplitude: f32,
    origin: [f32; 3],
    cols: u32,
    rows: u32,
    material: u32,
    _pad: [u32; 2],
}

kernel!(pub CLOTH_ANIMATE: FlagParams = "cloth_animate"::"main", [64, 1, 1], [ReadWrite]);

impl FlagParams {
    fn vertex(&self, i: u32, j: u32) -> Vec3 {
        let t = self.time;
        let u = i as f32 / self.cols as f32;
        let v = j as f32 / self.rows as f32;
        let wave =
            (9.0 * u - 5.0 * t + 1.3 * v).sin() + 0.4 * (17.0 * u - 8.3 * t + 3.1 * v + 1.0).sin();
        let x = u * self.width * (1.0 - 0.06 * u * (1.0 + 0.5 * (3.0 * t + 2.0 * v).sin()));
        let y =
            v * self.height - 0.08 * self.height * u * u * (1.0 + 0.5 * (2.3 * t + 4.0 * u).sin());
        let z = self.amplitude * u * wave;
        Vec3::from(self.origin) + Vec3::new(x, y, z)
    }
}

/// CPU twin of `cloth_animate.wgsl`: flag triangle `k` for `params`.
fn flag_triangle(params: &FlagParams, k: u32) -> Triangle {
    let cell = k / 2;
    let (ci, cj) = (cell % params.cols, cell / params.cols);
    let material = params.material + (cj * 3 / params.rows).min(2);
    let p00 = params.vertex(ci, cj);
    let p11 = params.vertex(ci + 1, cj + 1);
    if k.is_multiple_of(2) {
        Triangle::new(p00, params.vertex(ci + 1, cj), p11, material)
    } else {
        Triangle::new(p00, p11, params.vertex(ci, cj + 1), material)
    }
}

/// A flag of `cols` × `rows` cells waving on a pole.
pub struct Flag {
    cols: u32,
    rows: u32,
    static_triangles: Vec<Triangle>,
    materials: Vec<Material>,
    kernel: Option<AnimationKernel<FlagParams>>,
}

impl Flag {
    /// The default flag: 160 × 100 cells, 32,000 animated triangles.
    pub fn standard() -> Self {
        Self::new(160, 100)
    }

    /// A flag of `cols` × `rows` cells (each at least 1).
    pub fn new(cols: u32, rows: u32) -> Self {
        const GROUND: u32 = 0;
        const POLE: u32 = 1;
        let materials = vec![
            Material::diffuse(Vec3::new(0.45, 0.5, 0.4)),
            Material::diffuse(Vec3::new(0.8, 0.8, 0.78)),
            Material::diffuse(Vec3::new(0.1, 0.2, 0.65)),
            Material::diffuse(Vec3::new(0.9, 0.9, 0.88)),
            Material::diffuse(Vec3::new(0.75, 0.08, 0.08)),
        ];
        let top = ORIGIN.y + HEIGHT + 0.25;
        let mut static_triangles: Vec<Triangle> =
            box_between(Vec3::new(-0.05, 0.0, -0.05), Vec3::new(0.05, top, 0.05), 1)
                .into_iter()
                .chain(
                    icosphere(1)
                        .into_iter()
                        .map(|tri| tri.map(|p| Vec3::new(0.0, top + 0.06, 0.0) + 0.09 * p)),
                )
                .map(|[a, b, c]| Triangle::new(a, b, c, POLE))
                .collect();
        static_triangles.extend(
            grid(
                Vec3::new(-20.0, 0.0, -20.0),
                Vec3::Z * 40.0,
                Vec3::X * 40.0,
                8,
                8,
            )
            .into_iter()
            .map(|[a, b, c]| Triangle::new(a, b, c, GROUND)),
        );
        Self {
            cols: cols.max(1),
            rows: rows.max(1),
            static_triangles,
            materials,
            kernel: None,
        }
    }

    fn animated_count(&self) -> u32 {
        2 * self.cols * self.rows
    }

    fn params(&self, time: f32) -> FlagParams {
        FlagParams {
            count: self.animated_count(),
            row_pitch: 0,
            _pad_a: [0; 2],
            time,
            width: WIDTH,
            height: HEIGHT,
            amplitude: AMPLITUDE,
            origin: ORIGIN.to_array(),
            cols: self.cols,
            rows: self.rows,
            material: FLAG_MATERIAL,
            _pad: [0; 2],
        }
    }
}

impl Animation for Flag {
    fn name(&self) -> &str {
        "flag"
    }

    fn time_range(&self) -> TimeRange {
        TimeRange::new(0.0, 8.0, 241)
    }

    fn triangle_count(&self) -> usize {
        self.animated_count() as usize + self.static_triangles.len()
    }

    fn materials(&self) -> &[Material] {
        &self.materials
    }

    fn camera(&self, _t: f32) -> Camera {
        Camera {
            eye: Vec3::new(2.6, 2.4, 6.8),
            target: Vec3::new(1.3, 3.2, 0.0),
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
        out.extend((0..self.animated_count()).map(|k| flag_triangle(&params, k)));
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
        let kernel = self
            .kernel
            .get_or_insert_with(|| AnimationKernel::new(rec.ctx, &CLOTH_ANIMATE, Vec::new()));
        let row_pitch = |grid: Grid| FlagParams {
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
    fn the_flag_hangs_from_the_pole_and_keeps_its_topology() {
        let flag = Flag::new(8, 5);
        let mut a = Vec::new();
        let mut b = Vec::new();
        flag.evaluate(0.0, &mut a);
        flag.evaluate(1.7, &mut b);
        assert_eq!(a.len(), flag.triangle_count());
        assert_eq!(a.len(), b.len());
        assert!(a.iter().zip(&b).all(|(x, y)| x.material == y.material));
        // The edge at the pole (u = 0) does not move.
        assert_eq!(a[0].v0, b[0].v0);
        assert_eq!(a[0].v0, ORIGIN.to_array());
        assert_ne!(a[15], b[15]);
    }
}
