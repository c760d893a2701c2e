//! Helpers shared by the integration tests: one GPU context per test binary, random rays, and the
//! comparison of GPU hits against the CPU brute-force oracle.
#![allow(dead_code)] // each test binary uses a different subset

use std::sync::OnceLock;

use glam::Vec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use treelet::bvh::Bvh;
use treelet::geometry::{intersect_triangle, Hit, Ray};
use treelet::gpu::{GpuContext, GpuOptions};
use treelet::scene::Triangle;
use treelet::trace::brute_force_closest_hit;

/// The test GPU (the software driver in CI). Set `XDG_RUNTIME_DIR` quietly if missing.
pub fn gpu() -> &'static GpuContext {
    static GPU: OnceLock<GpuContext> = OnceLock::new();
    GPU.get_or_init(|| open_gpu(&GpuOptions::default()))
}

fn open_gpu(options: &GpuOptions) -> GpuContext {
    GpuContext::new(options).expect("a Vulkan adapter (run scripts/install-deps.sh)")
}

/// A device of the test GPU's adapter with the bottom-up climbs at `width` invocations per
/// workgroup (`GpuOptions::climb_width`): a GPU's width on the software driver, and the reverse.
pub fn gpu_with_climb_width(width: u32) -> GpuContext {
    open_gpu(&GpuOptions {
        climb_width: Some(width),
        ..GpuOptions::default()
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

/// Relative tolerance on hit distances between a traversal and the brute-force oracle. Both use
/// the watertight test, whose hit-or-miss decisions are bit-identical on every device (see
/// `treelet::geometry::RayTriangleTest`); a GPU's `t` may differ only through its division
/// (Vulkan allows 2.5 ulp), i.e. by ~3e-7 relative. 1e-5 leaves a wide margin and still tells a
/// wrong triangle or a wrong surface from the right one.
pub const T_TOLERANCE: f32 = 1e-5;

/// The brute-force oracle's closest hit of every ray.
pub fn oracle_hits(triangles: &[Triangle], rays: &[(&str, Ray)]) -> Vec<Hit> {
    rays.iter()
        .map(|(_, ray)| brute_force_closest_hit(triangles, ray))
        .collect()
}

/// Compares traced hits with the watertight brute-force oracle (see `assert_hits_equal`).
pub fn assert_hits_match(triangles: &[Triangle], rays: &[(&str, Ray)], hits: &[Hit]) -> usize {
    let oracle = oracle_hits(triangles, rays);
    let ties = assert_hits_equal(triangles, rays, &oracle, hits);
    let hit_count = oracle.iter().filter(|h| h.is_hit()).count();
    assert!(
        hit_count >= rays.len() / 6,
        "too few rays hit anything ({hit_count} of {}): the test would prove little",
        rays.len()
    );
    ties
}

/// Compares traced hits with the oracle's, ray by ray: hit or miss must agree, the distances must
/// agree within `T_TOLERANCE`, and a different triangle id is accepted only when the oracle's
/// test of that triangle hits it at the same distance too (both triangles contain the hit point:
/// a shared edge or vertex, or coplanar overlap). Returns the number of rays that hit such a
/// different but equally close triangle.
pub fn assert_hits_equal(
    triangles: &[Triangle],
    rays: &[(&str, Ray)],
    oracle: &[Hit],
    hits: &[Hit],
) -> usize {
    assert_eq!(rays.len(), hits.len());
    assert_eq!(rays.len(), oracle.len());
    let mut other_triangle = 0;
    for (i, (((kind, ray), want), got)) in rays.iter().zip(oracle).zip(hits).enumerate() {
        assert_eq!(
            want.is_hit(),
            got.is_hit(),
            "ray {i} ({kind}): oracle {want:?}, traced {got:?}"
        );
        if !want.is_hit() {
            continue;
        }
        let eps = T_TOLERANCE * want.t.abs().max(1e-30);
        assert!(
            (want.t - got.t).abs() <= eps,
            "ray {i} ({kind}): oracle hits {} at {}, traced {} at {}",
            want.tri,
            want.t,
            got.tri,
            got.t
        );
        if want.tri != got.tri {
            let [a, b, c] = triangles[got.tri as usize].vertices();
            let t = intersect_triangle(ray, a, b, c).map(|h| h.0);
            assert!(
                t.is_some_and(|t| (t - want.t).abs() <= eps),
                "ray {i} ({kind}): oracle hits {} at {}, traced {} at {} which the oracle sees at {t:?}",
                want.tri,
                want.t,
                got.tri,
                got.t
            );
            other_triangle += 1;
        }
    }
    other_triangle
}

/// The CPU traversal's closest hit of every ray through `bvh`.
pub fn cpu_traversal_hits(bvh: &Bvh, triangles: &[Triangle], rays: &[(&str, Ray)]) -> Vec<Hit> {
    rays.iter()
        .map(|(_, ray)| bvh.closest_hit(triangles, ray))
        .collect()
}

/// Traces `rays` through `bvh` with the CPU traversal and compares with brute force like
/// `assert_hits_match`.
pub fn assert_cpu_traversal_matches(bvh: &Bvh, triangles: &[Triangle], rays: &[(&str, Ray)]) {
    assert_hits_match(triangles, rays, &cpu_traversal_hits(bvh, triangles, rays));
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

/// A test's shared scene (`../shared/scenes`, or `TREELET_SCENES_DIR`) is not there. CI always
/// has the shared scenes, so with `CI` set this fails the test; elsewhere it says why the test
/// does nothing and lets it pass.
pub fn missing_shared_scene(what: impl std::fmt::Display) {
    if std::env::var_os("CI").is_some() {
        panic!(
            "{what}: the shared scenes must be present in CI (../shared/scenes or TREELET_SCENES_DIR)"
        );
    }
    eprintln!(
        "skipping: {what} (set TREELET_SCENES_DIR to the shared scenes; with CI set this fails)"
    );
}

/// The `treelet` binary with `args` and a private XDG_RUNTIME_DIR, to run.
#[cfg(feature = "app")]
pub fn treelet_command(args: &[&str]) -> std::process::Command {
    let xdg = std::env::temp_dir().join("treelet-test-xdg");
    std::fs::create_dir_all(&xdg).unwrap();
    let mut command = std::process::Command::new(env!("CARGO_BIN_EXE_treelet"));
    command.args(args).env("XDG_RUNTIME_DIR", &xdg);
    command
}

/// Runs the `treelet` binary with `args` (and a private XDG_RUNTIME_DIR).
#[cfg(feature = "app")]
pub fn run_treelet(args: &[&str]) -> std::process::Output {
    treelet_command(args).output().expect("binary runs")
}

/// `treelet args` fails with a message containing `expected`, and without a panic.
#[cfg(feature = "app")]
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

/// Records one update of `tree` by `updater` over `geometry` and submits it, as a frame does
/// (nothing is submitted when recording fails).
pub fn record_update(
    updater: &mut treelet::bvh::TreeUpdater,
    geometry: &treelet::device::Geometry,
    triangles: &[Triangle],
    tree: &mut treelet::device::Tree,
) -> treelet::Result<()> {
    let mut slab = treelet::gpu::ParamSlab::new(gpu());
    let mut rec = treelet::gpu::Recorder::new(gpu(), &mut slab, None);
    updater.record(&mut rec, geometry, triangles, tree)?;
    rec.submit();
    Ok(())
}

/// Converts `tree` over `geometry` into the wide layout on the GPU (`tree.wide`), as an update
/// does.
pub fn convert_wide(
    geometry: &treelet::device::Geometry,
    tree: &mut treelet::device::Tree,
    collapse: treelet::bvh::wide::WideCollapse,
) {
    let mut slab = treelet::gpu::ParamSlab::new(gpu());
    let mut rec = treelet::gpu::Recorder::new(gpu(), &mut slab, None);
    let mut converter =
        treelet::bvh::wide::WideConverter::new(gpu(), &treelet::bvh::SahParams::default());
    converter.set_collapse(collapse);
    converter.record(&mut rec, geometry, tree).unwrap();
    rec.submit();
}
