//! GPU closest-hit traversal (and the CPU traversal) through CPU-built trees equals CPU brute
//! force, for rays of every kind (inside boxes, aimed, through edges and vertices, along edges,
//! misses, short intervals) on several scenes, and counts the steps of its CPU twin.

mod common;

use common::{
    assert_cpu_traversal_matches, assert_hits_match, gpu, missing_shared_scene, random_soup,
    scene_of, test_rays,
};
use glam::Vec3;
use treelet::bvh::wide::Layout;
use treelet::bvh::{build_sweep_sah, validate, SahParams, TraversalSteps};
use treelet::device::{Geometry, Tree};
use treelet::geometry::Ray;
use treelet::scene::{load_scene, stacked_duplicates, Scene};
use treelet::trace::{closest_hits, closest_hits_with_steps};

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

/// The GPU's binary traversal counts the steps its CPU twin takes (`Bvh::closest_hit_steps`):
/// internal nodes whose children's boxes it tested and triangles tested, ray by ray. Exact on a
/// CPU device; a GPU may divide approximately (1/direction in the box test), which can order a
/// near-tie of two children's entries the other way, so there a few rays may differ.
#[test]
fn traversal_steps_equal_the_cpu_twin() {
    let exact = gpu().info.device_type == wgpu::DeviceType::Cpu;
    for (seed, scene) in [
        scene_of(random_soup(3000, 11)),
        load_scene("field-10k").unwrap(),
        stacked_duplicates(4),
    ]
    .iter()
    .enumerate()
    {
        let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
        let geometry = Geometry::upload(gpu(), scene).unwrap();
        let tree = Tree::upload(gpu(), &bvh).unwrap();
        let rays = test_rays(&scene.triangles, 300, seed as u64 + 60);
        let plain: Vec<Ray> = rays.iter().map(|(_, r)| *r).collect();
        let (hits, steps) =
            closest_hits_with_steps(gpu(), &geometry, &tree, &plain, Layout::Binary).unwrap();
        assert_hits_match(&scene.triangles, &rays, &hits);
        let twin: Vec<TraversalSteps> = plain
            .iter()
            .map(|r| bvh.closest_hit_steps(&scene.triangles, r).1)
            .collect();
        let differing = steps.iter().zip(&twin).filter(|(g, c)| g != c).count();
        let gpu_total: TraversalSteps = steps.iter().copied().sum();
        let cpu_total: TraversalSteps = twin.iter().copied().sum();
        println!(
            "{}: {} rays, {gpu_total:?} on the GPU, {cpu_total:?} on the CPU, {differing} rays differ",
            scene.name,
            rays.len()
        );
        assert!(cpu_total.nodes > plain.len() as u64 && cpu_total.triangles > 0);
        if exact {
            assert_eq!(steps, twin, "{}", scene.name);
        } else {
            assert!(
                differing * 100 <= plain.len(),
                "{}: {differing} rays",
                scene.name
            );
        }
    }
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
