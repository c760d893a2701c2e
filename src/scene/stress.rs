//! Stress scenes of the kinds in the trace issue's OptiX table: overlapping duplicates
//! (`stacked_duplicates`), thin grass blades (`grass_blades`), a ball of thin strands
//! (`hairball`) and a small detailed teapot in a large stadium (`teapot_in_stadium`). They are
//! procedural reconstructions at the table's triangle counts, not the geometry OptiX was measured
//! on. Each stresses what a BVH finds hard: boxes that overlap however the primitives are split,
//! long thin triangles whose boxes are mostly empty, rays that cross many boxes before their hit,
//! and a scene whose detail fills a tiny part of its bounds (Morton codes and quantized wide boxes
//! at their resolution). Deterministic; each takes a size, so that tests can trace small versions.

use super::meshes::{icosphere, lathe, tube};
use super::{Camera, Material, Scene, Triangle};
use glam::{Quat, Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// SplitMix64: a small deterministic generator (the scenes must not change between runs).
struct Random(u64);

impl Random {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn range(&mut self, low: f32, high: f32) -> f32 {
        low + (high - low) * self.unit()
    }

    /// Uniform in the unit ball.
    fn in_ball(&mut self) -> Vec3 {
        loop {
            let p = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if p.length_squared() <= 1.0 {
                return p;
            }
        }
    }

    /// Uniform on the unit sphere.
    fn direction(&mut self) -> Vec3 {
        loop {
            let p = self.in_ball();
            if p.length_squared() > 1e-4 {
                return p.normalize();
            }
        }
    }
}

/// A scene lit by a white sky alone, of diffuse materials with these albedos, seen from `eye`
/// towards `target` (y up) with a vertical field of view in degrees.
fn sky_lit(
    name: String,
    triangles: Vec<Triangle>,
    albedos: &[Vec3],
    (eye, target, fov_y_degrees): (Vec3, Vec3, f32),
) -> Scene {
    Scene {
        name,
        triangles,
        materials: albedos.iter().map(|&a| Material::diffuse(a)).collect(),
        camera: Camera {
            eye,
            target,
            up: Vec3::Y,
            fov_y_degrees,
        },
        sky: Vec3::ONE,
        lights: Vec::new(),
    }
}

/// Triangles appended with one material.
fn push_all(out: &mut Vec<Triangle>, triangles: &[[Vec3; 3]], material: u32) {
    out.extend(
        triangles
            .iter()
            .map(|&[a, b, c]| Triangle::new(a, b, c, material)),
    );
}

/// A square floor of half-side `half` at height `y`, facing up (two triangles).
fn floor(out: &mut Vec<Triangle>, half: f32, y: f32, material: u32) {
    let corner = |x: f32, z: f32| Vec3::new(x * half, y, z * half);
    let [a, b, c, d] = [
        corner(-1.0, -1.0),
        corner(-1.0, 1.0),
        corner(1.0, 1.0),
        corner(1.0, -1.0),
    ];
    push_all(out, &[[a, b, c], [a, c, d]], material);
}

/// Triangles of one sphere copy of `stacked_duplicates`.
const STACKED_SPHERE_TRIANGLES: usize = 1280;

/// Triangles of `stacked_duplicates(copies)`: the copies and the floor.
pub fn stacked_duplicates_triangle_count(copies: u32) -> usize {
    copies as usize * STACKED_SPHERE_TRIANGLES + 2
}

/// `copies` copies of one sphere of 1,280 triangles stacked nearly on top of one another: each
/// turned about a random axis and moved by up to 5 % of its radius, so their surfaces cross
/// everywhere and every box of one copy overlaps those of all the others; on a floor. The builtin
/// `stacked` has 80 copies (102,402 triangles). Sky-lit.
pub fn stacked_duplicates(copies: u32) -> Scene {
    let mut random = Random(0x5eed_0001);
    let sphere = icosphere(3);
    debug_assert_eq!(sphere.len(), STACKED_SPHERE_TRIANGLES);
    let mut triangles = Vec::with_capacity(stacked_duplicates_triangle_count(copies));
    for copy in 0..copies {
        let turn = Quat::from_axis_angle(random.direction(), random.range(0.0, TAU));
        let offset = 0.05 * random.in_ball();
        let moved: Vec<[Vec3; 3]> = sphere
            .iter()
            .map(|tri| tri.map(|p| turn * p + offset))
            .collect();
        push_all(&mut triangles, &moved, copy % 3);
    }
    floor(&mut triangles, 6.0, -1.1, 3);
    sky_lit(
        format!("stacked-{copies}"),
        triangles,
        &[
            Vec3::new(0.8, 0.35, 0.25),
            Vec3::new(0.3, 0.55, 0.8),
            Vec3::new(0.85, 0.8, 0.5),
            Vec3::splat(0.6),
        ],
        (Vec3::new(0.6, 0.9, 3.4), Vec3::new(0.0, -0.1, 0.0), 45.0),
    )
}

/// Triangles per grass blade: two tapering quads and a tip.
const BLADE_TRIANGLES: usize = 5;

/// Half the side of the square patch of `grass_blades`, in metres.
const GRASS_HALF_SIZE: f32 = 4.0;

/// Triangles of `grass_blades(blades)`: the blades and the ground.
pub fn grass_blades_triangle_count(blades: u32) -> usize {
    blades as usize * BLADE_TRIANGLES + 2
}

/// `blades` blades of grass at random places on an 8 × 8 m patch of flat ground: each 15–45 cm
/// tall, 8–16 mm wide at its foot and tapering to a tip, turned at random and bent out of its
/// plane, five triangles. The builtin `grass` has 50,000 blades (250,002 triangles); seen from
/// low over the patch. Sky-lit.
pub fn grass_blades(blades: u32) -> Scene {
    let mut random = Random(0x5eed_0002);
    let mut triangles = Vec::with_capacity(grass_blades_triangle_count(blades));
    for blade in 0..blades {
        let foot = Vec3::new(
            random.range(-GRASS_HALF_SIZE, GRASS_HALF_SIZE),
            0.0,
            random.range(-GRASS_HALF_SIZE, GRASS_HALF_SIZE),
        );
        let height = random.range(0.15, 0.45);
        let width = random.range(0.008, 0.016);
        let yaw = random.range(0.0, TAU);
        let bend = random.range(0.1, 0.6) * height;
        let across = Vec3::new(yaw.cos(), 0.0, yaw.sin());
        let lean = Vec3::new(-yaw.sin(), 0.0, yaw.cos());
        let centre = |s: f32| foot + Vec3::Y * (height * s) + lean * (bend * s * s);
        let edges = |s: f32, taper: f32| {
            let half = 0.5 * width * taper * across;
            (centre(s) - half, centre(s) + half)
        };
        let (l0, r0) = edges(0.0, 1.0);
        let (l1, r1) = edges(1.0 / 3.0, 0.7);
        let (l2, r2) = edges(2.0 / 3.0, 0.4);
        let tip = centre(1.0);
        push_all(
            &mut triangles,
            &[
                [l0, r0, r1],
                [l0, r1, l1],
                [l1, r1, r2],
                [l1, r2, l2],
                [l2, r2, tip],
            ],
            blade % 3,
        );
    }
    floor(&mut triangles, GRASS_HALF_SIZE + 1.0, 0.0, 3);
    sky_lit(
        format!("grass-{blades}"),
        triangles,
        &[
            Vec3::new(0.25, 0.55, 0.15),
            Vec3::new(0.35, 0.6, 0.2),
            Vec3::new(0.45, 0.55, 0.2),
            Vec3::new(0.35, 0.27, 0.18),
        ],
        (
            Vec3::new(0.0, 0.8, GRASS_HALF_SIZE + 0.8),
            Vec3::new(0.0, 0.0, 0.5),
            50.0,
        ),
    )
}

/// Segments per strand of `hairball` (two triangles each).
const STRAND_SEGMENTS: usize = 50;

/// Triangles of `hairball(strands)`.
pub fn hairball_triangle_count(strands: u32) -> usize {
    strands as usize * STRAND_SEGMENTS * 2
}

/// `strands` strands tangled in a ball of radius 1: each a random walk of 50 steps of 0.04 that
/// turns a little at every step and back inwards at the ball's surface, drawn as a ribbon 0.006
/// wide (two triangles per step). Seen from outside, the ball fills the view; a ray crosses many
/// strands' boxes before it hits one. The builtin `hairball` has 3,000 strands (300,000
/// triangles). Sky-lit.
pub fn hairball(strands: u32) -> Scene {
    const STEP: f32 = 0.04;
    const HALF_WIDTH: f32 = 0.003;
    let mut random = Random(0x5eed_0003);
    let mut triangles = Vec::with_capacity(hairball_triangle_count(strands));
    for strand in 0..strands {
        let mut point = 0.9 * random.in_ball();
        let mut heading = random.direction();
        let mut points = vec![point];
        for _ in 0..STRAND_SEGMENTS {
            heading = (heading + 0.35 * random.in_ball()).normalize();
            let outward = point.normalize_or_zero();
            if (point + STEP * heading).length() > 1.0 && heading.dot(outward) > 0.0 {
                heading = (heading - 2.0 * heading.dot(outward) * outward).normalize();
            }
            point += STEP * heading;
            points.push(point);
        }
        // The ribbon's width lies across the strand and across one direction fixed per strand.
        let up = random.direction();
        let edges: Vec<(Vec3, Vec3)> = (0..points.len())
            .map(|i| {
                let tangent = points[(i + 1).min(STRAND_SEGMENTS)] - points[i.saturating_sub(1)];
                let mut side = tangent.cross(up);
                if side.length_squared() < 1e-6 * tangent.length_squared() {
                    side = tangent.any_orthonormal_vector();
                }
                let half = HALF_WIDTH * side.normalize();
                (points[i] - half, points[i] + half)
            })
            .collect();
        for pair in edges.windows(2) {
            let ((l0, r0), (l1, r1)) = (pair[0], pair[1]);
            push_all(&mut triangles, &[[l0, r0, r1], [l0, r1, l1]], strand % 2);
        }
    }
    sky_lit(
        format!("hairball-{strands}"),
        triangles,
        &[Vec3::new(0.7, 0.55, 0.35), Vec3::new(0.6, 0.45, 0.3)],
        (Vec3::new(0.0, 0.4, 3.2), Vec3::ZERO, 42.0),
    )
}

/// The teapot's profile, (distance from its axis, height) in teapot units (1.04 tall): from the
/// middle of its foot out and up the body to the rim, over the lid and its knob to the top.
const TEAPOT_PROFILE: [[f32; 2]; 17] = [
    [0.0, 0.0],
    [0.5, 0.0],
    [0.56, 0.03],
    [0.64, 0.15],
    [0.68, 0.32],
    [0.66, 0.48],
    [0.58, 0.64],
    [0.48, 0.74],
    [0.5, 0.76],
    [0.46, 0.78],
    [0.38, 0.84],
    [0.22, 0.89],
    [0.07, 0.91],
    [0.06, 0.95],
    [0.11, 0.98],
    [0.09, 1.02],
    [0.0, 1.04],
];

/// The teapot's height in the stadium, in metres (a teapot unit is this many metres).
const TEAPOT_SCALE: f32 = 0.3;

/// Tiers of the stadium's stands and steps around its ellipse.
const STAND_TIERS: u32 = 12;
const STAND_STEPS: u32 = 64;

/// How far each tier of the stands steps out, and the height of the top of tier `tier` (the
/// lowest tier's riser is a wall 1.5 m high in front of it), in metres.
const STAND_DEPTH: f32 = 1.6;
fn tier_height(tier: u32) -> f32 {
    if tier == 0 {
        0.0
    } else {
        0.6 + 0.9 * tier as f32
    }
}

/// Triangles of the stadium: the ground, each tier's riser and tread, the outer wall.
const STADIUM_TRIANGLES: usize =
    2 + 4 * (STAND_TIERS * STAND_STEPS) as usize + 2 * STAND_STEPS as usize;

/// Triangles of `teapot_in_stadium(detail)`: the teapot's body (two fans and the quads between
/// its profile's rings), spout and handle, and the stadium.
pub fn teapot_in_stadium_triangle_count(detail: u32) -> usize {
    let detail = detail.max(1) as usize;
    let (around, rings) = (24 * detail, 16 * detail + 1);
    let body = 2 * around + 2 * around * (rings - 3);
    let tubes = 2 * (2 * (4 * detail) * (3 * detail / 2));
    body + tubes + STADIUM_TRIANGLES
}

/// Points along a Catmull-Rom spline through `keys` (ends clamped), `per_key` per key interval,
/// the keys included.
fn catmull_rom(keys: &[Vec2], per_key: u32) -> Vec<Vec2> {
    let last = keys.len() - 1;
    let mut out = Vec::with_capacity(last * per_key as usize + 1);
    for i in 0..last {
        let (p0, p1, p2, p3) = (
            keys[i.saturating_sub(1)],
            keys[i],
            keys[i + 1],
            keys[(i + 2).min(last)],
        );
        for step in 0..per_key {
            let t = step as f32 / per_key as f32;
            let (t2, t3) = (t * t, t * t * t);
            out.push(
                0.5 * (2.0 * p1
                    + (p2 - p0) * t
                    + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * t2
                    + (3.0 * p1 - p0 - 3.0 * p2 + p3) * t3),
            );
        }
    }
    out.push(keys[last]);
    out
}

/// A teapot of about 200k triangles (at `detail` 16) in the middle of a stadium about 500 times
/// its size: the teapot, 0.3 m tall, is a surface of revolution (body, lid and knob) with a
/// spout and a handle, tubes along plane curves; the stadium is a 160 × 132 m ground with 12
/// tiers of stands around an elliptic field, 3,202 triangles. Nearly all of the detail lies in a
/// millionth of the scene's volume; seen from close to the teapot, the stands behind it. The
/// teapot's tessellation grows with `detail` (24·detail steps around the body); the builtin
/// `stadium` takes detail 16. Sky-lit.
pub fn teapot_in_stadium(detail: u32) -> Scene {
    let detail = detail.max(1);
    let (teapot, ground, stands, risers) = (0, 1, 2, 3);
    let mut triangles = Vec::with_capacity(teapot_in_stadium_triangle_count(detail));
    let place = |tris: Vec<[Vec3; 3]>| -> Vec<[Vec3; 3]> {
        tris.into_iter()
            .map(|tri| tri.map(|p| TEAPOT_SCALE * p))
            .collect()
    };

    let keys: Vec<Vec2> = TEAPOT_PROFILE.iter().map(|&k| Vec2::from(k)).collect();
    push_all(
        &mut triangles,
        &place(lathe(&catmull_rom(&keys, detail), 24 * detail)),
        teapot,
    );

    // Spout and handle: tubes along curves in the xy plane, their ends inside the body.
    let along = 3 * detail / 2;
    let around = 4 * detail;
    let bezier = |t: f32| {
        let (p0, p1, p2) = (
            Vec3::new(0.5, 0.25, 0.0),
            Vec3::new(1.0, 0.3, 0.0),
            Vec3::new(1.08, 0.74, 0.0),
        );
        (1.0 - t) * (1.0 - t) * p0 + 2.0 * t * (1.0 - t) * p1 + t * t * p2
    };
    let spout: Vec<Vec3> = (0..=along)
        .map(|i| bezier(i as f32 / along as f32))
        .collect();
    let spout_radii: Vec<f32> = (0..=along)
        .map(|i| 0.12 - 0.07 * i as f32 / along as f32)
        .collect();
    push_all(
        &mut triangles,
        &place(tube(&spout, &spout_radii, Vec3::Z, around)),
        teapot,
    );
    let handle: Vec<Vec3> = (0..=along)
        .map(|i| {
            let angle = PI * (0.5 - i as f32 / along as f32);
            Vec3::new(-0.56 - 0.38 * angle.cos(), 0.38 + 0.24 * angle.sin(), 0.0)
        })
        .collect();
    push_all(
        &mut triangles,
        &place(tube(&handle, &vec![0.045; handle.len()], Vec3::Z, around)),
        teapot,
    );

    // The stadium: the ground, then tiers of stands stepping up and out from an ellipse around
    // the field, each a riser and a tread, and the wall behind the top tier down to the ground.
    let ground_corner = |x: f32, z: f32| Vec3::new(80.0 * x, 0.0, 66.0 * z);
    let [a, b, c, d] = [
        ground_corner(-1.0, -1.0),
        ground_corner(-1.0, 1.0),
        ground_corner(1.0, 1.0),
        ground_corner(1.0, -1.0),
    ];
    push_all(&mut triangles, &[[a, b, c], [a, c, d]], ground);
    let ring = |tier: u32, step: u32, y: f32| {
        let angle = TAU * step as f32 / STAND_STEPS as f32;
        let grow = STAND_DEPTH * tier as f32;
        Vec3::new((58.0 + grow) * angle.cos(), y, (44.0 + grow) * angle.sin())
    };
    for tier in 0..STAND_TIERS {
        let (low, high) = (tier_height(tier), tier_height(tier + 1));
        for step in 0..STAND_STEPS {
            let next = step + 1;
            // Riser: facing the field (inwards).
            let (r0, r1) = (ring(tier, step, low), ring(tier, next, low));
            let (r2, r3) = (ring(tier, next, high), ring(tier, step, high));
            push_all(&mut triangles, &[[r0, r1, r2], [r0, r2, r3]], risers);
            // Tread: facing up.
            let (t0, t1) = (ring(tier + 1, step, high), ring(tier + 1, next, high));
            push_all(&mut triangles, &[[r3, r2, t1], [r3, t1, t0]], stands);
        }
    }
    for step in 0..STAND_STEPS {
        let next = step + 1;
        let top = tier_height(STAND_TIERS);
        let (w0, w1) = (ring(STAND_TIERS, step, top), ring(STAND_TIERS, next, top));
        let (w2, w3) = (ring(STAND_TIERS, next, 0.0), ring(STAND_TIERS, step, 0.0));
        push_all(&mut triangles, &[[w0, w1, w2], [w0, w2, w3]], stands);
    }
    sky_lit(
        format!("stadium-{detail}"),
        triangles,
        &[
            Vec3::new(0.85, 0.85, 0.8),
            Vec3::new(0.25, 0.5, 0.2),
            Vec3::splat(0.55),
            Vec3::new(0.5, 0.25, 0.2),
        ],
        (Vec3::new(0.12, 0.3, 0.85), Vec3::new(0.0, 0.13, 0.0), 45.0),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Aabb;
    use crate::scene::sanitize;

    /// Small versions of the four scenes, with the triangle counts their functions give.
    fn small_scenes() -> Vec<(Scene, usize)> {
        vec![
            (stacked_duplicates(5), stacked_duplicates_triangle_count(5)),
            (grass_blades(300), grass_blades_triangle_count(300)),
            (hairball(40), hairball_triangle_count(40)),
            (teapot_in_stadium(3), teapot_in_stadium_triangle_count(3)),
            (teapot_in_stadium(2), teapot_in_stadium_triangle_count(2)),
        ]
    }

    #[test]
    fn counts_are_exact_and_every_triangle_is_clean() {
        for (mut scene, count) in small_scenes() {
            assert_eq!(scene.triangles.len(), count, "{}", scene.name);
            assert!(sanitize(&mut scene).is_clean(), "{}", scene.name);
            assert!(scene
                .triangles
                .iter()
                .all(|t| (t.material as usize) < scene.materials.len()));
        }
    }

    #[test]
    fn scenes_are_deterministic() {
        for ((a, _), (b, _)) in small_scenes().into_iter().zip(small_scenes()) {
            assert!(a.triangles == b.triangles, "{}", a.name);
        }
    }

    #[test]
    fn the_stacked_copies_overlap_one_another() {
        let scene = stacked_duplicates(6);
        let boxes: Vec<Aabb> = scene.triangles[..6 * STACKED_SPHERE_TRIANGLES]
            .chunks(STACKED_SPHERE_TRIANGLES)
            .map(|copy| copy.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds())))
            .collect();
        for b in &boxes {
            // Every copy's box is the unit sphere's, moved by at most 0.05.
            assert!(b.extent().min_element() > 1.9, "{b:?}");
            assert!(
                b.min.max_element() < -0.9 && b.max.min_element() > 0.9,
                "{b:?}"
            );
        }
    }

    #[test]
    fn blades_stand_on_the_patch_and_strands_stay_in_the_ball() {
        let grass = grass_blades(500);
        for t in &grass.triangles[..500 * BLADE_TRIANGLES] {
            for p in t.vertices() {
                assert!(p.y >= 0.0 && p.y <= 0.46, "{p}");
                assert!(p.x.abs() < GRASS_HALF_SIZE + 0.3 && p.z.abs() < GRASS_HALF_SIZE + 0.3);
            }
        }
        let ball = hairball(60);
        for t in &ball.triangles {
            assert!(t.vertices().iter().all(|p| p.length() < 1.05));
        }
    }

    #[test]
    fn the_teapot_is_tiny_in_its_stadium() {
        let scene = teapot_in_stadium(2);
        let teapot = scene
            .triangles
            .iter()
            .filter(|t| t.material == 0)
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let all = scene.bounds();
        let (small, large) = (teapot.extent(), all.extent());
        assert!(
            small.max_element() < 0.7 && small.min_element() > 0.15,
            "{small}"
        );
        assert!(large.x > 150.0 && large.z > 120.0, "{large}");
        // The camera looks at the teapot from outside it.
        let camera = scene.camera;
        let inside = |p: Vec3| p.cmpge(teapot.min).all() && p.cmple(teapot.max).all();
        assert!(!inside(camera.eye) && inside(camera.target));
    }
}
