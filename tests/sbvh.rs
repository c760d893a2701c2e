//! The CPU SBVH (Stich et al. 2009, `src/bvh/sbvh.rs`): its trees pass the multi-reference
//! validator, GPU traversal through them equals brute force (splitting never loses a hit), its SAH
//! is no worse than the sweep builder's on scenes with large triangles, and long diagonal slivers
//! get spatial splits.

mod common;

use common::{
    assert_cpu_traversal_matches, assert_hits_match, gpu, missing_shared_scene, random_soup,
    scene_named, test_rays,
};
use glam::Vec3;
use treelet::bvh::{
    build_sbvh, build_sweep_sah, sah_cost, validate_with_references, Bvh, SahParams,
};
use treelet::device::{Geometry, Tree};
use treelet::scene::{load_scene, Scene, Triangle};
use treelet::trace::closest_hits;

/// A fan of `n` long thin slivers on diagonals around the z axis.
fn fan(n: usize) -> Vec<Triangle> {
    (0..n)
        .map(|i| {
            let a = std::f32::consts::TAU * i as f32 / n as f32;
            let (s, c) = a.sin_cos();
            let d = Vec3::new(c, s, 0.3 * (3.0 * a).sin());
            let side = Vec3::new(-s, c, 0.0) * 0.002;
            Triangle::new(0.01 * d, d + side, d - side, 0)
        })
        .collect()
}

/// A few huge thin triangles crossing the whole scene diagonally, over a small grid of quads.
fn huge_thin() -> Vec<Triangle> {
    let mut tris = Vec::new();
    for i in 0..6 {
        let t = i as f32;
        let a = Vec3::new(-10.0, -10.0 + t, -5.0 + 2.0 * t);
        let b = Vec3::new(10.0, 10.0 - t, 5.0 - t);
        tris.push(Triangle::new(a, b, b + Vec3::new(0.0, 0.05, 0.05), 0));
    }
    for x in 0..10 {
        for y in 0..10 {
            let o = Vec3::new(x as f32 * 2.0 - 10.0, y as f32 * 2.0 - 10.0, 0.0);
            tris.push(Triangle::new(o, o + Vec3::X, o + Vec3::Y, 0));
            tris.push(Triangle::new(
                o + Vec3::X,
                o + Vec3::X + Vec3::Y,
                o + Vec3::Y,
                0,
            ));
        }
    }
    tris
}

/// Builds the SBVH, validates it, traces test rays through it on the GPU against brute force;
/// returns the tree.
fn check_scene(scene: &Scene, per_kind: usize, seed: u64) -> Bvh {
    let params = SahParams::default();
    let start = std::time::Instant::now();
    let bvh = build_sbvh(&scene.triangles, &params);
    let ms = start.elapsed().as_secs_f64() * 1e3;
    let stats = validate_with_references(&bvh, &scene.triangles)
        .unwrap_or_else(|e| panic!("{}: invalid sbvh: {e}", scene.name));
    assert!(stats.max_leaf_size <= params.max_leaf_size as usize);
    let geometry = Geometry::upload(gpu(), scene).unwrap();
    let tree = Tree::upload(gpu(), &bvh).unwrap();
    let rays = test_rays(&scene.triangles, per_kind, seed);
    let plain: Vec<_> = rays.iter().map(|(_, r)| *r).collect();
    let hits = closest_hits(gpu(), &geometry, &tree, &plain).unwrap();
    let ties = assert_hits_match(&scene.triangles, &rays, &hits);
    assert_cpu_traversal_matches(&bvh, &scene.triangles, &rays);
    println!(
        "{}: {} triangles, {} references, {} nodes, depth {}, SAH {:.3}, built in {ms:.1} ms; \
         {} rays, {ties} hit an equally close neighbour",
        scene.name,
        scene.triangles.len(),
        bvh.prim_indices.len(),
        bvh.nodes.len(),
        stats.max_depth,
        sah_cost(&bvh, &params),
        rays.len()
    );
    bvh
}

/// SBVH's SAH is at most the sweep builder's (0.1% slack); returns (sbvh, sweep).
fn assert_sah_not_worse(scene: &Scene, sbvh: &Bvh) -> (f32, f32) {
    let params = SahParams::default();
    let sweep = build_sweep_sah(&scene.triangles, &params);
    let (a, b) = (sah_cost(sbvh, &params), sah_cost(&sweep, &params));
    println!("{}: SAH sbvh {a:.4} vs sweep {b:.4}", scene.name);
    assert!(a <= b * 1.001, "{}: sbvh {a} vs sweep {b}", scene.name);
    (a, b)
}

#[test]
fn cornell_is_valid_traced_exactly_and_not_worse_than_sweep() {
    let scene = load_scene("cornell").unwrap();
    let bvh = check_scene(&scene, 400, 2);
    assert_sah_not_worse(&scene, &bvh);
}

#[test]
fn huge_thin_triangles_are_split_and_not_worse_than_sweep() {
    let scene = scene_named("huge-thin", huge_thin());
    let bvh = check_scene(&scene, 400, 6);
    assert!(bvh.prim_indices.len() > scene.triangles.len());
    let (a, b) = assert_sah_not_worse(&scene, &bvh);
    assert!(a < b, "spatial splits should pay here: {a} vs {b}");
}

#[test]
fn fan_of_slivers_gets_spatial_splits() {
    let scene = scene_named("fan", fan(2000));
    let bvh = check_scene(&scene, 400, 7);
    assert!(
        bvh.prim_indices.len() > scene.triangles.len(),
        "{} references for {} triangles",
        bvh.prim_indices.len(),
        scene.triangles.len()
    );
    let (a, b) = assert_sah_not_worse(&scene, &bvh);
    assert!(a < b, "spatial splits should pay here: {a} vs {b}");
}

#[test]
fn field_is_valid_and_traced_exactly() {
    check_scene(&load_scene("field-10k").unwrap(), 400, 3);
}

#[test]
fn random_soup_is_valid_and_traced_exactly() {
    check_scene(&scene_named("soup", random_soup(3000, 7)), 500, 1);
}

#[test]
fn shared_buddha_is_valid_and_traced_exactly() {
    match load_scene("buddha") {
        Ok(scene) => {
            check_scene(&scene, 300, 4);
        }
        Err(e) => missing_shared_scene(e),
    }
}
