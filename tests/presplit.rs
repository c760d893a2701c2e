//! Triangle pre-splitting (Karras & Aila 2013, §5): reference boxes are non-empty and inside their
//! triangle's box and together cover it; one triangle's references are distinct pieces; the
//! reference count respects the budget; the GPU stage agrees with its CPU twin (counts exactly
//! from the GPU's priorities, priorities and boxes within tolerances); whole trbvh-split trees
//! match the CPU twin's quality; β = 0 splits nothing; rays traced through trbvh-split trees equal
//! brute force.

mod common;

use common::{assert_hits_match, gpu, random_soup, scene_of, test_rays};
use glam::Vec3;
use treelet::bvh::presplit::{
    budget_scale, presplit_cpu, split_budget, split_importance, split_priority, split_triangle,
    splits_at, PreSplitter, SplitGrid,
};
use treelet::bvh::treelet::{
    build_trbvh_cpu, build_trbvh_split_cpu, CostModel, TrbvhBuilder, TreeletSettings,
};
use treelet::bvh::{sah_cost, validate_with_references, SahParams};
use treelet::device::{Geometry, Tree};
use treelet::geometry::Aabb;
use treelet::gpu::constants::{MAX_SPLITS, SPLIT_INLINE_PIECES};
use treelet::scene::{load_scene, Triangle};
use treelet::trace::closest_hits;

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

/// A few triangles spanning the scene diagonally among small ones: with a budget of 100 %, the
/// large ones get the most splits a triangle can have (`MAX_SPLITS`), the deepest piece splitting.
fn giants() -> Vec<Triangle> {
    let mut tris = random_soup(1000, 9);
    for i in 0..4 {
        let z = i as f32 / 4.0;
        tris.push(Triangle::new(
            Vec3::new(-1.0, -1.0, z),
            Vec3::new(2.0, 1.9, z + 0.5),
            Vec3::new(1.8, 2.0, z + 0.3),
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

/// Of the triangles, at least this fraction must agree with the CPU twin: priorities within
/// `PRIORITY_TOLERANCE`, and (where split) pieces within `BOX_TOLERANCE`. The rest are triangles
/// whose pieces end within rounding of a grid plane (2^21 cells per axis are near the precision of
/// the coordinates, and the grid scale is a division): a device may cut those elsewhere. Long
/// slivers lying on grid diagonals are the worst case (3 % of `slivers()` under a one-ulp change
/// of the grid scale).
const MIN_AGREEING: f64 = 0.95;
/// Where pieces are cut elsewhere they must still be as good: the total surface area of all
/// references agrees with the CPU twin's (same counts) within this fraction.
const PIECE_AREA_TOLERANCE: f64 = 0.05;
/// Priorities q = 2^i·(A_box − A_ideal) cancel where a triangle fills its box, so their tolerance
/// is relative to 2^i·A_box.
const PRIORITY_TOLERANCE: f32 = 1e-4;
/// Piece box coordinates, relative to the magnitude of the triangle's box coordinates (clipping
/// divides; GPUs may round a division differently).
const BOX_TOLERANCE: f32 = 1e-5;

/// The triangles whose priority or pieces on a device do not agree with the CPU twin's within
/// `PRIORITY_TOLERANCE` and `BOX_TOLERANCE`; the CPU splits each triangle into as many pieces as
/// the device did.
fn disagreeing_triangles(
    tris: &[Triangle],
    priorities: &[f32],
    boxes: &[Aabb],
    ref_tris: &[u32],
    grid: &SplitGrid,
) -> Vec<usize> {
    let mut pieces: Vec<Vec<Aabb>> = vec![Vec::new(); tris.len()];
    for (b, &t) in boxes.iter().zip(ref_tris) {
        pieces[t as usize].push(*b);
    }
    let key = |b: &Aabb| (b.min.to_array(), b.max.to_array());
    let mut disagreeing = Vec::new();
    for (t, (tri, got)) in tris.iter().zip(&mut pieces).enumerate() {
        let tb = tri.bounds();
        let importance = split_importance(tri, grid).unwrap_or(0);
        let scale = 2f32.powi(importance) * tb.surface_area();
        let q = split_priority(tri, grid);
        let mut agrees = (q - priorities[t]).abs() <= PRIORITY_TOLERANCE * scale.max(1e-30);
        if got.len() > 1 {
            let magnitude = tb.min.abs().max(tb.max.abs()).max_element();
            let tol = BOX_TOLERANCE * magnitude.max(tb.extent().max_element());
            let mut want = split_triangle(tri, got.len() as u32, grid);
            want.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
            got.sort_by(|a, b| key(a).partial_cmp(&key(b)).unwrap());
            agrees &= want.iter().zip(got.iter()).all(|(w, g)| {
                (w.min - g.min).abs().max_element() <= tol
                    && (w.max - g.max).abs().max_element() <= tol
            });
        }
        if !agrees {
            disagreeing.push(t);
        }
    }
    let area = |v: &[Aabb]| v.iter().map(|b| f64::from(b.surface_area())).sum::<f64>();
    let device: f64 = pieces.iter().map(|p| area(p)).sum();
    let twin: f64 = tris
        .iter()
        .zip(&pieces)
        .map(|(t, p)| area(&split_triangle(t, p.len() as u32, grid)))
        .sum();
    assert!(
        (device - twin).abs() <= PIECE_AREA_TOLERANCE * twin,
        "the pieces' total surface area {device} differs from the CPU twin's {twin}"
    );
    disagreeing
}

/// The agreement check holds for a device whose divisions round differently: the CPU twin with
/// the grid's scale and cell size one ulp off (both are divisions), against the plain twin.
#[test]
fn a_device_rounding_divisions_differently_passes_the_agreement_check() {
    for (tris, percent) in [
        (slivers(), 30),
        (load_scene("field-10k").unwrap().triangles, 50),
        (load_scene("cornell").unwrap().triangles, 30),
    ] {
        let budget = split_budget(tris.len() as u32, percent);
        let bounds = tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let grid = SplitGrid::new(&bounds);
        let next = |x: f32| f32::from_bits(x.to_bits() + 1);
        let device_grid = SplitGrid {
            scale: next(grid.scale),
            cell: next(grid.cell),
            ..grid
        };
        let priorities: Vec<f32> = tris
            .iter()
            .map(|t| split_priority(t, &device_grid))
            .collect();
        let e = budget_scale(&priorities, budget);
        let (mut boxes, mut ref_tris) = (Vec::new(), Vec::new());
        for (i, (t, &q)) in tris.iter().zip(&priorities).enumerate() {
            for b in split_triangle(t, splits_at(e, q) + 1, &device_grid) {
                boxes.push(b);
                ref_tris.push(i as u32);
            }
        }
        check_fragments(&tris, &boxes, &ref_tris, budget);
        let disagreeing = disagreeing_triangles(&tris, &priorities, &boxes, &ref_tris, &grid);
        println!(
            "{} triangles at {percent}%: {} disagree under other rounding",
            tris.len(),
            disagreeing.len()
        );
        assert!(
            disagreeing.len() as f64 <= (1.0 - MIN_AGREEING) * tris.len() as f64,
            "{} of {} triangles disagree",
            disagreeing.len(),
            tris.len()
        );
    }
}

/// The GPU stage against the CPU twin:
/// - split counts: exactly `splits_at(E, q)` of the GPU's own priorities and scale, within the
///   budget, and E the largest scale that fits (or the top of the search interval): exactly the
///   CPU twin's bisection result from the same priorities (the GPU searches 16-ary);
/// - priorities and pieces: within tolerances for at least `MIN_AGREEING` of the triangles, and
///   the pieces' total surface area within `PIECE_AREA_TOLERANCE`;
/// - the pieces themselves: inside their triangle's box, covering it, and distinct;
/// - some triangle gets `MAX_SPLITS + 1` pieces, the deepest splitting (the kernel's piece stack
///   of `PIECE_STACK` = 5 entries, cut to 3, fails this test; the fifth entry is needed only when
///   every cut shares the references evenly).
#[test]
fn gpu_split_agrees_with_cpu_twin() {
    let mut splitter = PreSplitter::new(gpu());
    let mut most_pieces = 0;
    // Triangles split by each kernel path (pieces in 2..=SPLIT_INLINE_PIECES: one invocation per
    // triangle; more: one per reference), and of those how many disagree with the twin.
    let (mut inline, mut inline_disagreeing) = (0usize, 0usize);
    let (mut heavy, mut heavy_disagreeing) = (0usize, 0usize);
    for (tris, percent) in [
        (slivers(), 30),
        (load_scene("field-10k").unwrap().triangles, 50),
        (load_scene("cornell").unwrap().triangles, 30),
        // Large budget: a search interval spanning many orders of magnitude.
        (load_scene("field-100k").unwrap().triangles, 30),
        (giants(), 100),
    ] {
        let budget = split_budget(tris.len() as u32, percent);
        let scene = scene_of(tris.clone());
        let geometry = Geometry::upload(gpu(), &scene).unwrap();
        let stages = splitter.split_stages(gpu(), &geometry, budget).unwrap();
        let boxes: Vec<Aabb> = stages.boxes.iter().copied().map(Aabb::from).collect();
        check_fragments(&tris, &boxes, &stages.ref_tris, budget);

        let (q, e) = (&stages.priorities, stages.scale);
        let mut pieces = vec![0u32; tris.len()];
        for &t in &stages.ref_tris {
            pieces[t as usize] += 1;
        }
        for (t, (&p, &q)) in pieces.iter().zip(q).enumerate() {
            assert_eq!(p, splits_at(e, q) + 1, "triangle {t}: pieces");
        }
        most_pieces = most_pieces.max(pieces.iter().copied().max().unwrap_or(0));

        let used = |e: f32| -> u64 { q.iter().map(|&q| u64::from(splits_at(e, q))).sum() };
        assert!(used(e) <= u64::from(budget), "over budget");
        assert_eq!(
            e,
            budget_scale(q, budget),
            "{percent}%: GPU scale vs CPU twin"
        );
        let q_max = q.iter().copied().fold(0.0f32, f32::max);
        let top = ((budget + 1) as f32).powi(3) / q_max;
        assert!(
            used(f32::from_bits(e.to_bits() + 1)) > u64::from(budget) || e >= top * 0.9999,
            "{percent}%: scale {e} is not the largest that fits"
        );

        let bounds = tris.iter().fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let grid = SplitGrid::new(&bounds);
        let disagreeing = disagreeing_triangles(&tris, q, &boxes, &stages.ref_tris, &grid);
        let is_heavy = |t: usize| pieces[t] > SPLIT_INLINE_PIECES;
        let is_inline = |t: usize| (2..=SPLIT_INLINE_PIECES).contains(&pieces[t]);
        heavy += (0..tris.len()).filter(|&t| is_heavy(t)).count();
        inline += (0..tris.len()).filter(|&t| is_inline(t)).count();
        heavy_disagreeing += disagreeing.iter().filter(|&&t| is_heavy(t)).count();
        inline_disagreeing += disagreeing.iter().filter(|&&t| is_inline(t)).count();
        let agreeing = 1.0 - disagreeing.len() as f64 / tris.len() as f64;
        println!(
            "{} triangles at {percent}%: {} disagree with the CPU twin",
            tris.len(),
            disagreeing.len()
        );
        assert!(
            agreeing >= MIN_AGREEING,
            "{percent}%: {} of {} triangles disagree with the CPU twin, e.g. {:?}",
            disagreeing.len(),
            tris.len(),
            &disagreeing[..disagreeing.len().min(5)]
        );
    }
    // The deepest piece splitting was exercised.
    assert_eq!(
        most_pieces,
        MAX_SPLITS + 1,
        "no triangle got the most pieces"
    );
    // Both kernel paths split triangles, and each agrees with the twin on its own (a path that
    // is wrong for all its triangles fails here even where it splits few of all triangles).
    println!("split by triangle: {inline} ({inline_disagreeing} disagree); by reference: {heavy} ({heavy_disagreeing} disagree)");
    for (path, count, disagreeing) in [
        ("per triangle", inline, inline_disagreeing),
        ("per reference", heavy, heavy_disagreeing),
    ] {
        assert!(count >= 50, "only {count} triangles split {path}");
        assert!(
            disagreeing as f64 <= (1.0 - MIN_AGREEING) * count as f64,
            "split {path}: {disagreeing} of {count} triangles disagree with the CPU twin"
        );
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
        let geometry = Geometry::upload(gpu(), &scene).unwrap();
        let mut tree = Tree::empty(gpu()).unwrap();
        builder.build(gpu(), &geometry, &mut tree).unwrap();
        let bvh = tree.download(gpu()).unwrap();
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
        let hits = closest_hits(gpu(), &geometry, &tree, &plain).unwrap();
        assert_hits_match(&scene.triangles, &rays, &hits);
        // The GPU collapse of the GPU's own working tree equals the CPU twin's exactly: unique
        // triangles per leaf, in depth-first order of first occurrence. Leaves of up to 8
        // references are gathered in registers, larger ones with a stack: both (a costly
        // traversal step makes large leaves), and leaves of one reference.
        let mut largest_leaf = 0;
        for (ci, max_leaf_size) in [
            (sah.ci, sah.max_leaf_size),
            (sah.ci, 1),
            (sah.ci, 3),
            (8.0, 20),
        ] {
            builder.sah = SahParams {
                ci,
                max_leaf_size,
                ..sah
            };
            let stages = builder.build_stages(gpu(), &geometry).unwrap();
            let ref_tris = stages.ref_tris.as_deref().expect("pre-split references");
            assert_eq!(
                stages.bvh,
                stages
                    .working
                    .collapse(&CostModel::from(&builder.sah), Some(ref_tris)),
                "{}, Ci {ci}, max leaf size {max_leaf_size}: collapsed tree",
                scene.name
            );
            let leaves = stages.bvh.nodes.iter().filter(|n| n.is_leaf());
            largest_leaf = leaves.map(|n| n.prim_count()).fold(largest_leaf, u32::max);
        }
        assert!(
            largest_leaf > 8,
            "{}: no leaf gathered with the stack",
            scene.name
        );
        builder.sah = sah;
    }
}

/// β = 0 splits nothing: the GPU stage gives every triangle one reference with exactly its own
/// box (so the LBVH over the references is the LBVH over the triangles), and the CPU twin's
/// trbvh-split tree is its trbvh tree.
#[test]
fn zero_budget_splits_nothing() {
    let sah = SahParams::default();
    let scene = load_scene("field-10k").unwrap();
    let geometry = Geometry::upload(gpu(), &scene).unwrap();
    let stages = PreSplitter::new(gpu())
        .split_stages(gpu(), &geometry, 0)
        .unwrap();
    let n = scene.triangles.len() as u32;
    assert_eq!(stages.ref_tris, (0..n).collect::<Vec<_>>());
    for (b, t) in stages.boxes.iter().zip(&scene.triangles) {
        assert_eq!(Aabb::from(*b), t.bounds());
    }
    let settings = TreeletSettings {
        split_percent: 0,
        ..TreeletSettings::BALANCED
    };
    assert_eq!(
        build_trbvh_split_cpu(&scene.triangles, &settings, &sah),
        build_trbvh_cpu(&scene.triangles, &settings, &sah)
    );
}
