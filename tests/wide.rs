//! The compressed wide BVH (Ylitie, Karras & Laine 2017): the GPU conversion makes the same tree
//! as its CPU twin from the same binary tree, for every builder and every level schedule; wide
//! trees pass the validator (every reference once, slot boxes conservative), and the validator
//! catches broken ones; closest and any hits through the wide layout equal brute force; the
//! layout takes at most 0.7× the binary tree's bytes; files round-trip; misuse is an error. Both
//! collapses (greedy, the default, and SAH-optimal) are checked; the optimal one makes fewer
//! nodes of a lower wide SAH, and a tree made on the CPU traces the same hits once uploaded. The
//! path tracer follows the same paths through both layouts of a deep scene (its ray count and
//! image brightness). Small versions of the stress scenes convert and trace as the others do.
//! Counting the traversal steps leaves the trace as it was; the wide layout takes far fewer. A tree deeper than a traversal's stack is an error, not a wrong hit.

mod common;

use common::{
    assert_hits_match, convert_wide, gpu, missing_shared_scene, oracle_hits, random_soup,
    record_update, scene_of, test_rays,
};
use glam::Vec3;
use treelet::bvh::treelet::TreeletSettings;
use treelet::bvh::wide::{
    gather_triangles, max_wide_nodes, validate_wide, validate_wide_with_references, wide_sah_costs,
    Layout, Slot, WideBvh, WideCollapse, WideConverter, FINISH_POOL, WIDTH,
};
use treelet::bvh::{
    build_sweep_sah, read_wide_bvh, validate, write_wide_bvh, Builder, Bvh, BvhNode, SahParams,
    TreeFingerprint, TreeUpdater, UpdateMode, ValidationError, WordsHasher, DEFAULT_SPLIT_PERCENT,
};
use treelet::device::{Geometry, Tree, WideTree};
use treelet::geometry::{Aabb, Hit, Ray};
use treelet::gpu::read_buffer;
use treelet::scene::{
    grass_blades, hairball, load_scene, stacked_duplicates, teapot_in_stadium, Scene, Triangle,
};
use treelet::trace::{
    any_hits_wide, closest_hits, closest_hits_wide, closest_hits_with_steps, PathTracer,
    RenderSettings,
};
use treelet::Error;

/// The tree as a sequence independent of node and reference-block numbering: each node's frame,
/// counts and quantized boxes, then per slot its references or its subtree, depth first.
fn canonical(wide: &WideBvh) -> Vec<u32> {
    let mut out = Vec::new();
    let mut stack = vec![0u32];
    while let Some(index) = stack.pop() {
        let node = &wide.nodes[index as usize];
        out.extend(node.origin);
        out.push(node.exponents);
        out.extend(node.leaf_counts);
        out.extend(node.quantized.iter().flatten());
        let mut children = Vec::new();
        for slot in 0..WIDTH {
            match node.slot(slot) {
                Slot::Empty => {}
                Slot::Internal(child) => children.push(child),
                Slot::Leaf { first, count } => out.extend_from_slice(
                    &wide.prim_indices[first as usize..(first + count) as usize],
                ),
            }
        }
        stack.extend(children.iter().rev());
    }
    out
}

fn split_builder() -> Builder {
    Builder::TrbvhSplit(TreeletSettings {
        split_percent: DEFAULT_SPLIT_PERCENT,
        ..TreeletSettings::BALANCED
    })
}

/// How the GPU conversion spreads a tree's levels over its dispatches (None: the defaults).
#[derive(Clone, Copy, Debug, Default)]
struct Spread {
    level_dispatches: Option<u32>,
    finish_pool: Option<u32>,
}

impl Spread {
    fn levels(dispatches: u32) -> Self {
        Self {
            level_dispatches: Some(dispatches),
            ..Self::default()
        }
    }
}

/// Builds `scene` with `builder` and converts it by `collapse`, spread as `spread` says.
fn build_wide(
    scene: &Scene,
    builder: Builder,
    collapse: WideCollapse,
    spread: Spread,
) -> (Geometry, Tree) {
    let geometry = Geometry::upload(gpu(), scene).unwrap();
    let mut tree = Tree::empty(gpu()).unwrap();
    let mut updater =
        TreeUpdater::new(gpu(), UpdateMode::Rebuild(builder), &SahParams::default()).unwrap();
    updater.set_layout(gpu(), Layout::Wide);
    let converter = updater.converter_mut().unwrap();
    converter.set_level_dispatches(spread.level_dispatches);
    converter.set_finish_pool(spread.finish_pool).unwrap();
    converter.set_collapse(collapse);
    record_update(&mut updater, &geometry, &scene.triangles, &mut tree).unwrap();
    (geometry, tree)
}

fn check_conversion(
    scene: &Scene,
    builder: Builder,
    collapse: WideCollapse,
    spread: Spread,
) -> WideBvh {
    let (_, tree) = build_wide(scene, builder, collapse, spread);
    let binary = tree.download(gpu()).unwrap();
    let gpu_wide = tree.wide.as_ref().unwrap().download(gpu()).unwrap();
    let cpu_wide = match collapse {
        WideCollapse::Optimal => WideBvh::from_binary_optimal(&binary, &SahParams::default()),
        WideCollapse::Greedy => WideBvh::from_binary(&binary),
    }
    .unwrap();
    let who = format!(
        "{} on {} ({}, {spread:?})",
        builder.label(),
        scene.name,
        collapse.name()
    );
    assert_eq!(
        gpu_wide.nodes.len(),
        cpu_wide.nodes.len(),
        "{who}: node count"
    );
    assert_eq!(
        gpu_wide.prim_indices.len(),
        binary.prim_indices.len(),
        "{who}"
    );
    assert!(
        canonical(&gpu_wide) == canonical(&cpu_wide),
        "{who}: the GPU conversion differs from its CPU twin"
    );
    let copies: Vec<Triangle> = read_buffer(
        gpu(),
        &tree.wide.as_ref().unwrap().triangles,
        gpu_wide.prim_indices.len(),
    )
    .unwrap();
    assert!(
        copies == gather_triangles(&scene.triangles, &gpu_wide.prim_indices),
        "{who}: the references' triangles"
    );
    let validation = if builder.duplicates_references() {
        validate_wide_with_references(&gpu_wide, &scene.triangles)
    } else {
        validate_wide(&gpu_wide, &scene.triangles)
    };
    validation.unwrap_or_else(|e| panic!("{who}: invalid wide tree: {e}"));
    gpu_wide
}

#[test]
fn gpu_conversion_equals_cpu_twin_for_every_builder() {
    let scenes = [
        scene_of(random_soup(3000, 11)),
        load_scene("cornell").unwrap(),
        load_scene("field-10k").unwrap(),
        scene_of(random_soup(1, 3)),
    ];
    for scene in &scenes {
        for builder in [
            Builder::Lbvh,
            Builder::Trbvh(TreeletSettings::BALANCED),
            split_builder(),
            Builder::Sweep,
        ] {
            for &collapse in WideCollapse::ALL {
                check_conversion(scene, builder, collapse, Spread::default());
            }
        }
    }
}

/// Every split of the levels between indirect dispatches and the finish gives the same tree: all
/// levels below the root in the finish (0), the root's dispatch alone (1, 2) or followed by level
/// dispatches (3), and more dispatches than levels; and so does a finish whose pools of subtree
/// roots fill (1 and 8 roots, the walks going on with what the pool has no room for). A pool of
/// no roots, or of more than the finish holds, is refused.
#[test]
fn every_level_schedule_gives_the_same_tree() {
    let scene = load_scene("field-10k").unwrap();
    let builder = Builder::Trbvh(TreeletSettings::BALANCED);
    let spreads =
        [0, 1, 2, 3, 32]
            .map(Spread::levels)
            .into_iter()
            .chain([(0, 1), (0, 8), (3, 8)].map(|(dispatches, roots)| Spread {
                finish_pool: Some(roots),
                ..Spread::levels(dispatches)
            }));
    for &collapse in WideCollapse::ALL {
        let reference = canonical(&check_conversion(
            &scene,
            builder,
            collapse,
            Spread::default(),
        ));
        for spread in spreads.clone() {
            let wide = check_conversion(&scene, builder, collapse, spread);
            assert!(
                canonical(&wide) == reference,
                "{} collapse, {spread:?}",
                collapse.name()
            );
        }
    }
    let mut converter = WideConverter::new(gpu(), &SahParams::default());
    for roots in [0, FINISH_POOL + 1] {
        let refused = converter.set_finish_pool(Some(roots));
        assert!(
            matches!(refused, Err(Error::InvalidArgument(_))),
            "{roots} roots: {refused:?}"
        );
    }
}

/// Any hit through the wide layout: found exactly when the closest hit (`oracle`) lies in the
/// ray's interval, and inside it.
fn assert_any_hits_match(
    name: &str,
    geometry: &Geometry,
    tree: &Tree,
    rays: &[Ray],
    oracle: &[Hit],
) {
    let any = any_hits_wide(gpu(), geometry, tree, rays).unwrap();
    for (i, (a, o)) in any.iter().zip(oracle).enumerate() {
        assert_eq!(a.is_hit(), o.is_hit(), "{name} ray {i}: any hit");
        if a.is_hit() {
            assert!(
                a.t >= rays[i].t_min && a.t <= rays[i].t_max,
                "{name} ray {i}"
            );
        }
    }
}

#[test]
fn wide_hits_equal_brute_force() {
    let scenes = [
        scene_of(random_soup(3000, 7)),
        load_scene("cornell").unwrap(),
        load_scene("field-10k").unwrap(),
    ];
    for (seed, scene) in scenes.iter().enumerate() {
        let rays = test_rays(&scene.triangles, 300, seed as u64 + 20);
        let plain: Vec<Ray> = rays.iter().map(|(_, r)| *r).collect();
        let oracle = oracle_hits(&scene.triangles, &rays);
        for (builder, collapse) in [
            (
                Builder::Trbvh(TreeletSettings::BALANCED),
                WideCollapse::Optimal,
            ),
            (
                Builder::Trbvh(TreeletSettings::BALANCED),
                WideCollapse::Greedy,
            ),
            (split_builder(), WideCollapse::Optimal),
        ] {
            let (geometry, tree) = build_wide(scene, builder, collapse, Spread::default());
            let hits = closest_hits_wide(gpu(), &geometry, &tree, &plain).unwrap();
            let ties = assert_hits_match(&scene.triangles, &rays, &hits);
            let binary = closest_hits(gpu(), &geometry, &tree, &plain).unwrap();
            let same_t = hits.iter().zip(&binary).filter(|(w, b)| w.t == b.t).count();
            assert_eq!(
                same_t,
                rays.len(),
                "{}: wide and binary distances",
                scene.name
            );
            assert_any_hits_match(&scene.name, &geometry, &tree, &plain, &oracle);
            println!("{} {}: {ties} ties", scene.name, builder.label());
        }
        // A CPU reference tree, uploaded and converted.
        let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
        let geometry = Geometry::upload(gpu(), scene).unwrap();
        let mut tree = Tree::upload(gpu(), &bvh).unwrap();
        for &collapse in WideCollapse::ALL {
            convert_wide(&geometry, &mut tree, collapse);
            let hits = closest_hits_wide(gpu(), &geometry, &tree, &plain).unwrap();
            assert_hits_match(&scene.triangles, &rays, &hits);
        }
    }
}

/// Small versions of the stress scenes (overlapping duplicates, thin grass blades, a hairball of
/// thin strands, a teapot in a stadium 500 times its size): every GPU builder's tree converts as
/// its CPU twin does into a valid wide tree, and both layouts trace the brute-force hits, closest
/// and any.
#[test]
fn stress_scenes_convert_like_the_cpu_twin_and_trace_brute_force_hits() {
    let scenes = [
        stacked_duplicates(6),
        grass_blades(2_000),
        hairball(100),
        teapot_in_stadium(2),
    ];
    for (seed, scene) in scenes.iter().enumerate() {
        let rays = test_rays(&scene.triangles, 150, seed as u64 + 40);
        let plain: Vec<Ray> = rays.iter().map(|(_, r)| *r).collect();
        let oracle = oracle_hits(&scene.triangles, &rays);
        for builder in [
            Builder::Lbvh,
            Builder::Trbvh(TreeletSettings::BALANCED),
            split_builder(),
        ] {
            check_conversion(scene, builder, WideCollapse::Greedy, Spread::default());
            let (geometry, tree) =
                build_wide(scene, builder, WideCollapse::Greedy, Spread::default());
            let who = format!("{} on {}", builder.label(), scene.name);
            let binary = closest_hits(gpu(), &geometry, &tree, &plain).unwrap();
            let ties = assert_hits_match(&scene.triangles, &rays, &binary);
            let wide = closest_hits_wide(gpu(), &geometry, &tree, &plain).unwrap();
            assert_hits_match(&scene.triangles, &rays, &wide);
            assert_any_hits_match(&who, &geometry, &tree, &plain, &oracle);
            println!("{who}: {} rays, {ties} ties", rays.len());
        }
    }
}

/// The SAH-optimal collapse makes fewer wide nodes than the greedy one from the same binary tree,
/// of a lower wide SAH; both trace the brute-force hits (closest and any), and so does the
/// optimal tree made on the CPU (`WideBvh::from_binary_optimal`) once uploaded.
#[test]
fn optimal_collapse_is_smaller_and_traces_brute_force_hits() {
    let params = SahParams::default();
    let builder = Builder::Trbvh(TreeletSettings::BALANCED);
    for (seed, scene) in [
        scene_of(random_soup(3000, 8)),
        load_scene("field-10k").unwrap(),
    ]
    .iter()
    .enumerate()
    {
        let (geometry, mut tree) =
            build_wide(scene, builder, WideCollapse::Optimal, Spread::default());
        let bvh = tree.download(gpu()).unwrap();
        let optimal = tree.wide.as_ref().unwrap().download(gpu()).unwrap();
        // The same binary tree, converted greedily (and traced as converted, below).
        convert_wide(&geometry, &mut tree, WideCollapse::Greedy);
        let greedy = tree.wide.as_ref().unwrap().download(gpu()).unwrap();
        assert!(
            optimal.nodes.len() < greedy.nodes.len(),
            "{}: {} optimal nodes, {} greedy",
            scene.name,
            optimal.nodes.len(),
            greedy.nodes.len()
        );
        let (greedy_sah, optimal_sah) = wide_sah_costs(&bvh, &params);
        assert!(optimal_sah < greedy_sah, "{}: SAH", scene.name);
        let rays = test_rays(&scene.triangles, 300, seed as u64 + 40);
        let plain: Vec<Ray> = rays.iter().map(|(_, r)| *r).collect();
        let oracle = oracle_hits(&scene.triangles, &rays);
        for wide in [
            None,
            Some(optimal),
            Some(WideBvh::from_binary_optimal(&bvh, &params).unwrap()),
        ] {
            if let Some(wide) = wide {
                tree.wide = Some(WideTree::upload(gpu(), &wide, &scene.triangles).unwrap());
                assert!(tree.wide.as_ref().unwrap().download(gpu()).unwrap() == wide);
            }
            let hits = closest_hits_wide(gpu(), &geometry, &tree, &plain).unwrap();
            assert_hits_match(&scene.triangles, &rays, &hits);
            assert_any_hits_match(&scene.name, &geometry, &tree, &plain, &oracle);
        }
    }
}

/// A balanced binary tree over `triangles` (a power of two of them) in their order, one reference
/// per leaf.
fn balanced_tree(triangles: &[Triangle]) -> Bvh {
    fn add(nodes: &mut Vec<BvhNode>, triangles: &[Triangle], first: u32, count: u32) {
        let bounds = triangles[first as usize..(first + count) as usize]
            .iter()
            .fold(Aabb::EMPTY, |b, t| b.union(t.bounds()));
        let index = nodes.len();
        nodes.push(BvhNode::leaf(bounds, first, 1));
        if count > 1 {
            let left = nodes.len() as u32;
            add(nodes, triangles, first, count / 2);
            let right = nodes.len() as u32;
            add(nodes, triangles, first + count / 2, count / 2);
            nodes[index] = BvhNode::internal(bounds, left, right);
        }
    }
    let mut nodes = Vec::new();
    add(&mut nodes, triangles, 0, triangles.len() as u32);
    Bvh {
        nodes,
        prim_indices: (0..triangles.len() as u32).collect(),
    }
}

/// A balanced tree of 2·8^k leaves converts greedily into the most wide nodes a tree of its size
/// can make (`max_wide_nodes`: 73 for 128 leaves, nodes of 8 children down to nodes over two
/// leaves, in k + 1 levels), and the GPU's node buffer, sized from the binary buffer, holds
/// exactly that many. The
/// optimal collapse's buffer is sized by its own bound (leaves − 1).
#[test]
fn largest_conversion_fits_the_node_buffer() {
    // Unit cells along x: subtrees of as many leaves have boxes of the same area, so the greedy
    // collapse opens them level by level.
    let cells = (0..128)
        .map(|i| {
            let x = i as f32;
            Triangle::new(
                Vec3::new(x, 0.0, 0.0),
                Vec3::new(x + 1.0, 0.0, 1.0),
                Vec3::new(x, 1.0, 1.0),
                0,
            )
        })
        .collect();
    let scene = scene_of(cells);
    let bvh = balanced_tree(&scene.triangles);
    validate(&bvh, &scene.triangles).unwrap();
    let geometry = Geometry::upload(gpu(), &scene).unwrap();
    let mut tree = Tree::upload(gpu(), &bvh).unwrap();
    convert_wide(&geometry, &mut tree, WideCollapse::Greedy);
    let wide_tree = tree.wide.as_ref().unwrap();
    assert_eq!(
        wide_tree.capacity,
        max_wide_nodes(128, WideCollapse::Greedy)
    );
    // Fails if the conversion ran out of room.
    let wide = wide_tree.download(gpu()).unwrap();
    assert_eq!(wide.nodes.len(), 73);
    // The root, 8 nodes, then 64 nodes over two leaves each.
    assert_eq!(wide.levels(), 3);
    validate_wide(&wide, &scene.triangles).unwrap();
    assert_eq!(
        canonical(&wide),
        canonical(&WideBvh::from_binary(&bvh).unwrap())
    );
    let mut tree = Tree::upload(gpu(), &bvh).unwrap();
    convert_wide(&geometry, &mut tree, WideCollapse::Optimal);
    let wide_tree = tree.wide.as_ref().unwrap();
    assert_eq!(wide_tree.capacity, 127);
    let wide = wide_tree.download(gpu()).unwrap();
    validate_wide(&wide, &scene.triangles).unwrap();
}

/// Wide nodes and references take at most 0.7× the bytes of the binary tree they come from.
#[test]
fn wide_layout_takes_less_memory() {
    let scene = load_scene("field-10k").unwrap();
    for builder in [Builder::Lbvh, Builder::Trbvh(TreeletSettings::BALANCED)] {
        for &collapse in WideCollapse::ALL {
            let (_, tree) = build_wide(&scene, builder, collapse, Spread::default());
            let binary = tree.download(gpu()).unwrap();
            let binary_bytes = binary.nodes.len() * 32 + binary.prim_indices.len() * 4;
            let wide = tree.wide.as_ref().unwrap().download(gpu()).unwrap();
            let ratio = wide.bytes() as f64 / binary_bytes as f64;
            let who = format!("{} {}", builder.label(), collapse.name());
            println!("{who}: wide/binary bytes {ratio:.3}");
            assert!(ratio <= 0.7, "{who}: {ratio}");
        }
    }
}

#[test]
fn validator_catches_broken_wide_trees() {
    let scene = scene_of(random_soup(500, 5));
    let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    let wide = WideBvh::from_binary(&bvh).unwrap();
    validate_wide(&wide, &scene.triangles).unwrap();
    assert!(wide.nodes.len() > 2, "a tree of several nodes");

    // A slot box shrunk by one quantum no longer contains what lies beneath it.
    let mut shrunk = wide.clone();
    let hi_x = &mut shrunk.nodes[0].quantized[3];
    let slot = (0..WIDTH)
        .find(|&s| (hi_x[s / 4] >> (8 * (s % 4))) & 0xff > 0)
        .unwrap();
    hi_x[slot / 4] -= 1 << (8 * (slot % 4));
    assert!(matches!(
        validate_wide(&shrunk, &scene.triangles),
        Err(ValidationError::SlotNotContaining { .. })
    ));

    // A reference dropped, a child pointer out of range, a bad exponent.
    let mut dropped = wide.clone();
    dropped.prim_indices.pop();
    assert!(validate_wide(&dropped, &scene.triangles).is_err());
    let mut dangling = wide.clone();
    let internal = dangling.nodes.iter().position(|n| n.imask() != 0).unwrap();
    dangling.nodes[internal].child_base = 1_000_000;
    assert!(matches!(
        validate_wide(&dangling, &scene.triangles),
        Err(ValidationError::ChildOutOfRange { .. })
    ));
    let mut frame = wide.clone();
    frame.nodes[0].exponents &= !0xff;
    assert!(matches!(
        validate_wide(&frame, &scene.triangles),
        Err(ValidationError::BadQuantizationFrame { node: 0 })
    ));
}

#[test]
fn wide_files_round_trip() {
    let scene = scene_of(random_soup(300, 9));
    let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    let wide = WideBvh::from_binary(&bvh).unwrap();
    let dir = std::env::temp_dir().join("treelet-wide-test");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("tree.cwbvh");
    write_wide_bvh(&path, &wide, 300).unwrap();
    assert_eq!(read_wide_bvh(&path).unwrap(), (wide, 300));
    // A binary-layout file is not a wide one, and a truncated file is refused.
    treelet::bvh::write_bvh(&path, &bvh, 300).unwrap();
    let e = read_wide_bvh(&path).unwrap_err().to_string();
    assert!(
        e.contains("not a treelet BVH file of the wide layout"),
        "{e}"
    );
    std::fs::write(&path, &b"TRLTCWB1\x05\0\0\0"[..]).unwrap();
    assert!(read_wide_bvh(&path).is_err());
}

#[test]
fn tracing_the_wide_layout_needs_a_conversion() {
    let scene = scene_of(random_soup(100, 1));
    let bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    let geometry = Geometry::upload(gpu(), &scene).unwrap();
    let tree = Tree::upload(gpu(), &bvh).unwrap();
    let settings = RenderSettings {
        width: 8,
        height: 8,
        layout: Layout::Wide,
        ..RenderSettings::default()
    };
    let mut tracer = PathTracer::new(gpu(), settings).unwrap();
    let e = tracer
        .trace(gpu(), &geometry, &tree, &scene.camera, scene.sky, 1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("not converted"), "{e}");
    let rays = [Ray::new(glam::Vec3::ZERO, glam::Vec3::X, 0.0, f32::MAX)];
    assert!(closest_hits_wide(gpu(), &geometry, &tree, &rays).is_err());
    // An uploaded wide tree must reference the triangles it is uploaded with.
    let wide = WideBvh::from_binary(&bvh).unwrap();
    let e = WideTree::upload(gpu(), &wide, &scene.triangles[..50])
        .err()
        .expect("references past the triangles refused")
        .to_string();
    assert!(e.contains("references triangle"), "{e}");
}

#[test]
fn leaves_too_large_for_the_layout_are_refused() {
    let scene = scene_of(random_soup(400, 2));
    let sah = SahParams {
        max_leaf_size: 300,
        ..SahParams::default()
    };
    let geometry = Geometry::upload(gpu(), &scene).unwrap();
    let mut tree = Tree::empty(gpu()).unwrap();
    let mut updater = TreeUpdater::new(gpu(), UpdateMode::Rebuild(Builder::Sweep), &sah).unwrap();
    updater.set_layout(gpu(), Layout::Wide);
    let e = record_update(&mut updater, &geometry, &scene.triangles, &mut tree)
        .unwrap_err()
        .to_string();
    assert!(e.contains("do not fit the wide layout"), "{e}");
    // The CPU twin refuses a leaf of more than 255 references too.
    let mut bvh = build_sweep_sah(&scene.triangles, &SahParams::default());
    bvh.nodes = vec![treelet::bvh::BvhNode::leaf(
        bvh.nodes[0].bounds(),
        0,
        bvh.prim_indices.len() as u32,
    )];
    assert!(WideBvh::from_binary(&bvh).is_err());
}

/// An updater's wide collapse applies to its conversions whether it is set before or after the
/// wide layout is chosen, and survives a switch to the binary layout and back.
#[test]
fn the_updater_keeps_its_wide_collapse() {
    let mut updater = TreeUpdater::new(
        gpu(),
        UpdateMode::Rebuild(Builder::Lbvh),
        &SahParams::default(),
    )
    .unwrap();
    updater.set_wide_collapse(WideCollapse::Optimal);
    updater.set_layout(gpu(), Layout::Wide);
    let collapse = |u: &mut TreeUpdater| u.converter_mut().unwrap().collapse();
    assert_eq!(collapse(&mut updater), WideCollapse::Optimal);
    updater.set_layout(gpu(), Layout::Binary);
    assert!(updater.converter_mut().is_none());
    updater.set_layout(gpu(), Layout::Wide);
    assert_eq!(collapse(&mut updater), WideCollapse::Optimal);
    updater.set_wide_collapse(WideCollapse::Greedy);
    assert_eq!(collapse(&mut updater), WideCollapse::Greedy);
}

/// The path tracer follows the same paths through both layouts of one tree on a deep interior
/// (crytek_sponza, trbvh): the same ray count and the same image. On an NVIDIA H200 a form of the
/// integrator that was right on lavapipe traced only 5 % of crytek_sponza's rays through the wide
/// layout (the paths ended early, the image came out dark), and the hit-level tests above passed:
/// this compares whole renders.
#[test]
fn both_layouts_trace_the_same_paths_on_a_deep_scene() {
    let scene = match load_scene("crytek_sponza") {
        Ok(scene) => scene,
        Err(e) => return missing_shared_scene(format!("crytek_sponza ({e})")),
    };
    let (geometry, tree) = build_wide(
        &scene,
        Builder::Trbvh(TreeletSettings::BALANCED),
        WideCollapse::Greedy,
        Spread::default(),
    );
    let render = |layout: Layout| {
        let settings = RenderSettings {
            width: 64,
            height: 48,
            max_depth: 4,
            exposure: 1.0,
            layout,
        };
        let mut tracer = PathTracer::new(gpu(), settings).unwrap();
        let stats = tracer
            .trace(gpu(), &geometry, &tree, &scene.camera, scene.sky, 4)
            .unwrap();
        let image = tracer.read_image(gpu()).unwrap();
        let mean = image
            .pixels()
            .map(|p| f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]))
            .sum::<f64>()
            / (3.0 * 255.0 * f64::from(image.width() * image.height()));
        (stats.rays, mean)
    };
    let (binary_rays, binary_mean) = render(Layout::Binary);
    let (wide_rays, wide_mean) = render(Layout::Wide);
    println!("crytek_sponza rays binary {binary_rays} wide {wide_rays}, mean {binary_mean:.4} / {wide_mean:.4}");
    // Every path takes at least its primary ray; hits through shared edges may pick the other,
    // equally close triangle and change a path, so the counts may differ by a few rays.
    assert!(binary_rays >= 64 * 48 * 4, "{binary_rays}");
    let rays_off = (wide_rays as f64 - binary_rays as f64).abs() / binary_rays as f64;
    assert!(
        rays_off <= 0.002,
        "rays: binary {binary_rays}, wide {wide_rays}"
    );
    let mean_off = (wide_mean - binary_mean).abs() / binary_mean;
    assert!(
        mean_off <= 0.01,
        "mean brightness: binary {binary_mean}, wide {wide_mean}"
    );
}

/// Counting the traversal steps changes neither the paths nor the image (the counting trace
/// traces the same rays to the same pixels; on a GPU within rounding), and the wide layout visits far fewer nodes than the
/// binary one, in paths and in ray queries (whose hits stay the brute-force ones).
#[test]
fn traversal_steps_are_counted_without_changing_the_trace() {
    // Exactly the same paths on a CPU device, whose compiler treats both pipelines alike.
    let exact = gpu().info.device_type == wgpu::DeviceType::Cpu;
    let scene = load_scene("field-10k").unwrap();
    let (geometry, tree) = build_wide(
        &scene,
        Builder::Trbvh(TreeletSettings::BALANCED),
        WideCollapse::Greedy,
        Spread::default(),
    );
    let mut path_steps = Vec::new();
    for layout in [Layout::Binary, Layout::Wide] {
        let settings = RenderSettings {
            width: 48,
            height: 32,
            max_depth: 4,
            exposure: 1.0,
            layout,
        };
        let mut tracer = PathTracer::new(gpu(), settings).unwrap();
        let trace = |tracer: &mut PathTracer| {
            tracer.reset();
            let stats = tracer
                .trace(gpu(), &geometry, &tree, &scene.camera, scene.sky, 2)
                .unwrap();
            (stats, tracer.read_image(gpu()).unwrap())
        };
        let (plain, plain_image) = trace(&mut tracer);
        tracer.set_count_steps(true);
        let (counted, counted_image) = trace(&mut tracer);
        assert_eq!(plain.steps, None);
        if exact {
            assert_eq!(counted.rays, plain.rays, "{layout:?}");
            assert!(
                counted_image == plain_image,
                "{layout:?}: the image changed"
            );
        } else {
            // A GPU compiler may contract the two pipelines' float operations differently.
            let off = |a: f64, b: f64| (a - b).abs() / b.max(1.0);
            assert!(
                off(counted.rays as f64, plain.rays as f64) <= 0.002,
                "{layout:?}"
            );
            let sum = |image: &image::RgbaImage| {
                image
                    .pixels()
                    .map(|p| f64::from(p[0]) + f64::from(p[1]) + f64::from(p[2]))
                    .sum::<f64>()
            };
            assert!(
                off(sum(&counted_image), sum(&plain_image)) <= 0.01,
                "{layout:?}"
            );
        }
        let steps = counted.steps.expect("counted");
        assert!(
            steps.nodes >= plain.rays / 2 && steps.triangles > 0,
            "{steps:?}"
        );
        println!("{layout:?}: {} rays, {steps:?}", counted.rays);
        path_steps.push(steps);
    }
    assert!(
        path_steps[1].nodes * 2 < path_steps[0].nodes,
        "{path_steps:?}"
    );

    let rays = test_rays(&scene.triangles, 200, 70);
    let plain: Vec<Ray> = rays.iter().map(|(_, r)| *r).collect();
    let mut query_nodes = Vec::new();
    for layout in [Layout::Binary, Layout::Wide] {
        let (hits, steps) =
            closest_hits_with_steps(gpu(), &geometry, &tree, &plain, layout).unwrap();
        assert_hits_match(&scene.triangles, &rays, &hits);
        assert_eq!(steps.len(), plain.len());
        query_nodes.push(steps.iter().map(|s| s.nodes).sum::<u64>());
    }
    assert!(query_nodes[1] * 2 < query_nodes[0], "{query_nodes:?}");
}

/// `wide` with its nodes and reference blocks numbered depth first (the conversion numbers them
/// level by level): the same tree, other `child_base` and `prim_base` words.
fn renumbered_depth_first(wide: &WideBvh) -> WideBvh {
    let mut nodes = vec![wide.nodes[0]; wide.nodes.len()];
    let mut prim_indices = Vec::with_capacity(wide.prim_indices.len());
    let mut next = 1u32;
    let mut stack = vec![(0u32, 0u32)];
    while let Some((old, new)) = stack.pop() {
        let mut node = wide.nodes[old as usize];
        let internal = (node.exponents >> 24).count_ones();
        let references: u32 = (0..WIDTH)
            .map(|slot| match node.slot(slot) {
                Slot::Leaf { count, .. } => count,
                _ => 0,
            })
            .sum();
        let first = node.prim_base as usize;
        node.prim_base = prim_indices.len() as u32;
        prim_indices.extend_from_slice(&wide.prim_indices[first..first + references as usize]);
        let old_base = node.child_base;
        node.child_base = next;
        next += internal;
        nodes[new as usize] = node;
        for k in (0..internal).rev() {
            stack.push((old_base + k, node.child_base + k));
        }
    }
    WideBvh {
        nodes,
        prim_indices,
    }
}

/// The tuning's tree fingerprint, hashed on the GPU, equals its CPU twin over the trees read back;
/// every level schedule of the conversion gives it; the wide layout's does not depend on how its
/// nodes and references are numbered; another tree, or another set of references, has another
/// one.
#[test]
fn the_gpu_fingerprint_equals_the_cpu_twin_and_ignores_wide_numbering() {
    let scene = load_scene("field-10k").unwrap();
    let builder = Builder::Trbvh(TreeletSettings::BALANCED);
    let mut hasher = WordsHasher::new(gpu()).unwrap();
    let (_, mut tree) = build_wide(&scene, builder, WideCollapse::Greedy, Spread::default());
    let fingerprint = TreeFingerprint::of(gpu(), &mut hasher, &tree).unwrap();
    let binary = tree.download(gpu()).unwrap();
    let wide = tree.wide.as_ref().unwrap().download(gpu()).unwrap();
    assert_eq!(
        fingerprint,
        TreeFingerprint::of_cpu(&binary, Some(&wide)),
        "GPU hash against the CPU twin"
    );
    for dispatches in [0, 1, 3] {
        let (_, other) = build_wide(
            &scene,
            builder,
            WideCollapse::Greedy,
            Spread::levels(dispatches),
        );
        assert_eq!(
            TreeFingerprint::of(gpu(), &mut hasher, &other).unwrap(),
            fingerprint,
            "{dispatches} level dispatches"
        );
    }
    let renumbered = renumbered_depth_first(&wide);
    validate_wide(&renumbered, &scene.triangles).unwrap();
    assert!(renumbered.nodes != wide.nodes && renumbered.prim_indices != wide.prim_indices);
    tree.wide = Some(WideTree::upload(gpu(), &renumbered, &scene.triangles).unwrap());
    assert_eq!(
        TreeFingerprint::of(gpu(), &mut hasher, &tree).unwrap(),
        fingerprint,
        "renumbered depth first"
    );
    // One reference twice and another missing: the same nodes, another tree.
    let mut duplicated = renumbered.clone();
    duplicated.prim_indices[0] = duplicated.prim_indices[1];
    tree.wide = Some(WideTree::upload(gpu(), &duplicated, &scene.triangles).unwrap());
    assert_ne!(
        TreeFingerprint::of(gpu(), &mut hasher, &tree).unwrap(),
        fingerprint,
        "a reference duplicated"
    );
    let (_, lbvh) = build_wide(
        &scene,
        Builder::Lbvh,
        WideCollapse::Greedy,
        Spread::default(),
    );
    let lbvh_fingerprint = TreeFingerprint::of(gpu(), &mut hasher, &lbvh).unwrap();
    assert_ne!(lbvh_fingerprint.binary, fingerprint.binary);
    assert_ne!(lbvh_fingerprint.wide, fingerprint.wide);
}

/// A comb of `levels` spine nodes over triangles in planes x = const that all cross the x axis:
/// spine node i has the rest of the spine and a pair of far triangles (x ≥ 1000) as children,
/// and the spine ends in the nearest triangle (x = 0, triangle 0). The spine's boxes are far
/// larger than the pairs', so the greedy collapse makes wide nodes of seven pairs and the rest of
/// the spine, all internal.
fn comb(levels: u32) -> (Vec<Triangle>, Bvh) {
    let plane = |x: f32| {
        Triangle::new(
            Vec3::new(x, -1.0, -1.0),
            Vec3::new(x, 2.0, -1.0),
            Vec3::new(x, -1.0, 2.0),
            0,
        )
    };
    let mut triangles = vec![plane(0.0)];
    for i in 0..levels {
        let x = 1000.0 + i as f32;
        triangles.extend([plane(x), plane(x + 0.5)]);
    }
    let bounds = |t: u32| triangles[t as usize].bounds();
    // Built from the end of the spine up, the root kept at node 0.
    let mut nodes: Vec<BvhNode> = Vec::new();
    let mut prim_indices = Vec::new();
    let mut leaf = |nodes: &mut Vec<BvhNode>, t: u32| {
        prim_indices.push(t);
        nodes.push(BvhNode::leaf(bounds(t), prim_indices.len() as u32 - 1, 1));
        nodes.len() as u32 - 1
    };
    // Reserve the root's slot so that it is node 0.
    nodes.push(BvhNode::leaf(Aabb::EMPTY, 0, 0));
    let mut rest = leaf(&mut nodes, 0);
    let mut rest_bounds = bounds(0);
    for i in (0..levels).rev() {
        let (a, b) = (1 + 2 * i, 2 + 2 * i);
        let left = leaf(&mut nodes, a);
        let right = leaf(&mut nodes, b);
        let pair_bounds = bounds(a).union(bounds(b));
        nodes.push(BvhNode::internal(pair_bounds, left, right));
        let pair = nodes.len() as u32 - 1;
        rest_bounds = rest_bounds.union(pair_bounds);
        if i == 0 {
            nodes[0] = BvhNode::internal(rest_bounds, rest, pair);
        } else {
            nodes.push(BvhNode::internal(rest_bounds, rest, pair));
            rest = nodes.len() as u32 - 1;
        }
    }
    (
        triangles,
        Bvh {
            nodes,
            prim_indices,
        },
    )
}

/// A ray along the comb's spine meets the rest of the spine first at every node, so both
/// traversals keep an entry per level (the far pair, or the group of seven pairs) on their
/// stacks: a layout whose stack holds the comb (64 binary entries, 32 wide groups) traces the
/// nearest triangle, and one whose stack it overflows reports the overflow as an error, not a
/// wrong hit (40 spine levels: both hold it; 200: the binary stack overflows, the wide one, 30
/// levels, holds it; 300: both overflow, 44 wide levels).
#[test]
fn traversal_stack_overflows_are_errors() {
    let ray = [Ray::new(Vec3::new(-1.0, 0.0, 0.0), Vec3::X, 0.0, f32::MAX)];
    for (levels, binary_overflows, wide_overflows) in
        [(40, false, false), (200, true, false), (300, true, true)]
    {
        let (triangles, bvh) = comb(levels);
        let scene = scene_of(triangles);
        let geometry = Geometry::upload(gpu(), &scene).unwrap();
        let mut tree = Tree::upload(gpu(), &bvh).unwrap();
        convert_wide(&geometry, &mut tree, WideCollapse::Greedy);
        let wide = tree.wide.as_ref().unwrap().download(gpu()).unwrap();
        validate_wide(&wide, &scene.triangles).unwrap();
        assert_eq!(
            wide.levels() > 33,
            wide_overflows,
            "{} wide levels",
            wide.levels()
        );
        for (layout, hits, overflows) in [
            (
                "binary",
                closest_hits(gpu(), &geometry, &tree, &ray),
                binary_overflows,
            ),
            (
                "wide",
                closest_hits_wide(gpu(), &geometry, &tree, &ray),
                wide_overflows,
            ),
        ] {
            match (hits, overflows) {
                (Ok(hits), false) => {
                    assert_eq!(hits[0].tri, 0, "{layout}, {levels} levels");
                    assert!((hits[0].t - 1.0).abs() < 1e-6, "{layout}: {}", hits[0].t);
                }
                (Err(e), true) => assert!(
                    e.to_string().contains("overflowed the traversal stack"),
                    "{layout}: {e}"
                ),
                (result, _) => panic!("{layout}, {levels} levels: {result:?}"),
            }
        }
    }
}
