//! Helpers shared by the integration tests: one GPU context per test binary, random rays, and the
//! comparison of GPU hits against the CPU brute-force oracle.
#![allow(dead_code)] // each test binary uses a different subset

use std::sync::OnceLock;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use treelet::geometry::{intersect_triangle, Hit, Ray};
use treelet::gpu::{GpuContext, GpuOptions};
use treelet::scene::Triangle;
use treelet::trace::brute_force_closest_hit;

/// The test GPU (the software driver in CI). Set `XDG_RUNTIME_DIR` quietly if missing.
pub fn gpu() -> &'static GpuContext {
    static GPU: OnceLock<GpuContext> = OnceLock::new();
    GPU.get_or_init(|| {
        GpuContext::new(&GpuOptions::default())
            .expect("a Vulkan adapter (run scripts/install-deps.sh)")
    })
}

pub fn rng(seed: u64) -> Pcg64 {
    Pcg64::seed_from_u64(seed)
}

pub fn random_unit(rng: &mut Pcg64) -> Vec3 {
    loop {
        let v = Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let l = v.length_squared();
        if l > 1e-4 && l <= 1.0 {
            return v / l.sqrt();
        }
    }
}

/// Test rays of every kind the traversal must get right, `per_kind` of each:
/// random rays starting inside the scene box (so inside node boxes), rays aimed at random points
/// on random triangles, rays through triangle edges and vertices, rays running along triangle edges,
/// rays that start outside and point away (misses), and rays with short [t_min, t_max] intervals.
pub fn test_rays(triangles: &[Triangle], per_kind: usize, seed: u64) -> Vec<(&'static str, Ray)> {
    let mut r = rng(seed);
    let bounds = triangles
        .iter()
        .fold(treelet::geometry::Aabb::EMPTY, |b, t| b.union(t.bounds()));
    let diag = bounds.extent().length().max(1e-6);
    let center = bounds.centroid();
    let mut rays = Vec::new();
    let point_in_box = |r: &mut Pcg64| {
        let e = bounds.extent();
        bounds.min
            + Vec3::new(
                r.random::<f32>() * e.x,
                r.random::<f32>() * e.y,
                r.random::<f32>() * e.z,
            )
    };
    for _ in 0..per_kind {
        let o = point_in_box(&mut r);
        rays.push(("inside", Ray::new(o, random_unit(&mut r), 0.0, f32::MAX)));
    }
    for _ in 0..per_kind {
        let tri = triangles[r.random_range(0..triangles.len())];
        let [a, b, c] = tri.vertices();
        let (mut u, mut v) = (r.random::<f32>(), r.random::<f32>());
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let target = a + u * (b - a) + v * (c - a);
        let o = center + random_unit(&mut r) * diag;
        rays.push(("aimed", Ray::new(o, target - o, 0.0, f32::MAX)));
    }
    for i in 0..per_kind {
        let tri = triangles[r.random_range(0..triangles.len())];
        let [a, b, c] = tri.vertices();
        let target = match i % 4 {
            0 => 0.5 * (a + b),
            1 => 0.5 * (b + c),
            2 => 0.5 * (c + a),
            _ => a,
        };
        let o = center + random_unit(&mut r) * diag;
        rays.push(("edge", Ray::new(o, target - o, 0.0, f32::MAX)));
    }
    for _ in 0..per_kind {
        let tri = triangles[r.random_range(0..triangles.len())];
        let [a, b, _] = tri.vertices();
        let o = a - (b - a) * r.random_range(0.1f32..2.0);
        rays.push(("along-edge", Ray::new(o, b - a, 0.0, f32::MAX)));
    }
    for _ in 0..per_kind {
        let d = random_unit(&mut r);
        let o = center + d * diag * 1.5;
        rays.push(("miss", Ray::new(o, d, 0.0, f32::MAX)));
    }
    for _ in 0..per_kind {
        let o = point_in_box(&mut r);
        let t0 = r.random::<f32>() * diag * 0.5;
        rays.push((
            "interval",
            Ray::new(
                o,
                random_unit(&mut r),
                t0,
                t0 + r.random::<f32>() * diag * 0.5,
            ),
        ));
    }
    rays
}

/// Whether a hit lies within 1e-4 (in barycentric terms) of its triangle's edges.
fn grazing(hit: &Hit) -> bool {
    let w = 1.0 - hit.u - hit.v;
    hit.u.min(hit.v).min(w) < 1e-4
}

/// Compares GPU hits with brute force. Identical triangle ids must agree in distance; different
/// ids are accepted as ties (the GPU's triangle is hit at the same distance). Any other
/// disagreement is accepted only for rays of the "edge"/"along-edge" kinds, and only where the
/// hit in question lies on a triangle edge or at the same distance: a crack or overlap between
/// neighbours that float rounding may open on either side (rays in the plane of axis-aligned walls
/// meet many such edges). At most 10% of all rays may disagree so.
/// Returns the number of tolerated edge disagreements.
pub fn assert_hits_match(triangles: &[Triangle], rays: &[(&str, Ray)], gpu_hits: &[Hit]) -> usize {
    assert_eq!(rays.len(), gpu_hits.len());
    let mut edge_disagreements = 0;
    let mut hits = 0;
    for (i, ((kind, ray), gpu)) in rays.iter().zip(gpu_hits).enumerate() {
        let cpu = brute_force_closest_hit(triangles, ray);
        hits += usize::from(cpu.is_hit());
        let eps = 1e-4 * cpu.t.abs().max(1.0);
        match (cpu.is_hit(), gpu.is_hit()) {
            (false, false) => {}
            (true, true) if cpu.tri == gpu.tri => {
                assert!(
                    (cpu.t - gpu.t).abs() <= eps,
                    "ray {i} ({kind}): t {} vs GPU {}",
                    cpu.t,
                    gpu.t
                );
            }
            (true, true) => {
                let [a, b, c] = triangles[gpu.tri as usize].vertices();
                let probe = Ray {
                    t_max: f32::MAX,
                    ..*ray
                };
                let t = intersect_triangle(&probe, a, b, c).map(|h| h.0);
                let tie = t.is_some_and(|t| (t - cpu.t).abs() <= eps);
                if !tie {
                    let edge_kind = *kind == "edge" || *kind == "along-edge";
                    assert!(
                        edge_kind && ((gpu.t - cpu.t).abs() <= eps || grazing(&cpu)),
                        "ray {i} ({kind}): CPU hits {} at {}, GPU hits {} at {} (CPU sees it at {t:?})",
                        cpu.tri, cpu.t, gpu.tri, gpu.t
                    );
                    edge_disagreements += 1;
                }
            }
            (cpu_hit, _) => {
                let h = if cpu_hit { cpu } else { *gpu };
                assert!(
                    (*kind == "edge" || *kind == "along-edge") && grazing(&h),
                    "ray {i} ({kind}): CPU {cpu:?} vs GPU {gpu:?}"
                );
                edge_disagreements += 1;
            }
        }
    }
    assert!(
        hits >= rays.len() / 6,
        "too few rays hit anything ({hits} of {}): the test would prove little",
        rays.len()
    );
    assert!(
        edge_disagreements * 10 <= rays.len(),
        "{edge_disagreements} edge disagreements of {} rays",
        rays.len()
    );
    edge_disagreements
}

/// A random triangle soup of `n` triangles in the unit cube.
pub fn random_soup(n: usize, seed: u64) -> Vec<Triangle> {
    let mut r = rng(seed);
    (0..n)
        .map(|_| {
            let c = Vec3::new(r.random(), r.random(), r.random());
            let s = r.random_range(0.005f32..0.08);
            Triangle::new(
                c + random_unit(&mut r) * s,
                c + random_unit(&mut r) * s,
                c + random_unit(&mut r) * s,
                0,
            )
        })
        .collect()
}

/// A scene of `triangles` with one grey material, framed by the default camera.
pub fn scene_of(triangles: Vec<Triangle>) -> treelet::scene::Scene {
    scene_named("test", triangles)
}

/// `scene_of` with a name (shown in assertion messages).
pub fn scene_named(name: &str, triangles: Vec<Triangle>) -> treelet::scene::Scene {
    let bounds = triangles
        .iter()
        .fold(treelet::geometry::Aabb::EMPTY, |b, t| b.union(t.bounds()));
    treelet::scene::Scene {
        name: name.into(),
        triangles,
        materials: vec![treelet::scene::Material::diffuse(Vec3::splat(0.5))],
        camera: treelet::scene::Camera::framing(&bounds),
        sky: Vec3::ONE,
        lights: Vec::new(),
    }
}

/// Runs the `treelet` binary with `args` (and a private XDG_RUNTIME_DIR).
pub fn run_treelet(args: &[&str]) -> std::process::Output {
    let xdg = std::env::temp_dir().join("treelet-test-xdg");
    std::fs::create_dir_all(&xdg).unwrap();
    std::process::Command::new(env!("CARGO_BIN_EXE_treelet"))
        .args(args)
        .env("XDG_RUNTIME_DIR", &xdg)
        .output()
        .expect("binary runs")
}

/// `treelet args` fails with a message containing `expected`, and without a panic.
pub fn assert_clean_failure(args: &[&str], expected: &str) {
    let out = run_treelet(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert!(
        stderr.contains(expected),
        "{args:?}: expected '{expected}' in: {stderr}"
    );
}
