//! Procedural geometry for the built-in scenes and animations, as triangle soups of vertex triples:
//! subdivided icospheres, subdivided cubes, tessellated rectangles, surfaces of revolution and
//! tubes along curves. All deterministic, all counter-clockwise seen from the outside (the side the
//! normal points to).

use glam::{Vec2, Vec3};
use std::f32::consts::TAU;

/// The icosahedron's 12 vertices (on the unit sphere) and 20 outward faces.
fn icosahedron() -> ([Vec3; 12], [[usize; 3]; 20]) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let v = [
        Vec3::new(-1.0, t, 0.0),
        Vec3::new(1.0, t, 0.0),
        Vec3::new(-1.0, -t, 0.0),
        Vec3::new(1.0, -t, 0.0),
        Vec3::new(0.0, -1.0, t),
        Vec3::new(0.0, 1.0, t),
        Vec3::new(0.0, -1.0, -t),
        Vec3::new(0.0, 1.0, -t),
        Vec3::new(t, 0.0, -1.0),
        Vec3::new(t, 0.0, 1.0),
        Vec3::new(-t, 0.0, -1.0),
        Vec3::new(-t, 0.0, 1.0),
    ]
    .map(Vec3::normalize);
    const FACES: [[usize; 3]; 20] = [
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    (v, FACES)
}

/// The unit sphere as an icosahedron subdivided `level` times: 20·4^level triangles, facing out.
pub fn icosphere(level: u32) -> Vec<[Vec3; 3]> {
    let (v, faces) = icosahedron();
    let mut triangles: Vec<[Vec3; 3]> = faces.iter().map(|&[i, j, k]| [v[i], v[j], v[k]]).collect();
    for _ in 0..level {
        triangles = triangles
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    (a + b).normalize(),
                    (b + c).normalize(),
                    (c + a).normalize(),
                );
                [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
            })
            .collect();
    }
    triangles
}

/// A rectangle from `origin` spanned by `u` and `v`, cut into `nu` × `nv` cells of two triangles;
/// the front faces `u × v`.
pub fn grid(origin: Vec3, u: Vec3, v: Vec3, nu: u32, nv: u32) -> Vec<[Vec3; 3]> {
    let (nu, nv) = (nu.max(1), nv.max(1));
    let point = |i: u32, j: u32| origin + u * (i as f32 / nu as f32) + v * (j as f32 / nv as f32);
    let mut out = Vec::with_capacity(2 * (nu * nv) as usize);
    for j in 0..nv {
        for i in 0..nu {
            let (p00, p10, p01, p11) = (
                point(i, j),
                point(i + 1, j),
                point(i, j + 1),
                point(i + 1, j + 1),
            );
            out.push([p00, p10, p11]);
            out.push([p00, p11, p01]);
        }
    }
    out
}

/// The cube [-1, 1]³ with every face cut into `n` × `n` cells: 12·n² triangles, facing out.
pub fn cube(n: u32) -> Vec<[Vec3; 3]> {
    let faces = [
        (Vec3::X, Vec3::Z, Vec3::Y),
        (Vec3::NEG_X, Vec3::Y, Vec3::Z),
        (Vec3::Y, Vec3::X, Vec3::Z),
        (Vec3::NEG_Y, Vec3::Z, Vec3::X),
        (Vec3::Z, Vec3::X, Vec3::Y),
        (Vec3::NEG_Z, Vec3::Y, Vec3::X),
    ];
    faces
        .iter()
        .flat_map(|&(normal, a, b)| {
            // u × v must point along the normal: swap the axes where a × b points inwards.
            let (u, v) = if a.cross(b).dot(normal) > 0.0 {
                (a, b)
            } else {
                (b, a)
            };
            grid(normal - u - v, 2.0 * u, 2.0 * v, n, n)
        })
        .collect()
}

/// A closed box between `min` and `max`, each face cut into `n` × `n` cells, facing out.
pub fn box_between(min: Vec3, max: Vec3, n: u32) -> Vec<[Vec3; 3]> {
    let center = 0.5 * (min + max);
    let half = 0.5 * (max - min);
    cube(n)
        .into_iter()
        .map(|tri| tri.map(|p| center + p * half))
        .collect()
}

/// The surface swept by turning `profile` (points (r, y), r ≥ 0: distance from the y axis and
/// height) about the y axis in `around` steps (at least 3): two triangles per step between
/// consecutive profile points, one where either point lies on the axis (r = 0), none where both
/// do. A profile that runs from the axis outwards and up, and back to the axis, gives a closed
/// surface facing out.
pub fn lathe(profile: &[Vec2], around: u32) -> Vec<[Vec3; 3]> {
    let around = around.max(3);
    let point = |p: Vec2, step: u32| {
        let angle = TAU * step as f32 / around as f32;
        Vec3::new(p.x * angle.cos(), p.y, p.x * angle.sin())
    };
    let mut out = Vec::new();
    for pair in profile.windows(2) {
        let (lower, upper) = (pair[0], pair[1]);
        for step in 0..around {
            let (a, b) = (point(lower, step), point(lower, step + 1));
            let (c, d) = (point(upper, step + 1), point(upper, step));
            if lower.x > 0.0 && upper.x > 0.0 {
                out.push([a, d, c]);
                out.push([a, c, b]);
            } else if lower.x > 0.0 {
                out.push([a, d, b]);
            } else if upper.x > 0.0 {
                out.push([a, d, c]);
            }
        }
    }
    out
}

/// A tube along the centre line `centres` (at least two points) with radius `radii[i]` at point
/// i, open at both ends: `around` (at least 3) steps around, two triangles per step and segment.
/// Each ring lies across the line's direction there, oriented by `binormal`, which must not be
/// parallel to the line anywhere (a plane curve's normal does it). Facing out.
pub fn tube(centres: &[Vec3], radii: &[f32], binormal: Vec3, around: u32) -> Vec<[Vec3; 3]> {
    let around = around.max(3);
    let last = centres.len() - 1;
    let rings: Vec<Vec<Vec3>> = (0..=last)
        .map(|i| {
            let tangent = (centres[(i + 1).min(last)] - centres[i.saturating_sub(1)]).normalize();
            let normal = binormal.cross(tangent).normalize();
            let side = tangent.cross(normal);
            (0..around)
                .map(|step| {
                    let angle = TAU * step as f32 / around as f32;
                    centres[i] + radii[i] * (angle.cos() * normal + angle.sin() * side)
                })
                .collect()
        })
        .collect();
    let mut out = Vec::with_capacity(2 * last * around as usize);
    for pair in rings.windows(2) {
        for step in 0..around as usize {
            let next = (step + 1) % around as usize;
            let (a, b) = (pair[0][step], pair[0][next]);
            let (c, d) = (pair[1][next], pair[1][step]);
            out.push([a, b, c]);
            out.push([a, c, d]);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn outward(triangles: &[[Vec3; 3]], center: Vec3) -> bool {
        triangles
            .iter()
            .all(|[a, b, c]| (*b - *a).cross(*c - *a).dot(*a + *b + *c - 3.0 * center) > 0.0)
    }

    #[test]
    fn icospheres_have_the_expected_size_and_face_out() {
        for level in 0..3 {
            let s = icosphere(level);
            assert_eq!(s.len(), 20 * 4usize.pow(level));
            assert!(outward(&s, Vec3::ZERO));
            assert!(s.iter().flatten().all(|v| (v.length() - 1.0).abs() < 1e-5));
        }
    }

    #[test]
    fn cubes_and_boxes_face_out() {
        let c = cube(3);
        assert_eq!(c.len(), 12 * 9);
        assert!(outward(&c, Vec3::ZERO));
        let b = box_between(Vec3::new(1.0, 2.0, 3.0), Vec3::new(2.0, 4.0, 4.0), 2);
        assert!(outward(&b, Vec3::new(1.5, 3.0, 3.5)));
        assert!(b
            .iter()
            .flatten()
            .all(|p| p.x >= 1.0 && p.x <= 2.0 && p.y >= 2.0 && p.y <= 4.0));
    }

    #[test]
    fn grids_face_u_cross_v() {
        let g = grid(Vec3::ZERO, Vec3::X, Vec3::Z, 3, 2);
        assert_eq!(g.len(), 12);
        assert!(g.iter().all(|[a, b, c]| (*b - *a).cross(*c - *a).y < 0.0));
    }

    /// Six times the signed volume a closed surface encloses (positive when it faces out).
    fn six_volumes(triangles: &[[Vec3; 3]]) -> f32 {
        triangles.iter().map(|[a, b, c]| a.dot(b.cross(*c))).sum()
    }

    #[test]
    fn lathes_close_and_face_out() {
        // A cylinder of radius 1 and height 2 with flat ends.
        let profile = [
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 2.0),
            Vec2::new(0.0, 2.0),
        ];
        let around = 64;
        let surface = lathe(&profile, around);
        assert_eq!(surface.len(), 4 * around as usize);
        let volume = six_volumes(&surface) / 6.0;
        let polygon = 0.5 * around as f32 * (TAU / around as f32).sin();
        assert!((volume - 2.0 * polygon).abs() < 1e-3, "{volume}");
        // Sides face away from the axis.
        for [a, b, c] in &surface[around as usize..3 * around as usize] {
            let n = (*b - *a).cross(*c - *a);
            let centre = (*a + *b + *c) / 3.0;
            assert!(n.dot(Vec3::new(centre.x, 0.0, centre.z)) > 0.0);
        }
    }

    #[test]
    fn tubes_face_away_from_their_centre_line() {
        let centres: Vec<Vec3> = (0..=8)
            .map(|i| {
                let a = 0.3 * i as f32;
                Vec3::new(a.cos(), a.sin(), 0.0)
            })
            .collect();
        let radii = vec![0.1; centres.len()];
        let around = 12;
        let surface = tube(&centres, &radii, Vec3::Z, around);
        assert_eq!(surface.len(), 2 * 8 * around as usize);
        for (k, [a, b, c]) in surface.iter().enumerate() {
            let segment = k / (2 * around as usize);
            let mid = 0.5 * (centres[segment] + centres[segment + 1]);
            let n = (*b - *a).cross(*c - *a);
            assert!(n.length() > 0.0);
            assert!(
                n.dot((*a + *b + *c) / 3.0 - mid) > 0.0,
                "triangle {k} faces in"
            );
        }
    }
}
