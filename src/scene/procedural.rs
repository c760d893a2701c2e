//! Built-in scenes generated in code: a Cornell-box-like room (`cornell_box`) and a heightfield
//! terrain with objects on it whose triangle count scales with a parameter (`tessellated_field`).
//! Both are deterministic.

use super::meshes::icosphere;
use super::{Camera, Material, Scene, Triangle};
use glam::{Mat3, Vec3};

/// Builds triangles with one material.
struct Mesher<'a> {
    triangles: &'a mut Vec<Triangle>,
    material: u32,
}

impl Mesher<'_> {
    fn triangle(&mut self, a: Vec3, b: Vec3, c: Vec3) {
        self.triangles.push(Triangle::new(a, b, c, self.material));
    }

    /// Two triangles; the front side (counter-clockwise order a, b, c, d) faces `(b - a) × (d - a)`.
    fn quad(&mut self, a: Vec3, b: Vec3, c: Vec3, d: Vec3) {
        self.triangle(a, b, c);
        self.triangle(a, c, d);
    }

    /// A closed box of `size` (full extents) standing on `base` (centre of its bottom face),
    /// rotated by `yaw` radians about +y; 12 triangles facing outwards.
    fn box_on(&mut self, base: Vec3, size: Vec3, yaw: f32) {
        let rotation = Mat3::from_rotation_y(yaw);
        let h = 0.5 * size;
        let corner =
            |x: f32, y: f32, z: f32| base + rotation * Vec3::new(x * h.x, (y + 1.0) * h.y, z * h.z);
        let [p000, p100, p010, p110] = [
            corner(-1.0, -1.0, -1.0),
            corner(1.0, -1.0, -1.0),
            corner(-1.0, 1.0, -1.0),
            corner(1.0, 1.0, -1.0),
        ];
        let [p001, p101, p011, p111] = [
            corner(-1.0, -1.0, 1.0),
            corner(1.0, -1.0, 1.0),
            corner(-1.0, 1.0, 1.0),
            corner(1.0, 1.0, 1.0),
        ];
        self.quad(p001, p101, p111, p011); // +z
        self.quad(p100, p000, p010, p110); // -z
        self.quad(p101, p100, p110, p111); // +x
        self.quad(p000, p001, p011, p010); // -x
        self.quad(p011, p111, p110, p010); // +y
        self.quad(p000, p100, p101, p001); // -y
    }

    /// The unit-sphere triangles `sphere` scaled by `radius` around `center`.
    fn sphere(&mut self, sphere: &[[Vec3; 3]], center: Vec3, radius: f32) {
        for [a, b, c] in sphere {
            self.triangle(
                center + radius * *a,
                center + radius * *b,
                center + radius * *c,
            );
        }
    }
}

/// A Cornell-box-like room: 2 × 2 × 2 units (x, z in [-1, 1], y in [0, 2]), white floor, ceiling
/// and back wall, red left (-x) and green right (+x) wall, a tall and a short white box (both
/// rotated about y) and a warm quad light (emission (17, 12, 4), as in the classic data) just
/// below the ceiling. The front (+z) is open, the sky black and the camera looks in through the
/// opening with a 40° vertical field of view. 36 triangles; walls face inwards, boxes outwards and
/// the light downwards.
pub fn cornell_box() -> Scene {
    const WHITE: u32 = 0;
    const RED: u32 = 1;
    const GREEN: u32 = 2;
    const LIGHT: u32 = 3;
    let materials = vec![
        Material::diffuse(Vec3::new(0.725, 0.71, 0.68)),
        Material::diffuse(Vec3::new(0.63, 0.065, 0.05)),
        Material::diffuse(Vec3::new(0.14, 0.45, 0.091)),
        Material::new(Vec3::splat(0.78), Vec3::new(17.0, 12.0, 4.0)),
    ];

    let mut triangles = Vec::with_capacity(36);
    let p = Vec3::new;
    let mut m = Mesher {
        triangles: &mut triangles,
        material: WHITE,
    };
    // Floor (up), ceiling (down), back wall (towards +z).
    m.quad(
        p(-1., 0., -1.),
        p(-1., 0., 1.),
        p(1., 0., 1.),
        p(1., 0., -1.),
    );
    m.quad(
        p(-1., 2., -1.),
        p(1., 2., -1.),
        p(1., 2., 1.),
        p(-1., 2., 1.),
    );
    m.quad(
        p(-1., 0., -1.),
        p(1., 0., -1.),
        p(1., 2., -1.),
        p(-1., 2., -1.),
    );
    // Tall box at the back left, short box at the front right, both 0.6 wide.
    m.box_on(p(-0.33, 0.0, -0.29), p(0.6, 1.2, 0.6), 17f32.to_radians());
    m.box_on(p(0.34, 0.0, 0.3), p(0.6, 0.6, 0.6), -17f32.to_radians());
    // Left wall (towards +x), right wall (towards -x).
    m.material = RED;
    m.quad(
        p(-1., 0., -1.),
        p(-1., 2., -1.),
        p(-1., 2., 1.),
        p(-1., 0., 1.),
    );
    m.material = GREEN;
    m.quad(p(1., 0., -1.), p(1., 0., 1.), p(1., 2., 1.), p(1., 2., -1.));
    // The light, 0.47 × 0.38 and 0.01 below the ceiling, facing down.
    m.material = LIGHT;
    let (lx, lz, ly) = (0.235, 0.19, 1.99);
    m.quad(
        p(-lx, ly, -lz),
        p(lx, ly, -lz),
        p(lx, ly, lz),
        p(-lx, ly, lz),
    );

    Scene {
        name: "cornell".into(),
        triangles,
        materials,
        camera: Camera {
            eye: Vec3::new(0.0, 1.0, 3.9),
            target: Vec3::new(0.0, 1.0, 0.0),
            up: Vec3::Y,
            fov_y_degrees: 40.0,
        },
        sky: Vec3::ZERO,
        lights: Vec::new(),
    }
}

/// Half the side of the square terrain of `tessellated_field`, in scene units.
const FIELD_HALF_SIZE: f32 = 50.0;

/// Terrain cells per object along each side of `tessellated_field`.
const CELLS_PER_OBJECT: u32 = 16;

/// The terrain height: a smooth, deterministic sum of sines (amplitude about ±5 units).
fn terrain_height(x: f32, z: f32) -> f32 {
    2.5 * (0.071 * x + 0.3).sin() * (0.063 * z - 0.7).cos()
        + 1.5 * (0.13 * x + 0.11 * z + 1.1).sin()
        + 0.6 * (0.37 * z - 0.29 * x + 2.0).sin()
        + 0.25 * (0.83 * x + 0.5).sin() * (0.91 * z + 0.2).sin()
}

/// Number of objects along each side of `tessellated_field(cells_per_side)`.
fn objects_per_side(cells_per_side: u32) -> u32 {
    cells_per_side.div_ceil(CELLS_PER_OBJECT)
}

/// Triangles in `tessellated_field(cells_per_side)`: 2·cells² terrain triangles plus the objects
/// (checkerboard of 80-triangle spheres and 12-triangle boxes).
fn field_triangle_count(cells_per_side: u32) -> usize {
    let cells = cells_per_side.max(1) as usize;
    let objects = objects_per_side(cells_per_side.max(1)) as usize;
    let spheres = (objects * objects).div_ceil(2);
    2 * cells * cells + 80 * spheres + 12 * (objects * objects - spheres)
}

/// A generated outdoor scene whose size scales with `cells_per_side` (at least 1): a 100 × 100
/// unit heightfield terrain (a smooth sum of sines) of `2 · cells_per_side²` triangles, with a grid
/// of `ceil(cells_per_side / 16)²` objects (at most 4 units wide) standing on it, alternating icospheres (80 triangles)
/// and rotated boxes (12 triangles) in three colours. `tessellated_field(710)` has 1,101,384
/// triangles. The camera looks across the terrain from above; the sky is bright. Deterministic.
pub fn tessellated_field(cells_per_side: u32) -> Scene {
    let n = cells_per_side.max(1);
    const TERRAIN: u32 = 0;
    let materials = vec![
        Material::diffuse(Vec3::new(0.45, 0.55, 0.3)),
        Material::diffuse(Vec3::new(0.8, 0.3, 0.2)),
        Material::diffuse(Vec3::new(0.25, 0.4, 0.8)),
        Material::diffuse(Vec3::new(0.85, 0.8, 0.7)),
    ];
    let mut triangles = Vec::with_capacity(field_triangle_count(n));

    // Terrain: (n + 1)² height samples, two triangles per cell, facing up.
    let size = 2.0 * FIELD_HALF_SIZE;
    let coord = |i: u32| -FIELD_HALF_SIZE + size * i as f32 / n as f32;
    let row = n as usize + 1;
    let points: Vec<Vec3> = (0..=n)
        .flat_map(|j| {
            (0..=n).map(move |i| {
                let (x, z) = (coord(i), coord(j));
                Vec3::new(x, terrain_height(x, z), z)
            })
        })
        .collect();
    let mut m = Mesher {
        triangles: &mut triangles,
        material: TERRAIN,
    };
    for j in 0..n as usize {
        for i in 0..n as usize {
            let p00 = points[j * row + i];
            let p10 = points[j * row + i + 1];
            let p01 = points[(j + 1) * row + i];
            let p11 = points[(j + 1) * row + i + 1];
            m.triangle(p00, p01, p11);
            m.triangle(p00, p11, p10);
        }
    }

    // Objects: one per cell of a coarser grid, centred in it.
    let sphere = icosphere(1);
    let k = objects_per_side(n);
    let spacing = size / k as f32;
    let radius = 0.25 * spacing.min(8.0);
    for j in 0..k {
        for i in 0..k {
            let x = -FIELD_HALF_SIZE + spacing * (i as f32 + 0.5);
            let z = -FIELD_HALF_SIZE + spacing * (j as f32 + 0.5);
            let ground = terrain_height(x, z);
            m.material = 1 + (i * 7 + j * 3) % 3;
            if (i + j).is_multiple_of(2) {
                // Sunk a little so that it meets sloped ground.
                m.sphere(&sphere, Vec3::new(x, ground + 0.8 * radius, z), radius);
            } else {
                let height = radius * (1.5 + (i * 5 + j * 11) as f32 % 7.0 / 3.0);
                let yaw = (i * 13 + j * 29) as f32 * 0.37;
                let base = Vec3::new(x, ground - 0.3 * radius, z);
                m.box_on(base, Vec3::new(1.4 * radius, height, 1.4 * radius), yaw);
            }
        }
    }
    debug_assert_eq!(triangles.len(), field_triangle_count(n));

    Scene {
        name: format!("field-{n}"),
        triangles,
        materials,
        camera: Camera {
            eye: Vec3::new(0.0, 0.6 * FIELD_HALF_SIZE, 1.45 * FIELD_HALF_SIZE),
            target: Vec3::new(0.0, 0.0, -0.2 * FIELD_HALF_SIZE),
            up: Vec3::Y,
            fov_y_degrees: 50.0,
        },
        sky: Vec3::ONE,
        lights: Vec::new(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::sanitize;

    #[test]
    fn cornell_box_is_small_closed_and_lit() {
        let mut scene = cornell_box();
        assert_eq!(scene.triangles.len(), 36);
        let b = scene.bounds();
        assert!(b.min.abs_diff_eq(Vec3::new(-1.0, 0.0, -1.0), 1e-6));
        assert!(b.max.abs_diff_eq(Vec3::new(1.0, 2.0, 1.0), 1e-6));
        // The camera is outside the open front, looking in.
        assert!(scene.camera.eye.z > 1.0 && scene.camera.target.z < 1.0);
        let lights: Vec<_> = scene
            .triangles
            .iter()
            .filter(|t| scene.materials[t.material as usize].emission != [0.0; 3])
            .collect();
        assert_eq!(lights.len(), 2);
        for t in lights {
            let [a, b, c] = t.vertices();
            assert!((b - a).cross(c - a).y < 0.0, "the light faces down");
            assert!(a.y < 2.0 && a.y > 1.9);
        }
        assert_eq!(scene.sky, Vec3::ZERO);
        assert!(sanitize(&mut scene).is_clean());
    }

    #[test]
    fn cornell_walls_face_inwards() {
        let scene = cornell_box();
        let center = Vec3::new(0.0, 1.0, 0.0);
        // The first 6 triangles are floor, ceiling, back; the last 6 left, right and the light.
        for t in scene.triangles[..6].iter().chain(&scene.triangles[30..]) {
            let [a, b, c] = t.vertices();
            let n = (b - a).cross(c - a);
            assert!(n.dot(center - a) > 0.0, "{t:?} faces outwards");
        }
    }

    #[test]
    fn icosphere_is_closed_and_outward() {
        let s = icosphere(1);
        assert_eq!(s.len(), 80);
        for [a, b, c] in &s {
            assert!((b - a).cross(c - a).dot(*a + *b + *c) > 0.0);
            for v in [a, b, c] {
                assert!((v.length() - 1.0).abs() < 1e-5);
            }
        }
    }

    #[test]
    fn small_fields_have_the_expected_counts_and_bounds() {
        for n in [1, 2, 16, 17, 67] {
            let mut scene = tessellated_field(n);
            assert_eq!(scene.triangles.len(), field_triangle_count(n), "n = {n}");
            assert!(scene.triangles.len() >= 2 * (n * n) as usize);
            let b = scene.bounds();
            assert!(b.min.is_finite() && b.max.is_finite());
            assert!((b.min.x + FIELD_HALF_SIZE).abs() < 1e-3);
            assert!((b.max.z - FIELD_HALF_SIZE).abs() < 1e-3);
            assert!(b.max.y < 30.0 && b.min.y > -10.0, "{b:?}");
            assert!(sanitize(&mut scene).is_clean(), "n = {n}");
            assert!(scene
                .triangles
                .iter()
                .all(|t| (t.material as usize) < scene.materials.len()));
        }
        assert_eq!(
            tessellated_field(0).triangles.len(),
            field_triangle_count(1)
        );
    }

    #[test]
    fn field_is_deterministic() {
        assert_eq!(
            tessellated_field(40).triangles,
            tessellated_field(40).triangles
        );
    }

    #[test]
    fn million_triangle_field() {
        let scene = tessellated_field(710);
        assert_eq!(scene.triangles.len(), 1_101_384);
        assert!(scene.triangles.len() >= 1_000_000);
        let b = scene.bounds();
        assert!(b.min.is_finite() && b.max.is_finite());
    }
}
