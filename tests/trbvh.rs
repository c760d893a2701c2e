//! Treelet restructuring (Karras & Aila 2013): the DP is optimal (against brute force over all
//! binary topologies, CPU and GPU), the GPU optimizer equals its CPU twin exactly, SAH never gets
//! worse than the input LBVH, every tree is valid, traced hits equal brute force, and repeated
//! builds are identical.

mod common;

use common::{assert_hits_match, gpu, random_soup, rng, scene_of, test_rays};
use glam::Vec3;
use rand::Rng;
use treelet::bvh::lbvh::build_lbvh_cpu;
use treelet::bvh::treelet::{
    build_trbvh_cpu, optimize_cpu, solve_treelet, surface_area, CostModel, TrbvhBuilder,
    TreeletLeaf, TreeletSettings,
};
use treelet::bvh::{sah_cost, validate, SahParams};
use treelet::scene::{load_scene, Triangle};
use treelet::trace::{closest_hits, GpuScene};

/// Every full binary tree over the leaf set `s` (bitmask), as its cost under `model`; each
/// unordered partition once, so 7 leaves give 10,395 topologies.
fn all_topology_costs(leaves: &[TreeletLeaf], s: u32, model: &CostModel) -> Vec<f32> {
    if s.count_ones() == 1 {
        return vec![leaves[s.trailing_zeros() as usize].cost];
    }
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(-f32::MAX));
    let mut prims = 0;
    for (i, l) in leaves.iter().enumerate() {
        if (s >> i) & 1 != 0 {
            lo = lo.min(l.min);
            hi = hi.max(l.max);
            prims += l.prims;
        }
    }
    let area = surface_area(lo, hi);
    let lowest = s & s.wrapping_neg();
    let mut costs = Vec::new();
    // P ranges over the proper subsets of s that contain its lowest leaf.
    let mut p = s;
    loop {
        p = (p - 1) & s;
        if p == 0 {
            break;
        }
        if p & lowest == 0 {
            continue;
        }
        for a in all_topology_costs(leaves, p, model) {
            for b in all_topology_costs(leaves, s ^ p, model) {
                costs.push(model.combine(area, prims, a + b));
            }
        }
    }
    costs
}

fn random_leaves(m: usize, seed: u64, model: &CostModel) -> Vec<TreeletLeaf> {
    let mut r = rng(seed);
    (0..m)
        .map(|_| {
            let c = Vec3::new(r.random(), r.random(), r.random()) * 10.0;
            let e = Vec3::new(r.random(), r.random(), r.random()) * 3.0;
            let prims = r.random_range(1..4);
            let area = surface_area(c, c + e);
            TreeletLeaf {
                min: c,
                max: c + e,
                cost: model.ct * area * prims as f32,
                prims,
            }
        })
        .collect()
}

fn close(a: f32, b: f32) -> bool {
    (a - b).abs() <= 1e-5 * a.abs().max(b.abs()).max(1e-6)
}

#[test]
fn dp_equals_brute_force_on_cpu() {
    for max_leaf_size in [1, 8] {
        let model = CostModel {
            ci: 1.2,
            ct: 1.0,
            max_leaf_size,
        };
        for m in [5usize, 6, 7] {
            for seed in 0..20 {
                let leaves = random_leaves(m, seed * 31 + m as u64, &model);
                let all = all_topology_costs(&leaves, (1 << m) - 1, &model);
                let expected_count = [1usize, 1, 1, 3, 15, 105, 945, 10395][m];
                assert_eq!(all.len(), expected_count, "{m} leaves");
                let brute = all.iter().copied().fold(f32::MAX, f32::min);
                let dp = solve_treelet(&leaves, &model);
                let got = dp.cost[dp.full() as usize];
                assert!(
                    close(got, brute),
                    "m={m} seed={seed}: DP {got} vs brute force {brute}"
                );
            }
        }
    }
}

#[test]
fn dp_equals_brute_force_on_gpu() {
    // A scene of m triangles is one treelet of m leaves at the root (γ = m), so after one round
    // the root's cost is the DP optimum computed by the kernel.
    let sah = SahParams::default();
    let mut builder = TrbvhBuilder::new(gpu(), TreeletSettings::BALANCED, sah).unwrap();
    for max_leaf_size in [1, 8] {
        let model = CostModel {
            ci: sah.ci,
            ct: sah.ct,
            max_leaf_size,
        };
        for m in [5u32, 6, 7] {
            for seed in 0..4 {
                let tris = random_soup(m as usize, 100 + seed * 7 + u64::from(m));
                builder.settings = TreeletSettings {
                    treelet_size: m,
                    rounds: 1,
                    split_percent: 0,
                };
                builder.sah = SahParams {
                    max_leaf_size,
                    ..sah
                };
                let scene = scene_of(tris.clone());
                let mut gpu_scene = GpuScene::upload_geometry(gpu(), &scene).unwrap();
                let stages = builder.build_stages(gpu(), &mut gpu_scene).unwrap();
                let leaves: Vec<TreeletLeaf> = tris
                    .iter()
                    .map(|t| {
                        let b = t.bounds();
                        TreeletLeaf {
                            min: b.min,
                            max: b.max,
                            cost: model.ct * surface_area(b.min, b.max),
                            prims: 1,
                        }
                    })
                    .collect();
                let brute = all_topology_costs(&leaves, (1 << m) - 1, &model)
                    .into_iter()
                    .fold(f32::MAX, f32::min);
                let got = stages.working.costs[0];
                assert!(
                    close(got, brute),
                    "m={m} seed={seed}: GPU root cost {got} vs brute force {brute}"
                );
            }
        }
    }
}

fn check_gpu_equals_cpu(
    builder: &mut TrbvhBuilder,
    triangles: Vec<Triangle>,
    settings: TreeletSettings,
) {
    check_gpu_equals_cpu_with(builder, triangles, settings, SahParams::default());
}

fn check_gpu_equals_cpu_with(
    builder: &mut TrbvhBuilder,
    triangles: Vec<Triangle>,
    settings: TreeletSettings,
    sah: SahParams,
) {
    builder.sah = sah;
    let scene = scene_of(triangles);
    let mut gpu_scene = GpuScene::upload_geometry(gpu(), &scene).unwrap();
    builder.settings = settings;
    let stages = builder.build_stages(gpu(), &mut gpu_scene).unwrap();
    let cpu = optimize_cpu(&scene.triangles, &settings, &sah);
    let w = &stages.working;
    assert_eq!(
        bytemuck::cast_slice::<_, u8>(&w.nodes),
        bytemuck::cast_slice::<_, u8>(&cpu.nodes),
        "working nodes (topology and bounds)"
    );
    assert_eq!(w.parents[1..], cpu.parents[1..], "parent links");
    assert_eq!(w.prim_counts, cpu.prim_counts, "primitive counts");
    let bits = |v: &[f32]| v.iter().map(|c| c.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&w.costs), bits(&cpu.costs), "costs");
    let expected = build_trbvh_cpu(&scene.triangles, &settings, &sah);
    assert_eq!(stages.bvh, expected, "collapsed tree");
    validate(&stages.bvh, &scene.triangles).expect("valid TRBVH");
}

#[test]
fn gpu_optimizer_equals_cpu_twin() {
    let builder =
        &mut TrbvhBuilder::new(gpu(), TreeletSettings::BALANCED, SahParams::default()).unwrap();
    check_gpu_equals_cpu(builder, random_soup(3000, 41), TreeletSettings::BALANCED);
    check_gpu_equals_cpu(
        builder,
        load_scene("cornell").unwrap().triangles,
        TreeletSettings::BALANCED,
    );
    check_gpu_equals_cpu(
        builder,
        load_scene("field-10k").unwrap().triangles,
        TreeletSettings::FAST,
    );
    check_gpu_equals_cpu(
        builder,
        random_soup(2000, 42),
        TreeletSettings::HIGH_QUALITY,
    );
    check_gpu_equals_cpu_with(
        builder,
        random_soup(1500, 43),
        TreeletSettings {
            treelet_size: 7,
            rounds: 0,
            split_percent: 0,
        },
        SahParams {
            max_leaf_size: 4,
            ..SahParams::default()
        },
    );
}

#[test]
fn small_and_degenerate_inputs() {
    let builder =
        &mut TrbvhBuilder::new(gpu(), TreeletSettings::BALANCED, SahParams::default()).unwrap();
    for n in [1usize, 2, 3, 4, 9] {
        check_gpu_equals_cpu(builder, random_soup(n, n as u64), TreeletSettings::BALANCED);
    }
    let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
    check_gpu_equals_cpu(builder, vec![t; 500], TreeletSettings::BALANCED);
}

#[test]
fn sah_never_increases_and_hits_equal_brute_force() {
    let sah = SahParams::default();
    for scene in [
        load_scene("cornell").unwrap(),
        load_scene("field-10k").unwrap(),
        scene_of(random_soup(4000, 9)),
    ] {
        let lbvh = build_lbvh_cpu(&scene.triangles);
        let mut gpu_scene = GpuScene::upload_geometry(gpu(), &scene).unwrap();
        let mut builder = TrbvhBuilder::new(gpu(), TreeletSettings::BALANCED, sah).unwrap();
        builder.build(gpu(), &mut gpu_scene).unwrap();
        let bvh = gpu_scene.download_bvh(gpu()).unwrap();
        validate(&bvh, &scene.triangles).unwrap();
        let (before, after) = (sah_cost(&lbvh, &sah), sah_cost(&bvh, &sah));
        println!("{}: LBVH SAH {before:.2} -> TRBVH {after:.2}", scene.name);
        assert!(
            after <= before,
            "{}: SAH grew from {before} to {after}",
            scene.name
        );
        let rays = test_rays(&scene.triangles, 300, 23);
        let plain: Vec<_> = rays.iter().map(|(_, r)| *r).collect();
        let hits = closest_hits(gpu(), &gpu_scene, &plain).unwrap();
        assert_hits_match(&scene.triangles, &rays, &hits);
    }
}

#[test]
fn repeated_builds_are_identical_and_valid() {
    let sah = SahParams::default();
    let scene = scene_of(random_soup(20_000, 77));
    let expected = build_trbvh_cpu(&scene.triangles, &TreeletSettings::BALANCED, &sah);
    validate(&expected, &scene.triangles).unwrap();
    let mut gpu_scene = GpuScene::upload_geometry(gpu(), &scene).unwrap();
    let mut builder = TrbvhBuilder::new(gpu(), TreeletSettings::BALANCED, sah).unwrap();
    for round in 0..100 {
        builder.build(gpu(), &mut gpu_scene).unwrap();
        let bvh = gpu_scene.download_bvh(gpu()).unwrap();
        assert!(bvh == expected, "build {round} differs from the CPU twin");
    }
}

#[test]
fn bad_settings_are_errors() {
    let sah = SahParams::default();
    for settings in [
        TreeletSettings {
            treelet_size: 2,
            ..TreeletSettings::BALANCED
        },
        TreeletSettings {
            treelet_size: 9,
            ..TreeletSettings::BALANCED
        },
        TreeletSettings {
            rounds: 17,
            ..TreeletSettings::BALANCED
        },
    ] {
        assert!(
            TrbvhBuilder::new(gpu(), settings, sah).is_err(),
            "{settings:?} accepted"
        );
    }
    for max_leaf_size in [0, 33] {
        let sah = SahParams {
            max_leaf_size,
            ..sah
        };
        assert!(
            TrbvhBuilder::new(gpu(), TreeletSettings::BALANCED, sah).is_err(),
            "max leaf {max_leaf_size} accepted"
        );
    }
}
