//! Triangle pre-splitting (Karras & Aila 2013, §5): reference boxes are non-empty and inside their
//! triangle's box and together cover it; one triangle's references are distinct pieces; the reference count respects the budget; the GPU stage
//! equals its CPU twin (counts exactly, boxes to rounding); whole trbvh-split trees match the CPU
//! twin's quality; β = 0 gives the trbvh tree exactly; rays traced through trbvh-split trees
//! equal brute force.

mod common;

use common::{assert_hits_match, gpu, random_soup, scene_of, test_rays};
use glam::Vec3;
use treelet::bvh::presplit::{
    budget_scale, presplit_cpu, split_budget, split_priority, splits_at, PreSplitter, SplitGrid,
};
use treelet::bvh::treelet::{
    build_trbvh_cpu, build_trbvh_split_cpu, TrbvhBuilder, TreeletSettings,
};
use treelet::bvh::{sah_cost, validate, validate_with_references, SahParams};
use treelet::geometry::Aabb;
use treelet::scene::{load_scene, Triangle};
use treelet::trace::{closest_hits, GpuScene};

/// A scene that needs splitting: long diagonal slivers crossing a field of small triangles.
fn slivers() -> Vec<Triangle> {
    let mut tris = random_soup(2000, 5);
    for i in 0..60 {
        let y = i as f32 / 60.0;
        tris.push(Triangle::new(
            Vec3::new(-1.0, y, -1.0),
            Vec3::new(2.0, y + 0.01, 2.0),
            Vec3::new(2.0, y, 1.9),
            0,
        ));
    }
    tris
}

fn check_fragments(triangles: &[Triangle], boxes: &[Aabb], ref_tris: &[u32], budget: u32) {
    assert_eq!(boxes.len(), ref_tris.len());
    assert!(
        boxes.len() as u64 <= triangles.len() as u64 + u64::from(budget),
        "budget exceeded"
    );
    let mut union = vec![Aabb::EMPTY; triangles.len()];
    for (b, &t) in boxes.iter().zip(ref_tris) {
        let tb = triangles[t as usize].bounds();
        assert!(!b.is_empty(), "empty fragment box of triangle {t}");
        assert!(
            tb.contains(b, 0.0),
            "fragment {b:?} outside triangle {t}'s box {tb:?}"
        );
        union[t as usize] = union[t as usize].union(*b);
    }
    // Every triangle here spans many grid cells, so each reference must be a different piece: a
    // copy of a box would spend budget on nothing (a piece cut at a grid plane must not be split
    // at that plane again).
    let mut pieces: Vec<(u32, [u32; 6])> = ref_tris
        .iter()
        .zip(boxes)
        .map(|(&t, b)| {
            let bits = [b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z].map(f32::to_bits);
            (t, bits)
        })
        .collect();
    pieces.sort_unstable();
    if let Some(w) = pieces.windows(2).find(|w| w[0] == w[1]) {
        panic!("triangle {} has two references with the same box", w[0].0);
    }
    for (t, (tri, u)) in triangles.iter().zip(&union).enumerate() {
        let tb = tri.bounds();
        let tol = 1e-5 * tb.extent().max_element().max(1e-6);
        assert!(
            u.contains(&tb, tol),
            "fragments of triangle {t} do not cover its box: {u:?} vs {tb:?}"
        );
    }
}

#[test]
fn cpu_fragments_cover_triangles_within_budget() {
    for (tris, percent) in [
        (slivers(), 30),
        (load_scene("cornell").unwrap().triangles, 50),
        (random_soup(3000, 3), 10),
    ] {
        let budget = split_budget(tris.len() as u32, percent);
        let (boxes, ref_tris) = presplit_cpu(&tris, budget);
        check_fragments(&tris, &boxes, &ref_tris, budget);
    }
    let tris = slivers();
    let (boxes, _) = presplit_cpu(&tris, split_budget(tris.len() as u32, 30));
    assert!(boxes.len() > tris.len(), "slivers were not split");
}

/// The budget search finds the largest scale whose split counts fit: Σ s_t ≤ budget at E, and
/// over budget at the next larger float (the whole budget is used when the priorities allow).
#[test]
fn budget_search_finds_the_largest_scale_that_fits() {
    for (tris, percent) in [
        (load_scene("field-100k").unwrap().triangles, 10),
        (load_scene("field-100k").unwrap().triangles, 50),
        (random_soup(20_000, 9), 30),
        (slivers(), 100),
    ] {
        let scene = tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let grid = SplitGrid::new(&scene);
        let priorities: Vec<f32> = tris.iter().map(|t| split_priority(t, &grid)).collect();
        let budget = split_budget(tris.len() as u32, percent);
        let used = |e: f32| -> u64 { priorities.iter().map(|&q| u64::from(splits_at(e, q))).sum() };
        let e = budget_scale(&priorities, budget);
        assert!(used(e) <= u64::from(budget), "over budget");
        let next = f32::from_bits(e.to_bits() + 1);
        assert!(
            used(next) > u64::from(budget),
            "{percent}%: scale {e} is not the largest that fits ({} of {budget} used)",
            used(e)
        );
    }
}

#[test]
fn gpu_split_equals_cpu_twin() {
    let mut splitter = PreSplitter::new(gpu());
    for (tris, percent) in [
        (slivers(), 30),
        (load_scene("field-10k").unwrap().triangles, 50),
        (load_scene("cornell").unwrap().triangles, 30),
        // Large budget: a search interval spanning many orders of magnitude.
        (load_scene("field-100k").unwrap().triangles, 30),
    ] {
        let budget = split_budget(tris.len() as u32, percent);
        let scene = scene_of(tris.clone());
        let gpu_scene = GpuScene::upload_geometry(gpu(), &scene).unwrap();
        let (gpu_boxes, gpu_tris) = splitter.split_and_read(gpu(), &gpu_scene, budget).unwrap();
        let (cpu_boxes, cpu_tris) = presplit_cpu(&tris, budget);
        assert_eq!(gpu_tris, cpu_tris, "references per triangle");
        let boxes: Vec<Aabb> = gpu_boxes.into_iter().map(Aabb::from).collect();
        check_fragments(&tris, &boxes, &gpu_tris, budget);
        for (g, c) in boxes.iter().zip(&cpu_boxes) {
            let tol = 1e-5 * c.extent().max_element().max(1e-3);
            assert!(
                (g.min - c.min).abs().max_element() <= tol
                    && (g.max - c.max).abs().max_element() <= tol,
                "GPU box {g:?} vs CPU {c:?}"
            );
        }
    }
}

#[test]
fn trbvh_split_trees_are_valid_and_hits_equal_brute_force() {
    let sah = SahParams::default();
    let settings = TreeletSettings {
        split_percent: 30,
        ..TreeletSettings::BALANCED
    };
    let mut builder = TrbvhBuilder::new(gpu(), settings, sah).unwrap();
    for scene in [
        scene_of(slivers()),
        load_scene("cornell").unwrap(),
        load_scene("field-10k").unwrap(),
    ] {
        let mut gpu_scene = GpuScene::upload_geometry(gpu(), &scene).unwrap();
        builder.build(gpu(), &mut gpu_scene).unwrap();
        let bvh = gpu_scene.download_bvh(gpu()).unwrap();
        validate_with_references(&bvh, &scene.triangles).expect("valid trbvh-split tree");
        // Reference boxes match the CPU twin only to rounding (clipping divides), which can move a
        // Morton key across a cell boundary: the trees agree in quality, not bit for bit.
        let expected = build_trbvh_split_cpu(&scene.triangles, &settings, &sah);
        let (got, want) = (sah_cost(&bvh, &sah), sah_cost(&expected, &sah));
        assert!(
            (got - want).abs() <= 0.02 * want,
            "{}: SAH {got} vs CPU twin {want}",
            scene.name
        );
        let refs = |b: &treelet::bvh::Bvh| b.prim_indices.len() as f64;
        assert!(
            (refs(&bvh) - refs(&expected)).abs() <= 0.02 * refs(&expected),
            "{}: references",
            scene.name
        );
        let rays = test_rays(&scene.triangles, 300, 29);
        let plain: Vec<_> = rays.iter().map(|(_, r)| *r).collect();
        let hits = closest_hits(gpu(), &gpu_scene, &plain).unwrap();
        assert_hits_match(&scene.triangles, &rays, &hits);
    }
}

#[test]
fn zero_budget_gives_the_trbvh_tree() {
    let sah = SahParams::default();
    let scene = load_scene("field-10k").unwrap();
    let settings = TreeletSettings {
        split_percent: 0,
        ..TreeletSettings::BALANCED
    };
    let mut gpu_scene = GpuScene::upload_geometry(gpu(), &scene).unwrap();
    TrbvhBuilder::new(gpu(), settings, sah)
        .unwrap()
        .build(gpu(), &mut gpu_scene)
        .unwrap();
    let bvh = gpu_scene.download_bvh(gpu()).unwrap();
    validate(&bvh, &scene.triangles).unwrap();
    assert_eq!(bvh, build_trbvh_cpu(&scene.triangles, &settings, &sah));
    assert_eq!(
        bvh,
        build_trbvh_split_cpu(&scene.triangles, &settings, &sah)
    );
}
