//! Integration tests of scene loading through the public API: every registered built-in loads
//! (the stress scenes with their exact triangle counts),
//! shared scenes load by name with the triangle counts of the shared README, OBJ files load by
//! path, and bad input (missing, malformed, empty, non-finite, degenerate files, unknown names)
//! gives the documented error or policy, never a panic.

mod common;

use common::missing_shared_scene;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use treelet::scene::{
    builtin_names, grass_blades_triangle_count, hairball_triangle_count, load_obj, load_scene,
    shared_scenes_dir, stacked_duplicates_triangle_count, teapot_in_stadium_triangle_count, Scene,
    SCENES,
};
use treelet::Error;

/// A fresh file under the system temp directory with `text` in it.
fn temp_obj(stem: &str, text: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let path = std::env::temp_dir().join(format!(
        "treelet-scenes-{}-{}-{stem}.obj",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::write(&path, text).expect("write temp OBJ");
    path
}

/// Loads `text` as an OBJ file via `load_scene(path)` and removes the file again.
fn load_text(stem: &str, text: &str) -> (PathBuf, treelet::Result<Scene>) {
    let path = temp_obj(stem, text);
    let result = load_scene(path.to_str().expect("temp path is UTF-8"));
    let _ = std::fs::remove_file(&path);
    (path, result)
}

/// Whether the shared scene file `relative` is present (see `missing_shared_scene` otherwise).
fn shared_available(relative: &str) -> bool {
    let present = shared_scenes_dir().is_some_and(|dir| dir.join(relative).is_file());
    if !present {
        missing_shared_scene(format!("shared scene {relative}"));
    }
    present
}

fn assert_sane(scene: &Scene) {
    assert!(!scene.triangles.is_empty(), "{}", scene.name);
    let bounds = scene.bounds();
    assert!(
        bounds.min.is_finite() && bounds.max.is_finite(),
        "{}",
        scene.name
    );
    for t in &scene.triangles {
        assert!(
            (t.material as usize) < scene.materials.len(),
            "{}",
            scene.name
        );
        assert!(t.area() > 0.0, "{}", scene.name);
    }
    let c = scene.camera;
    assert!(c.eye.is_finite() && c.target.is_finite() && c.eye != c.target);
    assert!(c.fov_y_degrees > 1.0 && c.fov_y_degrees < 179.0);
}

#[test]
fn every_builtin_loads() {
    for name in ["cornell", "field-10k", "field-100k"] {
        let scene = load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.name, name);
        assert_sane(&scene);
    }
    assert_eq!(load_scene("cornell").expect("cornell").triangles.len(), 36);
    let n = load_scene("field-10k").expect("field-10k").triangles.len();
    assert!((9_000..=11_000).contains(&n), "{n}");
    let n = load_scene("field-100k")
        .expect("field-100k")
        .triangles
        .len();
    assert!((90_000..=110_000).contains(&n), "{n}");
}

#[test]
fn stress_scenes_load_by_name_with_their_counts() {
    for (name, count) in [
        ("stacked", stacked_duplicates_triangle_count(80)),
        ("grass", grass_blades_triangle_count(50_000)),
        ("hairball", hairball_triangle_count(3_000)),
        ("stadium", teapot_in_stadium_triangle_count(16)),
    ] {
        let scene = load_scene(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.name, name);
        // Sanitizing dropped nothing.
        assert_eq!(scene.triangles.len(), count, "{name}");
        assert_sane(&scene);
    }
}

#[test]
fn field_1m_has_a_million_triangles() {
    let scene = load_scene("field-1m").expect("field-1m");
    assert!(
        scene.triangles.len() >= 1_000_000,
        "{}",
        scene.triangles.len()
    );
    assert_sane(&scene);
}

#[test]
fn registry_names_are_listed() {
    let names = builtin_names();
    assert_eq!(names.len(), SCENES.len());
    for name in [
        "cornell",
        "field-1m",
        "cornell_box",
        "crytek_sponza",
        "buddha_scans",
    ] {
        assert!(names.contains(&name), "{name}");
    }
    for entry in SCENES {
        assert!(!entry.description.is_empty(), "{}", entry.name);
    }
}

#[test]
fn shared_cornell_box_loads_by_name() {
    if !shared_available("cornell_box/CornellBox-Original.obj") {
        return;
    }
    let scene = load_scene("cornell_box").expect("cornell_box");
    assert_eq!(scene.triangles.len(), 36);
    assert_sane(&scene);
    // The light (Ke 17 12 4) is emissive, so the scene is self-lit with a black sky.
    let emissive = scene
        .triangles
        .iter()
        .filter(|t| scene.materials[t.material as usize].emission == [17.0, 12.0, 4.0])
        .count();
    assert_eq!(emissive, 2);
    assert_eq!(scene.sky, glam::Vec3::ZERO);
}

#[test]
fn shared_buddha_loads_by_name() {
    if !shared_available("buddha/happy_vrip_res3.obj") {
        return;
    }
    let scene = load_scene("buddha").expect("buddha");
    assert_eq!(scene.triangles.len(), 67_240);
    assert_sane(&scene);
}

#[test]
fn loads_by_path() {
    let path = temp_obj("by_path", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    let scene = load_scene(path.to_str().expect("UTF-8 path"));
    let direct = load_obj(&path);
    let _ = std::fs::remove_file(&path);
    let scene = scene.expect("loads by path");
    assert_eq!(scene.triangles.len(), 2);
    assert_eq!(
        Some(scene.name.as_str()),
        path.file_stem().and_then(|s| s.to_str())
    );
    assert_sane(&scene);
    assert_eq!(direct.expect("load_obj").triangles, scene.triangles);
}

#[test]
fn shared_scene_loads_by_path() {
    let relative = "cornell_box/CornellBox-Original.obj";
    if !shared_available(relative) {
        return;
    }
    let path = shared_scenes_dir().expect("checked above").join(relative);
    let scene = load_scene(path.to_str().expect("UTF-8 path")).expect("loads by path");
    assert_eq!(scene.triangles.len(), 36);
}

#[test]
fn missing_file_is_an_io_error_with_the_path() {
    let path = std::env::temp_dir().join(format!(
        "treelet-scenes-{}-does-not-exist.obj",
        std::process::id()
    ));
    let arg = path.to_str().expect("UTF-8 path");
    for result in [load_scene(arg), load_obj(&path)] {
        match result {
            Err(e @ Error::Io { .. }) => {
                assert!(e.to_string().contains(arg), "{e}");
                let Error::Io { path: p, .. } = e else {
                    unreachable!()
                };
                assert_eq!(p, path);
            }
            other => panic!("expected Error::Io, got {other:?}"),
        }
    }
    // A relative path-looking argument.
    assert!(matches!(
        load_scene("no/such/dir/scene.obj"),
        Err(Error::Io { .. })
    ));
}

#[test]
fn malformed_obj_is_an_obj_error_with_the_path() {
    for (stem, text) in [
        ("two_coords", "v 1 2\nv 0 0 0\nv 1 0 0\nf 1 2 3\n"),
        ("out_of_range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n"),
        ("negative_range", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -7\n"),
        ("non_numeric", "v 0 0 zero\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
        ("bad_face", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 two 3\n"),
        ("bad_normal", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0\nf 1 2 3\n"),
    ] {
        let (path, result) = load_text(stem, text);
        match result {
            Err(e @ Error::Obj { .. }) => {
                let message = e.to_string();
                assert!(
                    message.contains(&path.display().to_string()),
                    "{stem}: {message}"
                );
            }
            other => panic!("{stem}: expected Error::Obj, got {other:?}"),
        }
    }
}

#[test]
fn binary_garbage_is_an_error_not_a_panic() {
    let path =
        std::env::temp_dir().join(format!("treelet-scenes-{}-garbage.obj", std::process::id()));
    std::fs::write(&path, [0xff, 0xfe, 0x00, b'v', b' ', 0x80, b'\n']).expect("write");
    let result = load_scene(path.to_str().expect("UTF-8 path"));
    let _ = std::fs::remove_file(&path);
    assert!(matches!(result, Err(Error::Obj { .. })), "{result:?}");
}

#[test]
fn empty_obj_is_an_empty_scene() {
    for (stem, text) in [
        ("empty", ""),
        ("comments_only", "# nothing here\n\n"),
        ("vertices_only", "v 0 0 0\nv 1 0 0\nv 0 1 0\n"),
        (
            "points_and_lines",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\np 1\nl 1 2\n",
        ),
    ] {
        let (path, result) = load_text(stem, text);
        match result {
            Err(e @ Error::EmptyScene(_)) => {
                assert!(e.to_string().contains(&path.display().to_string()), "{e}");
            }
            other => panic!("{stem}: expected EmptyScene, got {other:?}"),
        }
    }
}

#[test]
fn non_finite_triangles_are_dropped() {
    let (_, result) = load_text(
        "some_nan",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nv 0 inf 0\nv -inf 1 1\n\
         f 1 2 3\nf 1 2 4\nf 5 2 3\nf 1 6 3\n",
    );
    let scene = result.expect("the finite triangle survives");
    assert_eq!(scene.triangles.len(), 1);
    assert_sane(&scene);

    let (path, result) = load_text(
        "all_nan",
        "v nan 0 0\nv 1 nan 0\nv 0 1 NaN\nv inf inf inf\nf 1 2 3\nf 2 3 4\n",
    );
    match result {
        Err(e @ Error::EmptyScene(_)) => {
            assert!(e.to_string().contains(&path.display().to_string()), "{e}");
        }
        other => panic!("expected EmptyScene, got {other:?}"),
    }
}

#[test]
fn zero_area_triangles_are_dropped() {
    let (_, result) = load_text(
        "degenerate",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\n\
         f 1 2 3\nf 1 1 2\nf 1 2 4\nf 3 3 3\n",
    );
    let scene = result.expect("the good triangle survives");
    assert_eq!(scene.triangles.len(), 1);

    let (_, result) = load_text("all_degenerate", "v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n");
    assert!(matches!(result, Err(Error::EmptyScene(_))), "{result:?}");
}

#[test]
fn unknown_scene_name_lists_the_known_names() {
    match load_scene("definitely-not-a-scene") {
        Err(e @ Error::UnknownScene { .. }) => {
            let message = e.to_string();
            assert!(message.contains("definitely-not-a-scene"), "{message}");
            assert!(
                message.contains("cornell") && message.contains("field-1m"),
                "{message}"
            );
        }
        other => panic!("expected UnknownScene, got {other:?}"),
    }
}

#[test]
fn non_obj_file_is_rejected() {
    let path = std::env::temp_dir().join(format!("treelet-scenes-{}-mesh.ply", std::process::id()));
    std::fs::write(&path, "ply\n").expect("write");
    let result = load_scene(path.to_str().expect("UTF-8 path"));
    let _ = std::fs::remove_file(&path);
    match result {
        Err(e @ Error::InvalidArgument(_)) => {
            assert!(e.to_string().contains(&path.display().to_string()), "{e}")
        }
        other => panic!("expected InvalidArgument, got {other:?}"),
    }
}

#[test]
fn field_of_any_size_loads_by_name() {
    let small = treelet::scene::load_scene("field:10").unwrap();
    assert!(
        small.triangles.len() >= 200,
        "{} triangles",
        small.triangles.len()
    );
    for bad in ["field:", "field:x", "field:0", "field:99999"] {
        let err = treelet::scene::load_scene(bad).unwrap_err();
        assert!(err.to_string().contains("field:N"), "{bad}: {err}");
    }
}
