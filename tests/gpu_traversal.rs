//! GPU closest-hit traversal (and the CPU traversal) through CPU-built trees equals CPU brute
//! force, for rays of every kind (inside boxes, aimed, through edges and vertices, along edges,
//! misses, short intervals) on several scenes.

mod common;

use common::{
    assert_cpu_traversal_matches, assert_hits_match, gpu, missing_shared_scene, random_soup,
    scene_of, test_rays,
};
use glam::Vec3;
use treelet::bvh::{build_sweep_sah, validate, SahParams};
use treelet::device::{Geometry, Tree};
use treelet::geometry::Ray;
use treelet::scene::{load_scene, Scene};
use treelet::trace::closest_hits;

fn check_scene(scene: &Scene, per_kind: usize, seed: u64) {
    let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    validate(&bvh, &scene.triangles).expect("sweep tree is valid");
    let geometry = Geometry::upload(gpu(), scene).unwrap();
    let tree = Tree::upload(gpu(), &bvh).unwrap();
    let rays = test_rays(&scene.triangles, per_kind, seed);
    let plain: Vec<_> = rays.iter().map(|(_, r)| *r).collect();
    let hits = closest_hits(gpu(), &geometry, &tree, &plain).unwrap();
    let ties = assert_hits_match(&scene.triangles, &rays, &hits);
    assert_cpu_traversal_matches(&bvh, &scene.triangles, &rays);
    println!(
        "{}: {} rays, {ties} hit an equally close neighbour",
        scene.name,
        rays.len()
    );
}

#[test]
fn random_soup_hits_equal_brute_force() {
    check_scene(&scene_of(random_soup(3000, 7)), 500, 1);
}

#[test]
fn cornell_hits_equal_brute_force() {
    check_scene(&load_scene("cornell").unwrap(), 400, 2);
}

#[test]
fn field_hits_equal_brute_force() {
    check_scene(&load_scene("field-10k").unwrap(), 400, 3);
}

#[test]
fn shared_buddha_hits_equal_brute_force() {
    match load_scene("buddha") {
        Ok(scene) => check_scene(&scene, 300, 4),
        Err(e) => missing_shared_scene(e),
    }
}

#[test]
fn single_triangle_scene() {
    check_scene(&scene_of(random_soup(1, 9)), 100, 5);
}

#[test]
fn rays_with_bad_intervals_are_rejected() {
    let scene = scene_of(random_soup(50, 4));
    let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    let geometry = Geometry::upload(gpu(), &scene).unwrap();
    let tree = Tree::upload(gpu(), &bvh).unwrap();
    let good = Ray::new(Vec3::ZERO, Vec3::X, 0.0, f32::MAX);
    for (t_min, t_max) in [(-1.0, 1.0), (2.0, 1.0), (f32::NAN, 1.0), (0.0, f32::NAN)] {
        let rays = [good, Ray::new(Vec3::ZERO, Vec3::X, t_min, t_max)];
        let err = closest_hits(gpu(), &geometry, &tree, &rays).unwrap_err();
        assert!(
            err.to_string().contains("ray 1 has the interval"),
            "[{t_min}, {t_max}]: {err}"
        );
    }
    assert_eq!(
        closest_hits(gpu(), &geometry, &tree, &[good])
            .unwrap()
            .len(),
        1
    );
}
