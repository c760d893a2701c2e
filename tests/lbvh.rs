//! GPU LBVH (Karras 2012): every stage against its CPU twin — integer stages exactly from the
//! GPU's own inputs, float stages within stated tolerances — adversarial inputs build valid trees,
//! repeated builds are identical (memory-ordering stress of the bottom-up pass), and rays traced
//! through the GPU-built tree equal brute force.

mod common;

use common::{assert_hits_match, gpu, gpu_with_climb_width, random_soup, rng, scene_of, test_rays};
use glam::Vec3;
use rand::Rng;
use treelet::bvh::lbvh::{
    assemble_lbvh_cpu, build_lbvh_from_boxes_cpu, centroid_bounds_cpu, hierarchy_cpu,
    morton_keys_cpu, prim_boxes_cpu, KeyWidth, LbvhBuilder, LBVH_KEY_BITS, MORTON_BITS,
    TRBVH_KEY_BITS,
};
use treelet::bvh::{sah_cost, validate, Bvh, SahParams};
use treelet::device::{Geometry, Tree};
use treelet::gpu::{GpuContext, CLIMB_WIDTHS};
use treelet::scene::{load_scene, Triangle};
use treelet::sort::packs_indices;
use treelet::trace::closest_hits;

/// The grid cell (x, y, z) of a key of the high `key_bits` bits of a full Morton key (whose bit
/// 3k+2 holds x's bit k, 3k+1 y's, 3k z's), with the dropped bits zero.
fn morton_cell(key: u64, key_bits: u32) -> [i64; 3] {
    let full = key << (MORTON_BITS - key_bits);
    let mut cell = [0i64; 3];
    for k in 0..(MORTON_BITS / 3) as usize {
        for (axis, c) in cell.iter_mut().enumerate() {
            *c |= (((full >> (3 * k + 2 - axis)) & 1) as i64) << k;
        }
    }
    cell
}

/// The cell size of each axis in keys of `key_bits` bits (in units of the full key's cells).
fn morton_cell_size(key_bits: u32) -> [i64; 3] {
    morton_cell(u64::MAX >> (64 - key_bits), key_bits).map(|c| c & -c)
}

/// Below this many primitives one key moving a cell can reorder much of the tree, so whole-tree
/// quality is compared with the CPU twin's only from here up.
const SAH_COMPARISON_MIN_PRIMS: usize = 1000;

/// Nor with keys of fewer bits than this (10 per axis): in a grid of a few cells per axis, a key
/// moving one cell moves its primitive across a large part of the scene (an H200's keys gave
/// field-10k at 7 bits an SAH of 38.01 against the CPU keys' 38.74). The stages are still
/// compared exactly from the GPU's own keys at every width.
const SAH_COMPARISON_MIN_KEY_BITS: u32 = 30;

/// The GPU tree's SAH is within 0.5 % of the CPU twin's (which builds from its own keys of
/// `key_bits`).
fn assert_sah_close_to_cpu_twin(bvh: &Bvh, triangles: &[Triangle], key_bits: u32) {
    if triangles.len() < SAH_COMPARISON_MIN_PRIMS || key_bits < SAH_COMPARISON_MIN_KEY_BITS {
        return;
    }
    let sah = SahParams::default();
    let (got, want) = (
        sah_cost(bvh, &sah),
        sah_cost(
            &build_lbvh_from_boxes_cpu(&prim_boxes_cpu(triangles), key_bits).0,
            &sah,
        ),
    );
    assert!(
        (got - want).abs() <= 0.005 * want,
        "SAH {got} vs CPU twin {want} ({key_bits}-bit keys)"
    );
}

/// Builds on the GPU with every stage read back and checks each against its CPU twin:
/// - centroid bounds: exactly (only min, max, one add and a halving, all correctly rounded);
/// - Morton keys: each within one grid cell per axis of the CPU key (the grid scale is a
///   division, which GPUs may round differently from the CPU), at the builder's key width;
/// - radix sort: the CPU sort of the GPU's keys gives the GPU's sorted keys and values exactly;
/// - hierarchy: Karras's top-down emission on the CPU from the GPU's sorted keys gives the
///   parents the GPU's bottom-up climb found, exactly;
/// - bounds: the CPU assembly from that hierarchy and the GPU's order gives the GPU's nodes bit
///   for bit (children, and boxes: unions are min/max, exact on every device);
/// - the whole tree: valid, and its SAH within 0.5 % of the CPU twin's.
///
/// At the `lbvh` builder's own key width (`KeyWidth::LBVH`, which depends on the count).
fn check_stages_against_cpu_twins(triangles: Vec<Triangle>) {
    check_stages_on(gpu(), triangles, None);
}

fn check_stages_with_key_bits(triangles: Vec<Triangle>, key_bits: u32) {
    check_stages_on(gpu(), triangles, Some(key_bits));
}

/// With keys of `key_bits` bits at every count, or, for `None`, the builder's default width.
fn check_stages_on(ctx: &GpuContext, triangles: Vec<Triangle>, key_bits: Option<u32>) {
    let scene = scene_of(triangles);
    let tris = &scene.triangles;
    let geometry = Geometry::upload(ctx, &scene).unwrap();
    let mut builder = match key_bits {
        Some(bits) => LbvhBuilder::new(ctx).with_key_bits(bits).unwrap(),
        None => LbvhBuilder::new(ctx),
    };
    let key_bits = key_bits.unwrap_or(KeyWidth::LBVH.bits(tris.len() as u32));
    let stages = builder.build_stages(ctx, &geometry).unwrap();

    let boxes = prim_boxes_cpu(tris);
    let bounds = centroid_bounds_cpu(&boxes);
    assert_eq!(stages.centroid_bounds, bounds, "centroid bounds");
    let cpu_keys = morton_keys_cpu(&boxes, &bounds, key_bits);
    let size = morton_cell_size(key_bits);
    for (i, (&g, &c)) in stages.keys.iter().zip(&cpu_keys).enumerate() {
        assert!(
            g >> key_bits == 0,
            "key {g:#x} of primitive {i} wider than {key_bits} bits"
        );
        let (gc, cc) = (morton_cell(g, key_bits), morton_cell(c, key_bits));
        assert!(
            (0..3).all(|a| (gc[a] - cc[a]).abs() <= size[a]),
            "morton key of primitive {i}: GPU cell {gc:?}, CPU cell {cc:?} ({key_bits} bits)"
        );
    }
    let mut pairs: Vec<(u64, u32)> = stages.keys.iter().copied().zip(0..).collect();
    pairs.sort_unstable();
    let (sorted_keys, sorted_prims): (Vec<u64>, Vec<u32>) = pairs.into_iter().unzip();
    assert_eq!(stages.sorted_keys, sorted_keys, "sorted keys");
    assert_eq!(stages.sorted_prims, sorted_prims, "sorted values");
    let hierarchy = hierarchy_cpu(&stages.sorted_keys);
    if tris.len() > 1 {
        assert_eq!(
            &stages.parents[1..],
            &hierarchy.parents[1..],
            "parent links"
        );
    }
    let expected = assemble_lbvh_cpu(&boxes, &hierarchy, &stages.sorted_prims);
    assert_eq!(
        bytemuck::cast_slice::<_, u8>(&stages.bvh.nodes),
        bytemuck::cast_slice::<_, u8>(&expected.nodes),
        "nodes (children and bit-identical bounds)"
    );
    assert_eq!(stages.bvh.prim_indices, stages.sorted_prims);
    validate(&stages.bvh, tris).expect("valid LBVH");
    assert_sah_close_to_cpu_twin(&stages.bvh, tris, key_bits);
}

#[test]
fn stages_equal_cpu_twins_on_random_soup() {
    check_stages_against_cpu_twins(random_soup(5000, 11));
}

#[test]
fn stages_equal_cpu_twins_on_scenes() {
    check_stages_against_cpu_twins(load_scene("cornell").unwrap().triangles);
    check_stages_against_cpu_twins(load_scene("field-10k").unwrap().triangles);
}

/// Past 2^20 primitives `lbvh` narrows its keys (43 bits up to 2^21) so that the sort still
/// moves each index with its key: every stage still equals its twin at that width.
#[test]
fn stages_equal_cpu_twins_past_a_million_primitives() {
    let field = load_scene("field:707").unwrap().triangles;
    assert!(field.len() > 1 << 20 && field.len() <= 1 << 21);
    assert_eq!(KeyWidth::LBVH.bits(field.len() as u32), 43);
    check_stages_against_cpu_twins(field);
}

/// The climb builds the same hierarchy and bit-identical boxes at every workgroup width (the
/// software driver runs 8 by default, GPUs 64), on sizes that leave a partial last workgroup.
#[test]
fn stages_equal_cpu_twins_at_every_climb_width() {
    for width in CLIMB_WIDTHS {
        let ctx = gpu_with_climb_width(width);
        check_stages_on(&ctx, random_soup(3001, 12), None);
        check_stages_on(&ctx, load_scene("cornell").unwrap().triangles, None);
    }
}

/// Narrower keys (the treelet builders' 32 bits, and odd widths that split an axis's bits) keep
/// every stage equal to its twin at that width.
#[test]
fn stages_equal_cpu_twins_at_other_key_widths() {
    let field = load_scene("field-10k").unwrap().triangles;
    for key_bits in [TRBVH_KEY_BITS, 31, 7, 1] {
        check_stages_with_key_bits(field.clone(), key_bits);
        check_stages_with_key_bits(random_soup(3000, u64::from(key_bits)), key_bits);
    }
}

/// Keys whose bits leave no room for the indices (all 48 bits past 2^16 primitives): the Morton
/// kernel writes the indices apart and the sort moves them beside the keys, and every stage
/// still equals its twin.
#[test]
fn stages_equal_cpu_twins_with_the_indices_apart() {
    let soup = random_soup(70_000, 48);
    assert!(!packs_indices(MORTON_BITS, soup.len() as u32));
    check_stages_with_key_bits(soup, MORTON_BITS);
}

#[test]
fn key_widths_out_of_range_are_errors() {
    for key_bits in [0, MORTON_BITS + 1] {
        assert!(LbvhBuilder::new(gpu()).with_key_bits(key_bits).is_err());
    }
}

#[test]
fn sizes_that_are_not_workgroup_multiples() {
    let mut r = rng(5);
    for n in [1usize, 2, 3, 63, 65, 257, 1023, 1025] {
        check_stages_against_cpu_twins(random_soup(n, n as u64));
    }
    for _ in 0..3 {
        let n = r.random_range(1000..20000);
        check_stages_against_cpu_twins(random_soup(n, n as u64));
    }
}

#[test]
fn all_centroids_identical() {
    let t = Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y, 0);
    check_stages_against_cpu_twins(vec![t; 3000]);
}

#[test]
fn two_clusters_far_apart() {
    let mut tris = random_soup(2000, 1);
    let far: Vec<Triangle> = random_soup(2000, 2)
        .into_iter()
        .map(|t| {
            let [a, b, c] = t.vertices();
            let o = Vec3::splat(1e5);
            Triangle::new(a + o, b + o, c + o, 0)
        })
        .collect();
    tris.extend(far);
    check_stages_against_cpu_twins(tris);
}

#[test]
fn coordinates_spanning_many_magnitudes() {
    let mut r = rng(3);
    let tris = (0..4000)
        .map(|_| {
            let scale = 10f32.powf(r.random_range(-3.0..6.0));
            let c = Vec3::new(r.random(), r.random(), r.random()) * scale;
            let s = scale * 1e-3;
            Triangle::new(c, c + Vec3::X * s, c + Vec3::Y * s, 0)
        })
        .collect();
    check_stages_against_cpu_twins(tris);
}

#[test]
fn degenerate_triangles() {
    let mut tris = random_soup(1000, 4);
    for (i, t) in tris.iter_mut().enumerate().step_by(3) {
        // Points and segments: zero area.
        let [a, b, _] = t.vertices();
        *t = if i % 2 == 0 {
            Triangle::new(a, a, a, 0)
        } else {
            Triangle::new(a, b, (a + b) * 0.5, 0)
        };
    }
    check_stages_against_cpu_twins(tris);
}

#[test]
fn zero_triangles_is_a_clear_error() {
    let scene = scene_of(Vec::new());
    let err = Geometry::upload(gpu(), &scene).err().expect("error");
    assert!(err.to_string().contains("no usable triangles"), "{err}");
}

/// Memory-ordering stress: the bottom-up pass runs across many workgroups with only relaxed
/// atomics and barriers between them; every one of 200 builds must give the identical valid tree
/// (the device's own first build: the same kernels on the same inputs are deterministic).
#[test]
fn repeated_builds_are_identical_and_valid() {
    let scene = scene_of(random_soup(100_000, 21));
    let geometry = Geometry::upload(gpu(), &scene).unwrap();
    let mut tree = Tree::empty(gpu()).unwrap();
    let mut builder = LbvhBuilder::new(gpu());
    builder.build(gpu(), &geometry, &mut tree).unwrap();
    let first = tree.download(gpu()).unwrap();
    validate(&first, &scene.triangles).unwrap();
    assert_sah_close_to_cpu_twin(&first, &scene.triangles, LBVH_KEY_BITS);
    for round in 1..200 {
        builder.build(gpu(), &geometry, &mut tree).unwrap();
        let bvh = tree.download(gpu()).unwrap();
        assert!(bvh == first, "build {round} differs from the first");
    }
}

#[test]
fn traced_hits_equal_brute_force() {
    for scene in [
        load_scene("cornell").unwrap(),
        load_scene("field-10k").unwrap(),
        scene_of(random_soup(3000, 8)),
    ] {
        let geometry = Geometry::upload(gpu(), &scene).unwrap();
        let mut tree = Tree::empty(gpu()).unwrap();
        LbvhBuilder::new(gpu())
            .build(gpu(), &geometry, &mut tree)
            .unwrap();
        let rays = test_rays(&scene.triangles, 300, 17);
        let plain: Vec<_> = rays.iter().map(|(_, r)| *r).collect();
        let hits = closest_hits(gpu(), &geometry, &tree, &plain).unwrap();
        assert_hits_match(&scene.triangles, &rays, &hits);
    }
}
