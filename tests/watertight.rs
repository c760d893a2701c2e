//! Watertightness (Woop, Benthin & Wald 2013): rays shot from inside closed meshes exactly at
//! their shared vertices and at points of their shared edges never escape, on the CPU (brute
//! force and traversal) and on the GPU through the tree of every builder, for closest-hit and
//! any-hit queries. The meshes stress the cases a non-watertight test leaks through: subdivided
//! grids (vertices of valence 4-6 on flat faces and folded cube edges), fans of high valence
//! (poles of a sphere, the apexes of a 300-sided bipyramid), a non-convex torus, and all of them
//! rotated and moved far from the origin, where coordinates carry few bits below the point.

mod common;

use common::{assert_hits_equal, cpu_traversal_hits, gpu, oracle_hits, record_update, rng};
use glam::{Quat, Vec3};
use rand::Rng;
use treelet::bvh::treelet::RoundSchedule;
use treelet::bvh::wide::{Layout, WideOptions};
use treelet::bvh::{validate_with_references, Builder, SahParams, TreeUpdater, UpdateMode};
use treelet::device::{Geometry, Tree};
use treelet::geometry::{Hit, Ray};
use treelet::gpu::Timing;
use treelet::scene::{Scene, Triangle};
use treelet::trace::{any_hits, any_hits_wide, closest_hits, closest_hits_wide};

/// A closed indexed mesh: shared vertices are one entry, so neighbours see bit-identical
/// coordinates after any transform.
struct Mesh {
    name: String,
    vertices: Vec<Vec3>,
    faces: Vec<[u32; 3]>,
    /// Points strictly inside, with the vertices each one aims at (all when `None`).
    viewpoints: Vec<(Vec3, Option<Vec<u32>>)>,
}

impl Mesh {
    fn triangles(&self) -> Vec<Triangle> {
        self.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| self.vertices[i as usize]);
                Triangle::new(a, b, c, 0)
            })
            .collect()
    }

    /// The same mesh rotated and moved to `offset` (every vertex transformed once).
    fn moved(&self, rotation: Quat, offset: Vec3) -> Self {
        let map = |p: Vec3| rotation * p + offset;
        Self {
            name: format!("{} at {offset}", self.name),
            vertices: self.vertices.iter().map(|&v| map(v)).collect(),
            faces: self.faces.clone(),
            viewpoints: self
                .viewpoints
                .iter()
                .map(|(p, targets)| (map(*p), targets.clone()))
                .collect(),
        }
    }

    /// Rays from the viewpoints exactly at vertices and at points of edges (midpoints and thirds),
    /// `t_max` = `reach` (in units of the distance to the target).
    fn rays(&self, reach: f32) -> Vec<(&'static str, Ray)> {
        let mut rays = Vec::new();
        for (origin, targets) in &self.viewpoints {
            let all: Vec<u32>;
            let targets = match targets {
                Some(t) => t,
                None => {
                    all = (0..self.vertices.len() as u32).collect();
                    &all
                }
            };
            let aimed = |target: Vec3| Ray::new(*origin, target - *origin, 0.0, reach);
            let mut aimed_at = vec![false; self.vertices.len()];
            for &v in targets {
                aimed_at[v as usize] = true;
                rays.push(("vertex", aimed(self.vertices[v as usize])));
            }
            for f in &self.faces {
                if !f.iter().all(|&v| aimed_at[v as usize]) {
                    continue;
                }
                for k in 0..3 {
                    let (a, b) = (
                        self.vertices[f[k] as usize],
                        self.vertices[f[(k + 1) % 3] as usize],
                    );
                    // Each edge once (from the face that walks it in increasing vertex order).
                    if f[k] < f[(k + 1) % 3] {
                        rays.push(("edge", aimed(0.5 * (a + b))));
                        rays.push(("edge", aimed(a + (b - a) / 3.0)));
                    }
                }
            }
        }
        rays
    }
}

/// A cube of side 2 with every face an n×n grid; vertices come from integer lattice points, so
/// the cube's edges and corners are shared exactly by the faces that meet there.
fn subdivided_cube(n: u32) -> Mesh {
    let mut index = std::collections::HashMap::new();
    let mut vertices = Vec::new();
    let mut vertex = |p: [u32; 3]| -> u32 {
        *index.entry(p).or_insert_with(|| {
            vertices
                .push(Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32) * (2.0 / n as f32) - 1.0);
            vertices.len() as u32 - 1
        })
    };
    let mut faces = Vec::new();
    for axis in 0..3 {
        for side in [0, n] {
            for i in 0..n {
                for j in 0..n {
                    let p = |di: u32, dj: u32| {
                        let mut q = [0; 3];
                        q[axis] = side;
                        q[(axis + 1) % 3] = i + di;
                        q[(axis + 2) % 3] = j + dj;
                        q
                    };
                    let [a, b, c, d] = [p(0, 0), p(1, 0), p(1, 1), p(0, 1)].map(&mut vertex);
                    // Alternate the diagonal so that vertices get valences 4 to 8.
                    if (i + j) % 2 == 0 {
                        faces.extend([[a, b, c], [a, c, d]]);
                    } else {
                        faces.extend([[a, b, d], [b, c, d]]);
                    }
                }
            }
        }
    }
    Mesh {
        name: format!("cube {n}x{n}"),
        vertices,
        faces,
        viewpoints: interior_points(0.6),
    }
}

/// A unit UV sphere: two poles of valence `segments`.
fn uv_sphere(segments: u32, rings: u32) -> Mesh {
    let mut vertices = vec![Vec3::Y, -Vec3::Y];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            vertices.push(Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ));
        }
    }
    let ring = |r: u32, s: u32| 2 + (r - 1) * segments + s % segments;
    let mut faces = Vec::new();
    for s in 0..segments {
        faces.push([0, ring(1, s + 1), ring(1, s)]);
        faces.push([1, ring(rings - 1, s), ring(rings - 1, s + 1)]);
        for r in 1..rings - 1 {
            let (a, b) = (ring(r, s), ring(r, s + 1));
            let (c, d) = (ring(r + 1, s), ring(r + 1, s + 1));
            faces.extend([[a, b, d], [a, d, c]]);
        }
    }
    Mesh {
        name: format!("sphere {segments}x{rings}"),
        vertices,
        faces,
        viewpoints: interior_points(0.5),
    }
}

/// Two cones of `segments` sliver triangles glued at their rims: apexes of valence `segments`.
fn bipyramid(segments: u32) -> Mesh {
    let mut vertices = vec![Vec3::Z, -Vec3::Z];
    for s in 0..segments {
        let phi = std::f32::consts::TAU * s as f32 / segments as f32;
        vertices.push(Vec3::new(phi.cos(), phi.sin(), 0.0));
    }
    let rim = |s: u32| 2 + s % segments;
    let faces = (0..segments)
        .flat_map(|s| [[0, rim(s), rim(s + 1)], [1, rim(s + 1), rim(s)]])
        .collect();
    Mesh {
        name: format!("bipyramid {segments}"),
        vertices,
        faces,
        viewpoints: interior_points(0.3),
    }
}

/// A torus (major radius 1, minor 0.35): non-convex. Each viewpoint is the centre of one tube
/// section and aims at that section's ring of vertices.
fn torus(sections: u32, sides: u32) -> Mesh {
    let (major, minor) = (1.0f32, 0.35f32);
    let mut vertices = Vec::new();
    let mut viewpoints = Vec::new();
    for i in 0..sections {
        let phi = std::f32::consts::TAU * i as f32 / sections as f32;
        let centre = Vec3::new(phi.cos(), 0.0, phi.sin()) * major;
        let targets = (0..sides).map(|j| i * sides + j).collect();
        viewpoints.push((centre, Some(targets)));
        for j in 0..sides {
            let psi = std::f32::consts::TAU * j as f32 / sides as f32;
            let radial = major + minor * psi.cos();
            vertices.push(Vec3::new(
                phi.cos() * radial,
                minor * psi.sin(),
                phi.sin() * radial,
            ));
        }
    }
    let at = |i: u32, j: u32| (i % sections) * sides + j % sides;
    let mut faces = Vec::new();
    for i in 0..sections {
        for j in 0..sides {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            faces.extend([[a, b, c], [a, c, d]]);
        }
    }
    Mesh {
        name: format!("torus {sections}x{sides}"),
        vertices,
        faces,
        viewpoints: viewpoints.into_iter().step_by(5).collect(),
    }
}

/// The centre and a random point within `radius` of it.
fn interior_points(radius: f32) -> Vec<(Vec3, Option<Vec<u32>>)> {
    let mut r = rng(3);
    let mut points = vec![(Vec3::ZERO, None)];
    for _ in 0..1 {
        let p = Vec3::new(r.random(), r.random(), r.random()) * 2.0 - 1.0;
        points.push((p.normalize_or_zero() * radius * r.random::<f32>(), None));
    }
    points
}

/// Every mesh in place and rotated far from the origin.
fn meshes() -> Vec<Mesh> {
    let base = [
        subdivided_cube(12),
        uv_sphere(64, 16),
        bipyramid(300),
        torus(60, 24),
    ];
    let turn = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 0.7);
    let far = [
        Vec3::new(1.0e4, -2.5e3, 3.0e3),
        Vec3::new(-2.0e5, 1.0e5, 5.0e4),
        Vec3::new(3.0e2, 1.0e3, -7.0e2),
        Vec3::new(6.0e3, 6.0e3, -6.0e3),
    ];
    let mut all = Vec::new();
    for (mesh, offset) in base.into_iter().zip(far) {
        let moved = mesh.moved(turn, offset);
        all.push(mesh);
        all.push(moved);
    }
    all
}

fn scene_of(mesh: &Mesh) -> Scene {
    common::scene_named(&mesh.name, mesh.triangles())
}

/// How far a ray aimed at a surface point from inside reaches before it must have hit: the aim
/// point (t = 1), plus its rounding (an edge point far from the origin, where an ulp may be 1/64,
/// may lie a few ulps off the surface).
fn reach(ray: &Ray) -> f32 {
    let (origin, dir) = (Vec3::from(ray.origin), Vec3::from(ray.dir));
    let magnitude = (origin + dir).abs().max_element();
    let ulp = f32::from_bits(magnitude.to_bits() + 1) - magnitude;
    1.0 + 1e-4 + 16.0 * ulp / dir.length()
}

/// Every ray hits, at most `reach` along.
fn assert_no_escape(
    mesh: &Mesh,
    rays: &[(&str, Ray)],
    t: impl Fn(usize) -> Option<f32>,
    who: &str,
) {
    let mut escaped = Vec::new();
    for (i, (kind, ray)) in rays.iter().enumerate() {
        match t(i) {
            Some(t) if t > 0.0 && t <= reach(ray) => {}
            other => escaped.push(format!("ray {i} ({kind}) from {:?}: {other:?}", ray.origin)),
        }
    }
    assert!(
        escaped.is_empty(),
        "{who}, {}: {} of {} rays escaped, e.g. {:?}",
        mesh.name,
        escaped.len(),
        rays.len(),
        &escaped[..escaped.len().min(3)]
    );
}

#[test]
fn brute_force_never_escapes() {
    for mesh in meshes() {
        let rays = mesh.rays(f32::MAX);
        let hits = oracle_hits(&mesh.triangles(), &rays);
        assert_no_escape(
            &mesh,
            &rays,
            |i| hits[i].is_hit().then_some(hits[i].t),
            "brute force",
        );
    }
}

/// Every builder's tree, traced on the GPU (closest hit and any hit, binary and wide layout) and
/// on the CPU: no ray escapes, and the closest hits equal brute force.
#[test]
fn no_builder_lets_a_ray_escape() {
    let params = SahParams::default();
    let cases: Vec<_> = meshes()
        .into_iter()
        .map(|mesh| {
            let scene = scene_of(&mesh);
            let rays = mesh.rays(f32::MAX);
            let oracle = oracle_hits(&scene.triangles, &rays);
            (mesh, scene, rays, oracle)
        })
        .collect();
    for &builder in Builder::ALL {
        let who = builder.label();
        // Builders compile their pipelines once and rebuild per mesh, as per frame.
        let mut updater = TreeUpdater::new(gpu(), UpdateMode::Rebuild(builder), &params).unwrap();
        updater.set_layout(gpu(), Layout::Wide);
        for (mesh, scene, rays, oracle) in &cases {
            let geometry = Geometry::upload(gpu(), scene).unwrap();
            let mut tree = Tree::empty(gpu()).unwrap();
            record_update(&mut updater, &geometry, &scene.triangles, &mut tree).unwrap();
            let bvh = tree.download(gpu()).unwrap();
            validate_with_references(&bvh, &scene.triangles)
                .unwrap_or_else(|e| panic!("{who}, {}: invalid tree: {e}", mesh.name));
            let plain: Vec<Ray> = rays.iter().map(|(_, r)| *r).collect();
            let hits = closest_hits(gpu(), &geometry, &tree, &plain).unwrap();
            let t_of = |h: &[Hit], i: usize| h[i].is_hit().then_some(h[i].t);
            assert_no_escape(mesh, rays, |i| t_of(&hits, i), &format!("GPU {who}"));
            assert_hits_equal(&scene.triangles, rays, oracle, &hits);
            let wide = closest_hits_wide(gpu(), &geometry, &tree, &plain).unwrap();
            assert_no_escape(mesh, rays, |i| t_of(&wide, i), &format!("GPU wide {who}"));
            assert_hits_equal(&scene.triangles, rays, oracle, &wide);
            let cpu = cpu_traversal_hits(&bvh, &scene.triangles, rays);
            assert_no_escape(mesh, rays, |i| t_of(&cpu, i), &format!("CPU {who}"));
            assert_hits_equal(&scene.triangles, rays, oracle, &cpu);
            // Any-hit rays end just beyond the aim point: each must find the surface.
            let shadow: Vec<Ray> = plain
                .iter()
                .map(|r| Ray {
                    t_max: reach(r),
                    ..*r
                })
                .collect();
            let any = any_hits(gpu(), &geometry, &tree, &shadow).unwrap();
            assert_no_escape(mesh, rays, |i| t_of(&any, i), &format!("GPU any-hit {who}"));
            let any_wide = any_hits_wide(gpu(), &geometry, &tree, &shadow).unwrap();
            assert_no_escape(
                mesh,
                rays,
                |i| t_of(&any_wide, i),
                &format!("GPU wide any-hit {who}"),
            );
            let cpu_any: Vec<Hit> = shadow
                .iter()
                .map(|r| bvh.any_hit(&scene.triangles, r))
                .collect();
            assert_no_escape(
                mesh,
                rays,
                |i| t_of(&cpu_any, i),
                &format!("CPU any-hit {who}"),
            );
        }
    }
}

/// Any-hit queries that end before the surface find nothing inside a closed convex mesh.
#[test]
fn any_hit_respects_the_interval() {
    let mesh = uv_sphere(48, 16);
    let scene = scene_of(&mesh);
    let short: Vec<Ray> = mesh.rays(0.9).into_iter().map(|(_, r)| r).collect();
    let (geometry, tree, _) = Builder::Lbvh
        .build(
            gpu(),
            &scene,
            &SahParams::default(),
            &Timing::quick(1),
            Layout::Wide,
            WideOptions::default(),
            RoundSchedule::default(),
            None,
        )
        .unwrap();
    for any in [
        any_hits(gpu(), &geometry, &tree, &short).unwrap(),
        any_hits_wide(gpu(), &geometry, &tree, &short).unwrap(),
    ] {
        assert!(
            any.iter().all(|h| !h.is_hit()),
            "a hit inside an empty sphere"
        );
    }
}
