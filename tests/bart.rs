//! Tests of the BART (AFF) loader: every construct on small hand-written snippets, the spline
//! interpolation against an independent implementation of the Kochanek–Bartels formulas,
//! malformed files (each an `Error::Aff` with the right line), and the three BART scenes of the
//! shared scenes folder against the reference frames evaluated there.

mod common;

use common::missing_shared_scene;
use glam::{Quat, Vec3};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;
use treelet::scene::{shared_scenes_dir, BartScene, PointLight, Triangle, CONE_SIDES};
use treelet::Error;

/// A fresh temporary folder holding the given (relative path, contents) files.
fn snippet_dir(files: &[(&str, &str)]) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "treelet-bart-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    for (name, text) in files {
        let path = dir.join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, text).unwrap();
    }
    dir
}

/// Loads `text` as `scene.aff` (with extra files beside it).
fn load_with(text: &str, extra: &[(&str, &str)]) -> treelet::Result<BartScene> {
    let mut files = vec![("scene.aff", text)];
    files.extend_from_slice(extra);
    let dir = snippet_dir(&files);
    let result = BartScene::load(&dir.join("scene.aff"));
    let _ = std::fs::remove_dir_all(dir);
    result
}

fn load(text: &str) -> BartScene {
    load_with(text, &[]).unwrap_or_else(|e| panic!("{e}"))
}

fn eval(scene: &BartScene, t: f32) -> Vec<Triangle> {
    let mut out = Vec::new();
    scene.evaluate(t, &mut out);
    assert_eq!(out.len(), scene.triangle_count());
    out
}

fn verts(tri: &Triangle) -> [Vec3; 3] {
    tri.vertices()
}

fn assert_close(a: Vec3, b: Vec3, tol: f32) {
    assert!((a - b).abs().max_element() <= tol, "{a} != {b}");
}

/// The error must be `Error::Aff` for the file `file_name` at `line`; returns its message.
fn expect_aff_error(result: treelet::Result<BartScene>, file_name: &str, line: usize) -> String {
    match result {
        Err(Error::Aff {
            path,
            line: l,
            message,
        }) => {
            assert_eq!(
                path.file_name().unwrap().to_str().unwrap(),
                file_name,
                "{message}"
            );
            assert_eq!(l, line, "{message}");
            message
        }
        Err(other) => panic!("expected Error::Aff, got {other}"),
        Ok(_) => panic!("expected Error::Aff, the file loaded"),
    }
}

#[test]
fn polygons_are_fan_triangulated() {
    let scene = load(
        "# a quad and a patch\n\
         p 4\n 0 0 0\n 1 0 0\n 1 1 0\n 0 1 0\n\
         pp 3\n 0 0 1  0 0 1\n 1 0 1  0 0 1\n 0 1 1  0 0 1\n",
    );
    let tris = eval(&scene, 0.0);
    assert_eq!(tris.len(), 3);
    let (a, b, c, d) = (Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y);
    assert_eq!(verts(&tris[0]), [a, b, c]);
    assert_eq!(verts(&tris[1]), [a, c, d]);
    assert_eq!(
        verts(&tris[2]),
        [Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0)]
    );
}

#[test]
fn textured_triangles_give_one_triangle() {
    let scene = load(
        "tt wood.ppm\n 0 0 0 0 0\n 1 0 0 1 0\n 0 1 0 0 1\n\
         ttp wood.ppm\n 0 0 2 0 0 1 0 0\n 1 0 2 0 0 1 1 0\n 0 1 2 0 0 1 0 1\n",
    );
    let tris = eval(&scene, 0.0);
    assert_eq!(tris.len(), 2);
    assert_eq!(verts(&tris[0]), [Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(verts(&tris[1])[2], Vec3::new(0.0, 1.0, 2.0));
}

#[test]
fn meshes_are_indexed() {
    // With normals and texture coordinates: each triangle lists vertex, normal, texture indices.
    let scene = load(
        "m\nvertices 4\n 0 0 0\n 1 0 0\n 1 1 0\n 0 1 0\n\
         normals 1\n 0 0 1\n\
         texturecoords 2 tiles.ppm\n 0 0\n 1 1\n\
         triangles 2\n 0 1 2  0 0 0  0 1 1\n 0 2 3  0 0 0  0 1 0\n\
         m vertices 3 0 0 5 1 0 5 0 1 5 triangles 1 2 1 0\n",
    );
    let tris = eval(&scene, 0.0);
    assert_eq!(tris.len(), 3);
    assert_eq!(
        verts(&tris[1]),
        [Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]
    );
    assert_eq!(
        verts(&tris[2]),
        [
            Vec3::new(0.0, 1.0, 5.0),
            Vec3::new(1.0, 0.0, 5.0),
            Vec3::new(0.0, 0.0, 5.0)
        ]
    );
}

#[test]
fn cones_are_open_frusta() {
    let scene = load("c 1 0 0 0.5  1 2 0 0.25\n");
    let tris = eval(&scene, 0.0);
    assert_eq!(tris.len(), 2 * CONE_SIDES);
    for tri in &tris {
        for v in verts(tri) {
            let radial = Vec3::new(v.x - 1.0, 0.0, v.z).length();
            let expected = if v.y == 0.0 { 0.5 } else { 0.25 };
            assert!(v.y == 0.0 || (v.y - 2.0).abs() < 1e-6, "{v}");
            assert!((radial - expected).abs() < 1e-6, "{v}");
        }
    }
    // Side 0: (base 0, base 1, apex 0), (apex 0, base 1, apex 1); the rings start at
    // axis × x = −z and turn counter-clockwise about the axis.
    let [b0, b1, a0] = verts(&tris[0]);
    assert_close(b0, Vec3::new(1.0, 0.0, -0.5), 1e-6);
    let step = std::f32::consts::TAU / CONE_SIDES as f32;
    assert_close(
        b1,
        Vec3::new(1.0 - 0.5 * step.sin(), 0.0, -0.5 * step.cos()),
        1e-6,
    );
    assert_close(a0, Vec3::new(1.0, 2.0, -0.25), 1e-6);
    assert_eq!(verts(&tris[1])[0], a0);
    assert_eq!(verts(&tris[1])[1], b1);
}

#[test]
fn animated_triangles_interpolate_linearly() {
    let scene = load(
        "tpa 2\n\
         1.0\n 0 0 0  0 0 1\n 1 0 0  0 0 1\n 0 1 0  0 0 1\n\
         3.0\n 0 0 2  0 0 1\n 1 0 2  0 0 1\n 0 1 2  0 0 1\n",
    );
    assert_eq!(verts(&eval(&scene, 0.0)[0])[0], Vec3::ZERO);
    assert_eq!(verts(&eval(&scene, 1.0)[0])[1], Vec3::X);
    assert_close(
        verts(&eval(&scene, 1.5)[0])[2],
        Vec3::new(0.0, 1.0, 0.5),
        1e-6,
    );
    assert_eq!(verts(&eval(&scene, 3.0)[0])[0], Vec3::new(0.0, 0.0, 2.0));
    assert_eq!(verts(&eval(&scene, 9.0)[0])[0], Vec3::new(0.0, 0.0, 2.0));
}

#[test]
fn static_transforms_scale_then_rotate_then_translate() {
    // xs sx sy sz  rx ry rz degrees  tx ty tz: (1,0,0) scaled by 2 → (2,0,0), rotated 90° about
    // +z → (0,2,0), translated → (10,2,0). Nested blocks compose outer·inner.
    let scene = load(
        "xs 2 2 2  0 0 3 90  10 0 0 {\n\
           p 3 1 0 0  0 0 0  0 0 1\n\
           xs 1 1 1  1 0 0 0  0 0 5 {\n\
             p 3 1 0 0  0 0 0  0 0 1\n\
           }\n\
         }\n\
         p 3 1 0 0  0 0 0  0 0 1\n",
    );
    let tris = eval(&scene, 0.0);
    assert_close(verts(&tris[0])[0], Vec3::new(10.0, 2.0, 0.0), 1e-5);
    assert_close(verts(&tris[0])[2], Vec3::new(10.0, 0.0, 2.0), 1e-5);
    assert_close(verts(&tris[1])[0], Vec3::new(10.0, 2.0, 10.0), 1e-5);
    assert_eq!(verts(&tris[2])[0], Vec3::X);
}

/// Independent Kochanek–Bartels reference: Hermite basis with the TCB tangents of the segment
/// from key `i1` to key `i1 + 1` and the uneven-spacing adjustment, keys given as
/// (time, value, tension, continuity, bias); a missing neighbour of an end key is that key.
fn tcb_reference(keys: &[(f64, f64, f64, f64, f64)], i1: usize, time: f64) -> f64 {
    let (t0, p0, ..) = keys[i1.saturating_sub(1)];
    let (t1, p1, ten1, con1, bia1) = keys[i1];
    let (t2, p2, ten2, con2, bia2) = keys[i1 + 1];
    let (t3, p3, ..) = keys[(i1 + 2).min(keys.len() - 1)];
    let source = (1.0 - ten1) * (1.0 + con1) * (1.0 + bia1) / 2.0 * (p1 - p0)
        + (1.0 - ten1) * (1.0 - con1) * (1.0 - bia1) / 2.0 * (p2 - p1);
    let dest = (1.0 - ten2) * (1.0 - con2) * (1.0 + bia2) / 2.0 * (p2 - p1)
        + (1.0 - ten2) * (1.0 + con2) * (1.0 - bia2) / 2.0 * (p3 - p2);
    let source = source * 2.0 * (t2 - t1) / (t2 - t0);
    let dest = dest * 2.0 * (t2 - t1) / (t3 - t1);
    let u = (time - t1) / (t2 - t1);
    let (u2, u3) = (u * u, u * u * u);
    (2.0 * u3 - 3.0 * u2 + 1.0) * p1
        + (u3 - 2.0 * u2 + u) * source
        + (-2.0 * u3 + 3.0 * u2) * p2
        + (u3 - u2) * dest
}

/// A triangle under `x mover` with the given `transl` keys (time, x, y, z; tension, continuity
/// and bias 0); returns the position of its first vertex (the origin) as a function of time.
fn translation_track(keys: &[(f32, Vec3)]) -> impl Fn(f32) -> Vec3 {
    let track: String = keys
        .iter()
        .map(|(t, v)| format!("{t} {} {} {} 0 0 0\n", v.x, v.y, v.z))
        .collect();
    let scene = load(&format!(
        "x mover {{ p 3 0 0 0  0 1 0  0 0 1 }}\nk mover {{\n transl {}\n{track}}}\n",
        keys.len()
    ));
    move |t| verts(&eval(&scene, t)[0])[0]
}

#[test]
fn translation_keys_follow_the_tcb_spline() {
    // Two keys: exactly the keys at their times, clamped outside, and (with both end tangents
    // equal to the chord) straight uniform motion in between.
    let end = Vec3::new(4.0, 2.0, 0.0);
    let two = translation_track(&[(0.0, Vec3::ZERO), (1.0, end)]);
    assert_eq!(two(0.0), Vec3::ZERO, "start key exactly");
    assert_eq!(two(1.0), end, "end key exactly");
    assert_close(two(0.25), 0.25 * end, 1e-6);
    assert_eq!(two(-3.0), Vec3::ZERO, "clamped before the first key");
    assert_eq!(two(9.0), end, "clamped after the last key");

    // Four keys: the curve passes through all of them; between the middle two the tangents are
    // 0.5·(P2 − P0), so at u = 1/4 the Hermite value is 0.203125·(4, 2, 0) (not 0.25).
    let four = translation_track(&[
        (-1.0, Vec3::ZERO),
        (0.0, Vec3::ZERO),
        (1.0, end),
        (2.0, end),
    ]);
    assert_eq!(four(0.0), Vec3::ZERO);
    assert_close(four(1.0), end, 1e-6);
    assert_close(four(0.25), 0.203125 * end, 1e-6);
    // In the first segment (both keys at the origin) the incoming tangent at t = 0 is
    // 0.5·(4, 2, 0), so halfway the curve dips to h11(1/2)·(2, 1, 0) = −(0.25, 0.125, 0).
    assert_close(four(-0.5), Vec3::new(-0.25, -0.125, 0.0), 1e-6);
    assert_eq!(four(-5.0), Vec3::ZERO);

    // Uneven times and non-zero tension, continuity and bias, against the reference above.
    let keys = [
        (-0.5, 1.0, 0.2, 0.1, -0.3),
        (0.0, 0.0, 0.3, -0.2, 0.5),
        (0.5, 2.0, -0.4, 0.6, -0.3),
        (2.0, -1.0, 0.1, 0.0, 0.2),
        (3.5, 0.5, 0.5, 0.5, 0.5),
        (4.0, 0.0, -0.2, 0.3, 0.1),
    ];
    let track: String = keys
        .iter()
        .map(|(t, v, te, co, bi)| format!("{t} {v} 0 0 {te} {co} {bi}\n"))
        .collect();
    let scene = load(&format!(
        "x m {{ p 3 0 0 0  0 1 0  0 0 1 }}\nk m {{\n transl {}\n{track}}}\n",
        keys.len()
    ));
    let samples = [
        (-0.4, 0),
        (-0.1, 0),
        (0.0, 1),
        (0.37, 1),
        (0.5, 2),
        (1.2, 2),
        (1.9, 2),
        (2.5, 3),
        (3.6, 4),
        (3.9, 4),
    ];
    for (time, i1) in samples {
        let expected = tcb_reference(&keys, i1, time);
        let got = verts(&eval(&scene, time as f32)[0])[0].x;
        assert!(
            (f64::from(got) - expected).abs() < 1e-5,
            "t={time}: {got} vs {expected}"
        );
    }
}

#[test]
fn rotation_and_scale_keys_compose_as_t_r_s() {
    // Rotation about +y (axis given unnormalised) from 0° to 90° between t = 0 and t = 1, with a
    // constant scale of 2 and a translation of (0, 5, 0).
    let scene = load(
        "x spin { p 3 1 0 0  0 0 0  0 1 0 }\n\
         k spin {\n\
          rot 4\n -1 0 2 0 0  0 0 0\n 0 0 2 0 0  0 0 0\n 1 0 2 0 90  0 0 0\n 2 0 2 0 90  0 0 0\n\
          scale 4\n -1 2 2 2 0 0 0\n 0 2 2 2 0 0 0\n 1 2 2 2 0 0 0\n 2 2 2 2 0 0 0\n\
          transl 4\n -1 0 5 0 0 0 0\n 0 0 5 0 0 0 0\n 1 0 5 0 0 0 0\n 2 0 5 0 0 0 0\n\
         }\n",
    );
    assert_close(
        verts(&eval(&scene, 0.0)[0])[0],
        Vec3::new(2.0, 5.0, 0.0),
        1e-5,
    );
    assert_close(
        verts(&eval(&scene, 1.0)[0])[0],
        Vec3::new(0.0, 5.0, -2.0),
        1e-5,
    );
    // Halfway the angle spline gives 45° (symmetric keys).
    let half = Quat::from_rotation_y(45f32.to_radians()) * Vec3::new(2.0, 0.0, 0.0);
    assert_close(
        verts(&eval(&scene, 0.5)[0])[0],
        half + Vec3::new(0.0, 5.0, 0.0),
        1e-5,
    );
}

#[test]
fn nested_animated_transforms_and_visibility() {
    let scene = load(
        "x outer {\n xs 1 1 1  1 0 0 0  1 0 0 {\n  x inner { p 3 0 0 0  0 1 0  0 0 1 }\n }\n}\n\
         p 3 0 0 0  0 1 0  0 0 1\n\
         k inner { transl 4\n -1 0 0 0 0 0 0\n 0 0 0 0 0 0 0\n 1 0 0 3 0 0 0\n 2 0 0 3 0 0 0\n\
           visibility 2\n 0.5 0\n 0.75 1\n }\n\
         k outer { transl 4\n -1 0 0 0 0 0 0\n 0 0 0 0 0 0 0\n 1 0 7 0 0 0 0\n 2 0 7 0 0 0 0 }\n",
    );
    let tris = eval(&scene, 1.0);
    assert_close(verts(&tris[0])[0], Vec3::new(1.0, 7.0, 3.0), 1e-5);
    assert_eq!(
        verts(&tris[1])[0],
        Vec3::ZERO,
        "untransformed geometry stays static"
    );
    // Invisible from 0.5 to 0.75: the triangle collapses to a point but keeps its slot.
    let hidden = verts(&eval(&scene, 0.6)[0]);
    assert_eq!(hidden[0], hidden[1]);
    assert_eq!(hidden[1], hidden[2]);
    let shown = verts(&eval(&scene, 0.8)[0]);
    assert_ne!(shown[0], shown[1]);
}

#[test]
fn transforms_without_keys_are_the_identity() {
    // As in BART's code (the robots scene has five such transforms).
    let scene = load("x no_keys {\n p 3 0 0 0  1 0 0  0 1 0\n}\n");
    assert_eq!(verts(&eval(&scene, 0.0)[0]), [Vec3::ZERO, Vec3::X, Vec3::Y]);
}

#[test]
fn includes_are_relative_to_the_including_file() {
    let scene = load_with(
        "i 0 parts/part.aff\ni 1 parts/skipped.aff\np 3 0 0 9  1 0 9  0 1 9\n",
        &[
            (
                "parts/part.aff",
                "xs 1 1 1 0 0 1 0  0 0 1 {\n i 0 leaf.aff\n}\n",
            ),
            ("parts/leaf.aff", "% leaf\np 3 0 0 0  1 0 0  0 1 0\n"),
            ("parts/skipped.aff", "p 3 0 0 0  1 0 0  0 1 0\n"),
        ],
    )
    .unwrap();
    let tris = eval(&scene, 0.0);
    assert_eq!(tris.len(), 2, "the detail-level-1 include is skipped");
    assert_eq!(verts(&tris[0])[0], Vec3::new(0.0, 0.0, 1.0));
    assert_eq!(verts(&tris[1])[0], Vec3::new(0.0, 0.0, 9.0));
}

#[test]
fn materials_take_the_diffuse_colour_and_carry_over() {
    let scene = load_with(
        "p 3 0 0 0  1 0 0  0 1 0\n\
         fm 0.1 0.1 0.1  0.2 0.4 0.6  1 1 1  10 0 1\n\
         xs 1 1 1 0 1 0 0 0 0 0 { p 3 0 0 0  1 0 0  0 1 0 }\n\
         i 0 other.aff\n\
         p 3 0 0 0  1 0 0  0 1 0\n\
         fm 0 0 0  0.2 0.4 0.6  0 0 0  1 0 1\n\
         p 3 0 0 0  1 0 0  0 1 0\n",
        &[(
            "other.aff",
            "p 3 0 0 0  1 0 0  0 1 0\nf 1 0.5 0 0.8 0.2 10 0 1\n",
        )],
    )
    .unwrap();
    let s = scene.to_scene(0.0);
    let albedo = |i: usize| Vec3::from(s.materials[s.triangles[i].material as usize].albedo);
    assert_close(albedo(0), Vec3::splat(0.75), 1e-6);
    assert_close(albedo(1), Vec3::new(0.2, 0.4, 0.6), 1e-6);
    assert_close(albedo(2), Vec3::new(0.2, 0.4, 0.6), 1e-6);
    assert_close(albedo(3), Vec3::new(0.8, 0.4, 0.0), 1e-6);
    assert_eq!(
        s.triangles[4].material, s.triangles[1].material,
        "equal materials are shared"
    );
    assert_eq!(s.materials.len(), 3);
    assert!(s.materials.iter().all(|m| m.emission == [0.0; 3]));
}

#[test]
fn view_animation_range_background_and_lights() {
    let scene = load(
        "b 0.5 0.5 1.0\n\
         v\nfrom 0 0 10\nat 0 0 0\nup 0 1 0\nangle 40\nhither 0.01\nresolution 800 600\n\
         l 1 2 3\nl 4 5 6 0.3 0.2 0.1\nla lamp 7 8 9 1 1 1\nam 0.2 0.2 0.2\n\
         a 2.0 6.0 5  % five frames\n\
         p 3 0 0 0  1 0 0  0 1 0\n",
    );
    assert_eq!(scene.time_range(), (2.0, 6.0, 5));
    assert_eq!(scene.frame_time(0), 2.0);
    assert_eq!(scene.frame_time(2), 4.0);
    assert_eq!(scene.frame_time(4), 6.0);
    let s = scene.to_scene(3.0);
    assert_eq!(s.camera.eye, Vec3::new(0.0, 0.0, 10.0));
    assert_eq!(s.camera.target, Vec3::ZERO);
    assert_eq!(s.camera.fov_y_degrees, 40.0);
    assert_eq!(s.sky, Vec3::new(0.5, 0.5, 1.0));
    assert_eq!(s.name, "scene");
    // Static lights keep their colour (white without one); the animated `la` light is dropped.
    assert_eq!(
        s.lights,
        vec![
            PointLight::new(Vec3::new(1.0, 2.0, 3.0), Vec3::ONE),
            PointLight::new(Vec3::new(4.0, 5.0, 6.0), Vec3::new(0.3, 0.2, 0.1)),
        ]
    );

    // The `camera` animation moves the view: position from transl, −z of the rotation forward.
    let animated = load(
        "v from 0 0 10 at 0 0 0 up 0 1 0 angle 40 hither 1 resolution 8 6\n\
         p 3 0 0 0  1 0 0  0 1 0\n\
         k camera { transl 4\n -1 5 0 0 0 0 0\n 0 5 0 0 0 0 0\n 1 5 0 0 0 0 0\n 2 5 0 0 0 0 0\n\
           rot 4\n -1 0 1 0 90 0 0 0\n 0 0 1 0 90 0 0 0\n 1 0 1 0 90 0 0 0\n 2 0 1 0 90 0 0 0\n}\n",
    );
    let camera = animated.to_scene(0.5).camera;
    assert_close(camera.eye, Vec3::new(5.0, 0.0, 0.0), 1e-6);
    assert_close((camera.target - camera.eye).normalize(), Vec3::NEG_X, 1e-6);
    assert_close(camera.up, Vec3::Y, 1e-6);
}

#[test]
fn malformed_files_report_the_line() {
    let tri = "p 3 0 0 0  1 0 0  0 1 0\n";
    // Unclosed transform: reported at its opening line.
    let m = expect_aff_error(
        load_with(&format!("{tri}xs 1 1 1 0 1 0 0 0 0 0 {{\n{tri}"), &[]),
        "scene.aff",
        2,
    );
    assert!(m.contains("missing '}'"), "{m}");
    // `x name` without a brace: reported at the token found instead.
    let m = expect_aff_error(load_with(&format!("x foo\n{tri}}}\n"), &[]), "scene.aff", 2);
    assert!(m.contains("expected '{'"), "{m}");
    // A stray closing brace.
    expect_aff_error(load_with(&format!("{tri}}}\n"), &[]), "scene.aff", 2);
    // A bad number on the third line of a polygon.
    let m = expect_aff_error(
        load_with("\np 3\n 0 0 0\n 1 0 zero\n 0 1 0\n", &[]),
        "scene.aff",
        4,
    );
    assert!(m.contains("'zero'"), "{m}");
    // An `x` transform without a name.
    let m = expect_aff_error(
        load_with(&format!("{tri}\nx {{\n{tri}}}\n"), &[]),
        "scene.aff",
        3,
    );
    assert!(m.contains("transform name"), "{m}");
    // Include of a missing file: reported in the including file.
    let m = expect_aff_error(
        load_with("i 0 ok.aff\n", &[("ok.aff", "\n\ni 0 missing.aff\n")]),
        "ok.aff",
        3,
    );
    assert!(m.contains("missing.aff"), "{m}");
    // A truncated mesh: the file ends inside the `m` command that starts on line 2.
    let m = expect_aff_error(
        load_with(
            "% mesh\nm vertices 3\n0 0 0\n1 0 0\n0 1 0\ntriangles 2\n0 1 2\n",
            &[],
        ),
        "scene.aff",
        2,
    );
    assert!(m.contains("ends inside 'm'"), "{m}");
    // A mesh index out of range.
    expect_aff_error(
        load_with("m vertices 3 0 0 0 1 0 0 0 1 0\ntriangles 1\n0 1 3\n", &[]),
        "scene.aff",
        3,
    );
    // Unknown command, too few keys, unknown track, an include cycle.
    expect_aff_error(
        load_with(&format!("{tri}\nsphere 1 2 3\n"), &[]),
        "scene.aff",
        3,
    );
    let m = expect_aff_error(load_with("k a {\n transl 0\n}\n", &[]), "scene.aff", 2);
    assert!(m.contains("at least one key"), "{m}");
    // A key line cut short: its bad token is the closing brace on line 4.
    expect_aff_error(
        load_with("k a {\n rot 1\n 0 0 1 0 90 0 0\n}\n", &[]),
        "scene.aff",
        4,
    );
    expect_aff_error(load_with("k a {\n spin 0\n}\n", &[]), "scene.aff", 2);
    expect_aff_error(
        load_with("i 0 a.aff\n", &[("a.aff", "\ni 0 scene.aff\n")]),
        "a.aff",
        2,
    );
    // A top-level file that does not exist is an I/O error.
    let missing = BartScene::load(Path::new("/nonexistent/treelet/scene.aff"));
    assert!(matches!(missing, Err(Error::Io { .. })));
}

// ---------------------------------------------------------------------------------------------
// The BART scenes against the reference frames.

/// Triangles of a reference OBJ frame (`v x y z` and `f a b c` lines) and its time from the
/// header comment `# BART frame at animation time t=…`.
fn read_reference_frame(path: &Path) -> (f32, Vec<[Vec3; 3]>) {
    let text = std::fs::read_to_string(path).unwrap();
    let mut time = None;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for line in text.lines() {
        let mut words = line.split_ascii_whitespace();
        match words.next() {
            Some("v") => {
                let mut c = words.map(|w| w.parse::<f32>().unwrap());
                vertices.push(Vec3::new(
                    c.next().unwrap(),
                    c.next().unwrap(),
                    c.next().unwrap(),
                ));
            }
            Some("f") => {
                let idx: Vec<usize> = words
                    .map(|w| w.split('/').next().unwrap().parse::<usize>().unwrap() - 1)
                    .collect();
                assert_eq!(idx.len(), 3, "reference frames hold triangles only");
                triangles.push([vertices[idx[0]], vertices[idx[1]], vertices[idx[2]]]);
            }
            Some("#") if time.is_none() => {
                time = line
                    .split("time t=")
                    .nth(1)
                    .and_then(|s| s.split_whitespace().next())
                    .and_then(|s| s.parse::<f32>().ok());
            }
            _ => {}
        }
    }
    (time.expect("a time in the header"), triangles)
}

/// Loads a BART scene, checks the frame times, compares the evaluation with each reference
/// frame and sanity-checks the whole animation; returns the scene (or `None` when the shared
/// folder is missing).
fn check_against_reference(scene: &str, entry: &str, frames: &[u32]) -> Option<BartScene> {
    let Some(dir) = shared_scenes_dir()
        .map(|d| d.join("bart").join(scene))
        .filter(|d| d.is_dir())
    else {
        missing_shared_scene(format!("the shared BART scene bart/{scene}"));
        return None;
    };
    let start = Instant::now();
    let bart = BartScene::load(&dir.join("aff").join(entry)).unwrap_or_else(|e| panic!("{e}"));
    println!(
        "{scene}: loaded in {:.0} ms, {} triangles, {} materials, time range {:?}",
        start.elapsed().as_secs_f64() * 1e3,
        bart.triangle_count(),
        bart.materials().len(),
        bart.time_range()
    );
    for &frame in frames {
        let (ref_time, reference) =
            read_reference_frame(&dir.join("frames").join(format!("frame_{frame:04}.obj")));
        let t = bart.frame_time(frame);
        assert!(
            (t - ref_time).abs() < 1e-4,
            "frame {frame}: t = {t}, reference {ref_time}"
        );
        let tris = eval(&bart, t);
        assert_eq!(
            tris.len(),
            reference.len(),
            "{scene} frame {frame}: triangle count"
        );
        let bounds = reference
            .iter()
            .flatten()
            .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let diagonal = (bounds.1 - bounds.0).length();
        // The frames print 6 significant digits, about 6e-7 of the diagonal; a convention
        // difference (spline ends, rotation interpolation) shows as 1e-3 or more.
        let tolerance = 1e-5 * diagonal;
        let (mut max, mut sum, mut worst) = (0.0f32, 0.0f64, 0);
        for (i, (mine, theirs)) in tris.iter().zip(&reference).enumerate() {
            for (a, b) in verts(mine).iter().zip(theirs) {
                let e = (*a - *b).length();
                sum += f64::from(e);
                if e > max {
                    (max, worst) = (e, i);
                }
            }
        }
        let mean = sum / (3 * tris.len()) as f64;
        println!(
            "{scene} frame {frame} (t = {t}): max vertex error {max:.3e} ({:.2e} of the diagonal \
             {diagonal:.1}), mean {mean:.3e}",
            max / diagonal
        );
        assert!(
            max <= tolerance,
            "{scene} frame {frame}: triangle {worst} is off by {max} (> {tolerance}): mine {:?}, \
             reference {:?}",
            verts(&tris[worst]),
            reference[worst]
        );
    }
    // Every 10th frame of the whole animation: finite, and the camera too.
    let (_, _, frames) = bart.time_range();
    let mut tris = Vec::new();
    for frame in (0..frames).step_by(10) {
        bart.evaluate(bart.frame_time(frame), &mut tris);
        assert!(tris
            .iter()
            .all(|t| t.vertices().iter().all(|v| v.is_finite())));
    }
    let camera = bart.to_scene(bart.frame_time(frames / 2)).camera;
    assert!(camera.eye.is_finite() && camera.target.is_finite() && camera.eye != camera.target);
    Some(bart)
}

#[test]
fn kitchen_matches_the_reference_frames() {
    let Some(kitchen) = check_against_reference("kitchen", "kitchen.aff", &[0, 400]) else {
        return;
    };
    // Per-frame evaluation cost (reported; the buffer is reused as a renderer would).
    let mut out = Vec::new();
    kitchen.evaluate(0.0, &mut out);
    let runs = 20;
    let start = Instant::now();
    for f in 0..runs {
        kitchen.evaluate(kitchen.frame_time(f * 40), &mut out);
    }
    println!(
        "kitchen: evaluate takes {:.2} ms per frame ({} triangles)",
        start.elapsed().as_secs_f64() * 1e3 / f64::from(runs),
        out.len()
    );
}

#[test]
fn robots_match_the_reference_frames() {
    check_against_reference("robots", "Robot.aff", &[0, 400]);
}

#[test]
fn museum_matches_the_reference_frames() {
    check_against_reference("museum5", "museum5.aff", &[0, 150]);
}
