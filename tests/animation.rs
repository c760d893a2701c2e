//! Animated scenes (`treelet::anim`): every animation kernel equals its CPU twin over a few
//! frames; the tree of every frame (GPU LBVH and TRBVH rebuilds) is valid; refits keep valid
//! boxes over frames (and their SAH cost is reported); the headless animation writes its PNGs; the
//! BART kitchen through the animation path equals `BartScene::evaluate`. Small configurations keep
//! the whole file fast on the software driver.

mod common;

use common::{gpu, gpu_with_climb_width, missing_shared_scene, record_update};
use treelet::anim::{load_animation, Animation, Explosion, Flag, RigidBodies};
use treelet::bvh::treelet::TreeletSettings;
use treelet::bvh::{sah_cost, validate, Builder, SahParams, TreeUpdater, UpdateMode};
use treelet::device::{Geometry, Tree};
use treelet::gpu::{GpuContext, ParamSlab, Recorder};
use treelet::scene::{shared_scenes_dir, BartScene, Triangle};

/// Small versions of the built-in animations.
fn small_animations() -> Vec<Box<dyn Animation>> {
    vec![
        Box::new(Flag::new(24, 16)),
        Box::new(RigidBodies::new(6, 1, 2)),
        Box::new(Explosion::new(3)),
    ]
}

/// Times to check: the start, a few frames in, and late frames (the explosion has burst by then).
fn check_times(animation: &dyn Animation) -> Vec<f32> {
    let range = animation.time_range();
    [0, 3, range.frames / 2, range.frames - 1]
        .iter()
        .map(|&f| range.frame_time(f))
        .collect()
}

/// The scene uploaded at its start time, as the viewer and the headless renderer do.
fn upload(animation: &dyn Animation) -> Geometry {
    let first = animation.scene_at(animation.time_range().start);
    Geometry::upload(gpu(), &first).unwrap()
}

/// Animates `geometry` to time `t` in a recording of its own, submitted.
fn animate(animation: &mut dyn Animation, t: f32, geometry: &Geometry) {
    let mut params = ParamSlab::new(gpu());
    let mut rec = Recorder::new(gpu(), &mut params, None);
    animation.animate(&mut rec, t, geometry).unwrap();
    rec.submit();
}

/// Updates `tree` to `geometry` with `updater`, in a recording of its own, submitted.
fn update(updater: &mut TreeUpdater, geometry: &Geometry, tree: &mut Tree) {
    record_update(updater, geometry, &[], tree).unwrap();
}

fn gpu_triangles(geometry: &Geometry) -> Vec<Triangle> {
    geometry.read_triangles(gpu()).unwrap()
}

fn scene_diagonal(triangles: &[Triangle]) -> f32 {
    triangles
        .iter()
        .fold(treelet::geometry::Aabb::EMPTY, |b, t| b.union(t.bounds()))
        .extent()
        .length()
}

#[test]
fn animation_kernels_equal_their_cpu_twins() {
    for mut animation in small_animations() {
        let scene = upload(animation.as_ref());
        let mut expected = Vec::new();
        for t in check_times(animation.as_ref()) {
            animate(animation.as_mut(), t, &scene);
            animation.evaluate(t, &mut expected);
            let got = gpu_triangles(&scene);
            assert_eq!(got.len(), expected.len());
            // GPU sin/cos/sqrt differ from the CPU's in the last bits.
            let tolerance = 1e-5 * scene_diagonal(&expected) + 1e-6;
            let mut worst = 0.0f32;
            for (i, (g, e)) in got.iter().zip(&expected).enumerate() {
                assert_eq!(
                    g.material,
                    e.material,
                    "{} t={t}: triangle {i}",
                    animation.name()
                );
                for (p, q) in g.vertices().iter().zip(e.vertices()) {
                    worst = worst.max(p.distance(q));
                }
            }
            assert!(
                worst <= tolerance,
                "{} t={t}: GPU and CPU twin differ by {worst} (tolerance {tolerance})",
                animation.name()
            );
        }
    }
}

#[test]
fn every_frame_tree_is_valid_for_gpu_builders() {
    let params = SahParams::default();
    for builder in [Builder::Lbvh, Builder::Trbvh(TreeletSettings::BALANCED)] {
        for mut animation in small_animations() {
            let scene = upload(animation.as_ref());
            let mut tree = Tree::empty(gpu()).unwrap();
            let mut updater =
                TreeUpdater::new(gpu(), UpdateMode::Rebuild(builder), &params).unwrap();
            for t in check_times(animation.as_ref()) {
                animate(animation.as_mut(), t, &scene);
                update(&mut updater, &scene, &mut tree);
                let bvh = tree.download(gpu()).unwrap();
                if let Err(e) = validate(&bvh, &gpu_triangles(&scene)) {
                    panic!("{} {} t={t}: {e}", builder.name(), animation.name());
                }
            }
        }
    }
}

#[test]
fn refits_keep_valid_boxes_and_lose_quality_when_the_mesh_bursts() {
    let params = SahParams::default();
    for mode in UpdateMode::REFITS.iter().copied() {
        let mut animation = Explosion::new(4);
        let geometry = upload(&animation);
        let (mut refitted, mut rebuilt) =
            (Tree::empty(gpu()).unwrap(), Tree::empty(gpu()).unwrap());
        let mut refit = TreeUpdater::new(gpu(), mode, &params).unwrap();
        let mut rebuild =
            TreeUpdater::new(gpu(), UpdateMode::Rebuild(mode.builder()), &params).unwrap();
        let mut costs = Vec::new();
        for t in check_times(&animation) {
            animate(&mut animation, t, &geometry);
            update(&mut refit, &geometry, &mut refitted);
            update(&mut rebuild, &geometry, &mut rebuilt);
            let triangles = gpu_triangles(&geometry);
            let bvh = refitted.download(gpu()).unwrap();
            if let Err(e) = validate(&bvh, &triangles) {
                panic!("{} t={t}: {e}", mode.name());
            }
            let refit_sah = sah_cost(&bvh, &params);
            let rebuild_sah = sah_cost(&rebuilt.download(gpu()).unwrap(), &params);
            eprintln!(
                "{} t={t:.2}: SAH refit {refit_sah:.2}, rebuild {rebuild_sah:.2}",
                mode.name()
            );
            costs.push((refit_sah, rebuild_sah));
        }
        let (first_refit, first_rebuild) = costs[0];
        assert!(
            (first_refit - first_rebuild).abs() <= 1e-3 * first_rebuild,
            "{}: the first frame's refit is its build",
            mode.name()
        );
        let (last_refit, last_rebuild) = costs[costs.len() - 1];
        assert!(
            last_refit > 1.5 * last_rebuild,
            "{}: after the burst the refitted tree should be far worse ({last_refit} vs {last_rebuild})",
            mode.name()
        );
    }
}

/// Refits climb the tree (`nodes_refit`) to the same bit-identical boxes at a GPU's workgroup
/// width (64) as at the software driver's (8), frame after frame.
#[test]
fn refits_are_the_same_at_every_climb_width() {
    let params = SahParams::default();
    let refit_frames = |ctx: &GpuContext| {
        let mut animation = Explosion::new(3);
        let geometry =
            Geometry::upload(ctx, &animation.scene_at(animation.time_range().start)).unwrap();
        let mut tree = Tree::empty(ctx).unwrap();
        let mut updater = TreeUpdater::new(ctx, UpdateMode::REFITS[0], &params).unwrap();
        let mut frames = Vec::new();
        for t in check_times(&animation) {
            let mut slab = ParamSlab::new(ctx);
            let mut rec = Recorder::new(ctx, &mut slab, None);
            animation.animate(&mut rec, t, &geometry).unwrap();
            updater.record(&mut rec, &geometry, &[], &mut tree).unwrap();
            rec.submit();
            let bvh = tree.download(ctx).unwrap();
            validate(&bvh, &geometry.read_triangles(ctx).unwrap()).unwrap();
            frames.push(bytemuck::cast_slice::<_, u8>(&bvh.nodes).to_vec());
        }
        frames
    };
    assert!(
        refit_frames(&gpu_with_climb_width(64)) == refit_frames(&gpu_with_climb_width(8)),
        "refits at climb widths 64 and 8 differ"
    );
}

#[cfg(feature = "app")]
#[test]
fn headless_animation_writes_one_png_per_frame() {
    let out = std::env::temp_dir().join(format!("treelet-anim-frames-{}", std::process::id()));
    std::fs::remove_dir_all(&out).ok();
    let output = common::run_treelet(&[
        "render",
        "--scene",
        "flag",
        "--frames",
        "3",
        "--width",
        "32",
        "--height",
        "24",
        "--spp",
        "1",
        "--builder",
        "refit",
        "--json",
        "--out",
        out.to_str().expect("temp path is UTF-8"),
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "render failed: {stderr}");
    for frame in 0..3 {
        let path = out.join(format!("frame_{frame:04}.png"));
        let image = image::open(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!((image.width(), image.height()), (32, 24));
    }
    assert!(!out.join("frame_0003.png").exists());
    let stdout = String::from_utf8_lossy(&output.stdout);
    let records: Vec<serde_json::Value> = stdout
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert_eq!(records.len(), 3);
    for (i, r) in records.iter().enumerate() {
        assert_eq!(r["frame"], i);
        assert_eq!(r["builder"], "refit");
        for key in ["t", "build_ms", "sah", "rays", "trace_ms", "mrays_per_s"] {
            assert!(r.get(key).is_some(), "{key} missing in {r}");
        }
        assert!(r["sah"].as_f64().unwrap() > 0.0);
        assert!(r["rays"].as_u64().unwrap() >= 32 * 24);
        // A refit has no build schedule (its topology is built once).
        assert!(r["schedule"].is_null());
    }
    std::fs::remove_dir_all(&out).ok();
}

/// `render --frames --tune-schedule on` tunes an lbvh rebuild's schedule on the first frame (its
/// sort tile, on a CPU device too) and reports it in every frame's JSON; the frames' trees are
/// those of the untuned run.
#[cfg(feature = "app")]
#[test]
fn headless_animation_tunes_the_schedule_on_request() {
    let run = |tune: &str| {
        let out =
            std::env::temp_dir().join(format!("treelet-anim-tune-{tune}-{}", std::process::id()));
        let output = common::run_treelet(&[
            "render",
            "--scene",
            "flag",
            "--frames",
            "2",
            "--width",
            "16",
            "--height",
            "16",
            "--spp",
            "1",
            "--builder",
            "lbvh",
            "--tune-schedule",
            tune,
            "--json",
            "--out",
            out.to_str().expect("temp path is UTF-8"),
        ]);
        let stderr = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "render failed: {stderr}");
        std::fs::remove_dir_all(&out).ok();
        String::from_utf8_lossy(&output.stdout)
            .lines()
            .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
            .collect::<Vec<serde_json::Value>>()
    };
    let (tuned, untuned) = (run("on"), run("off"));
    assert_eq!(tuned.len(), 2);
    for (t, u) in tuned.iter().zip(&untuned) {
        let schedule = t["schedule"].as_str().expect("a schedule");
        assert!(
            schedule == "default" || schedule.starts_with("tile="),
            "{schedule}"
        );
        assert_eq!(u["schedule"], "default");
        assert_eq!(t["sah"], u["sah"]);
        assert_eq!(t["nodes"], u["nodes"]);
    }
}

#[test]
fn bart_kitchen_through_the_animation_path_equals_evaluate() {
    let Some(path) = shared_scenes_dir()
        .map(|d| d.join("bart/kitchen/aff/kitchen.aff"))
        .filter(|p| p.is_file())
    else {
        missing_shared_scene("the shared BART kitchen (bart/kitchen/aff/kitchen.aff)");
        return;
    };
    let reference = BartScene::load(&path).unwrap();
    let mut animation = load_animation("bart-kitchen").unwrap();
    let t0 = animation.time_range().start;
    // Upload a later frame, then animate back to frame 0 through the GPU scene.
    let later = animation.scene_at(animation.time_range().frame_time(200));
    let scene = Geometry::upload(gpu(), &later).unwrap();
    animate(animation.as_mut(), t0, &scene);
    let mut expected = Vec::new();
    reference.evaluate(t0, &mut expected);
    let got = gpu_triangles(&scene);
    assert_eq!(got.len(), expected.len());
    assert!(got == expected, "frame 0 differs from BartScene::evaluate");
    assert_ne!(
        later.triangles, expected,
        "frame 200 should differ from frame 0"
    );
    assert_eq!(animation.materials(), reference.materials());
}

#[cfg(feature = "app")]
#[test]
fn animated_render_errors_are_clear() {
    for (args, expected) in [
        (&["render", "--builder", "refit"][..], "--frames"),
        (
            &["render", "--scene", "no-such-animation", "--frames", "2"][..],
            "unknown scene",
        ),
        (&["render", "--frames", "0"][..], "--frames"),
        (
            &[
                "render",
                "--scene",
                "flag",
                "--frames",
                "1",
                "--builder",
                "refit",
                "--tune-schedule",
                "on",
            ][..],
            "--tune-schedule on does not apply to refit: only GPU rebuilds",
        ),
        (&["render", "--tune-schedule", "on"][..], "--frames"),
        (&["render", "--json"][..], "--frames"),
    ] {
        common::assert_clean_failure(args, expected);
    }
}
