//! The scene registry: every scene the CLI, the viewer and the tests know by name (procedural
//! built-ins and the OBJ files of the shared scenes folder), and `load_scene`, which resolves a
//! name or an OBJ path and applies the bad-geometry policy (`sanitize`) to the result.

use super::{
    cornell_box, grass_blades, hairball, load_obj, sanitize, stacked_duplicates, teapot_in_stadium,
    tessellated_field, Camera, Scene,
};
use crate::{Error, Result};
use glam::Vec3;
use std::path::{Path, PathBuf};

/// Environment variable naming the shared scenes folder (the one holding `cornell_box/`,
/// `sibenik/`, …); it overrides the default search.
pub const SCENES_DIR_ENV: &str = "TREELET_SCENES_DIR";

/// A fixed camera, in plain arrays so that it can live in a `const`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPreset {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    pub up: [f32; 3],
    pub fov_y_degrees: f32,
}

impl From<CameraPreset> for Camera {
    fn from(p: CameraPreset) -> Self {
        Camera {
            eye: Vec3::from(p.eye),
            target: Vec3::from(p.target),
            up: Vec3::from(p.up),
            fov_y_degrees: p.fov_y_degrees,
        }
    }
}

/// Where a registered scene comes from.
#[derive(Clone, Copy, Debug)]
pub enum SceneSource {
    /// Generated in code.
    Builtin(fn() -> Scene),
    /// An OBJ file, `path` relative to the shared scenes folder (`shared_scenes_dir`). Without a
    /// camera preset the scene uses `Camera::framing` of its bounds.
    Shared {
        path: &'static str,
        camera: Option<CameraPreset>,
    },
}

/// One named scene.
#[derive(Clone, Copy, Debug)]
pub struct SceneEntry {
    pub name: &'static str,
    pub description: &'static str,
    pub source: SceneSource,
}

fn field_1m() -> Scene {
    tessellated_field(710)
}

fn field_100k() -> Scene {
    tessellated_field(213)
}

fn field_10k() -> Scene {
    tessellated_field(67)
}

fn stacked() -> Scene {
    stacked_duplicates(80)
}

fn grass() -> Scene {
    grass_blades(50_000)
}

fn hairball_300k() -> Scene {
    hairball(3_000)
}

fn stadium() -> Scene {
    teapot_in_stadium(16)
}

const fn shared(path: &'static str) -> SceneSource {
    SceneSource::Shared { path, camera: None }
}

const fn shared_with_camera(path: &'static str, camera: CameraPreset) -> SceneSource {
    SceneSource::Shared {
        path,
        camera: Some(camera),
    }
}

const fn preset(eye: [f32; 3], target: [f32; 3], fov_y_degrees: f32) -> CameraPreset {
    CameraPreset {
        eye,
        target,
        up: [0.0, 1.0, 0.0],
        fov_y_degrees,
    }
}

/// All scenes known by name, built-ins first.
pub static SCENES: &[SceneEntry] = &[
    SceneEntry {
        name: "cornell",
        description: "procedural Cornell box, 36 triangles",
        source: SceneSource::Builtin(cornell_box),
    },
    SceneEntry {
        name: "field-1m",
        description: "procedural terrain with objects, 1,101,384 triangles",
        source: SceneSource::Builtin(field_1m),
    },
    SceneEntry {
        name: "field-100k",
        description: "procedural terrain with objects, 99,754 triangles",
        source: SceneSource::Builtin(field_100k),
    },
    SceneEntry {
        name: "field-10k",
        description: "procedural terrain with objects, 10,162 triangles",
        source: SceneSource::Builtin(field_10k),
    },
    SceneEntry {
        name: "stacked",
        description:
            "procedural stress scene: 80 overlapping copies of a sphere, 102,402 triangles",
        source: SceneSource::Builtin(stacked),
    },
    SceneEntry {
        name: "grass",
        description: "procedural stress scene: 50,000 thin grass blades, 250,002 triangles",
        source: SceneSource::Builtin(grass),
    },
    SceneEntry {
        name: "hairball",
        description:
            "procedural stress scene: 3,000 thin strands tangled in a ball, 300,000 triangles",
        source: SceneSource::Builtin(hairball_300k),
    },
    SceneEntry {
        name: "stadium",
        description: "procedural stress scene: a detailed teapot in a stadium, 205,186 triangles",
        source: SceneSource::Builtin(stadium),
    },
    SceneEntry {
        name: "cornell_box",
        description: "Cornell box (McGuire's original OBJ), 36 triangles",
        source: shared("cornell_box/CornellBox-Original.obj"),
    },
    SceneEntry {
        name: "sibenik",
        description: "Sibenik cathedral interior, 75,284 triangles",
        source: shared_with_camera(
            "sibenik/sibenik.obj",
            // From the west end of the nave (bounds x -20.1..20.1, y -15.3..15.3) towards the altar.
            preset([-17.0, -11.0, 0.0], [10.0, -9.0, 0.0], 60.0),
        ),
    },
    SceneEntry {
        name: "dabrovic_sponza",
        description: "Dabrovic Sponza atrium, 66,450 triangles",
        source: shared_with_camera(
            "dabrovic_sponza/sponza.obj",
            // At eye height at one end of the atrium (x -17.4..17.4, floor y ≈ 0), along +x.
            preset([-14.0, 2.0, 0.0], [10.0, 4.5, 0.0], 60.0),
        ),
    },
    SceneEntry {
        name: "crytek_sponza",
        description: "Crytek Sponza atrium, 279,163 triangles",
        source: shared_with_camera(
            "crytek_sponza/sponza.obj",
            // In the atrium (x -1921..1800, y -126..1429, z -1183..1105), along +x past the banner.
            preset([-1100.0, 200.0, -40.0], [1000.0, 300.0, -40.0], 60.0),
        ),
    },
    SceneEntry {
        name: "conference",
        description: "conference room, 331,179 triangles",
        source: shared_with_camera(
            "conference/conference.obj",
            // From a corner of the room (x -1020..1686, y -3..650, z -1056..668) over the table.
            preset([1300.0, 300.0, 300.0], [0.0, 120.0, -600.0], 60.0),
        ),
    },
    SceneEntry {
        name: "bunny",
        description: "Stanford bunny, 144,046 triangles",
        source: shared("bunny/bunny.obj"),
    },
    SceneEntry {
        name: "armadillo",
        description: "Stanford armadillo, 345,944 triangles",
        source: shared("armadillo/armadillo.obj"),
    },
    SceneEntry {
        name: "lost_empire",
        description: "Lost Empire Minecraft world, 224,998 triangles",
        source: shared("lost_empire/lost_empire.obj"),
    },
    SceneEntry {
        name: "buddha",
        description: "Happy Buddha, decimated reconstruction, 67,240 triangles",
        source: shared("buddha/happy_vrip_res3.obj"),
    },
    SceneEntry {
        name: "buddha_scans",
        description: "Happy Buddha raw range scans (overlapping), 2,079,334 triangles",
        source: shared("buddha/happy_stand_scans.obj"),
    },
];

/// The names of all registered scenes, in registry order.
pub fn builtin_names() -> Vec<&'static str> {
    SCENES.iter().map(|e| e.name).collect()
}

/// The default places of the shared scenes folder, in search order.
fn default_scene_dirs() -> Vec<PathBuf> {
    vec![
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/scenes"),
        PathBuf::from("../shared/scenes"),
        PathBuf::from("shared/scenes"),
    ]
}

/// The shared scenes folder: `$TREELET_SCENES_DIR` if set and non-empty (whether or not it
/// exists), otherwise the first existing of `<crate>/../shared/scenes`, `./../shared/scenes` and
/// `./shared/scenes`.
pub fn shared_scenes_dir() -> Option<PathBuf> {
    match std::env::var_os(SCENES_DIR_ENV) {
        Some(dir) if !dir.is_empty() => Some(PathBuf::from(dir)),
        _ => default_scene_dirs().into_iter().find(|d| d.is_dir()),
    }
}

/// Where a shared scene's file is, or an error explaining where we looked.
fn shared_scene_path(name: &str, relative: &str) -> Result<PathBuf> {
    let not_found = |path: PathBuf, looked: String| Error::Io {
        path,
        source: std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!(
                "shared scene '{name}' not found ({looked}); set {SCENES_DIR_ENV} to the folder \
                 that holds the shared scenes (the one with cornell_box/, sibenik/, ...)"
            ),
        ),
    };
    match shared_scenes_dir() {
        Some(dir) => {
            let path = dir.join(relative);
            if path.is_file() {
                Ok(path)
            } else {
                let from = if std::env::var_os(SCENES_DIR_ENV).is_some_and(|d| !d.is_empty()) {
                    format!("{SCENES_DIR_ENV}={}", dir.display())
                } else {
                    format!("scenes folder {}", dir.display())
                };
                Err(not_found(path, format!("looked in {from}")))
            }
        }
        None => {
            let looked: Vec<String> = default_scene_dirs()
                .iter()
                .map(|d| d.display().to_string())
                .collect();
            Err(not_found(
                PathBuf::from(relative),
                format!("no scenes folder at {}", looked.join(", ")),
            ))
        }
    }
}

fn load_entry(entry: &SceneEntry) -> Result<Scene> {
    match entry.source {
        SceneSource::Builtin(build) => {
            let mut scene = build();
            scene.name = entry.name.to_owned();
            Ok(scene)
        }
        SceneSource::Shared { path, camera } => {
            let mut scene = load_obj(&shared_scene_path(entry.name, path)?)?;
            scene.name = entry.name.to_owned();
            if let Some(camera) = camera {
                scene.camera = camera.into();
            }
            Ok(scene)
        }
    }
}

/// Whether an argument is meant as a file path rather than a scene name.
fn looks_like_path(arg: &str) -> bool {
    arg.contains('/') || arg.contains(std::path::MAIN_SEPARATOR) || has_obj_extension(arg)
}

fn has_obj_extension(path: impl AsRef<Path>) -> bool {
    path.as_ref()
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

/// Loads a scene by registry name (`SCENES`) or by the path of an `.obj` file, then sanitizes it.
///
/// Errors: a name that is neither registered nor a file gives `Error::UnknownScene` (listing the
/// names); a path-like argument (containing a path separator or ending in `.obj`) that does not
/// exist gives `Error::Io`, as does a shared scene whose file is missing (the message says where
/// it looked and mentions `TREELET_SCENES_DIR`); an existing file that is not `.obj` gives
/// `Error::InvalidArgument`; OBJ problems come from `load_obj`; a scene with no triangles left
/// after `sanitize` gives `Error::EmptyScene`.
pub fn load_scene(name_or_path: &str) -> Result<Scene> {
    let mut scene = if let Some(entry) = SCENES.iter().find(|e| e.name == name_or_path) {
        load_entry(entry)?
    } else if let Some(cells) = name_or_path.strip_prefix("field:") {
        // The procedural terrain at any size (2·cells² terrain triangles plus objects), for scaling
        // studies: `field:710` is field-1m.
        let cells: u32 = cells
            .parse()
            .ok()
            .filter(|&c| (1..=20_000).contains(&c))
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "'{name_or_path}': field:N takes N (cells per side) in 1..=20000"
                ))
            })?;
        tessellated_field(cells)
    } else {
        let path = Path::new(name_or_path);
        if path.is_file() {
            if !has_obj_extension(path) {
                return Err(Error::InvalidArgument(format!(
                    "{name_or_path}: only Wavefront .obj files can be loaded"
                )));
            }
            load_obj(path)?
        } else if looks_like_path(name_or_path) {
            // load_obj reports the missing (or unreadable) file with its path.
            load_obj(path)?
        } else {
            return Err(Error::UnknownScene {
                name: name_or_path.to_owned(),
                known: builtin_names().join(", "),
            });
        }
    };
    sanitize(&mut scene);
    if scene.triangles.is_empty() {
        return Err(Error::EmptyScene(name_or_path.to_owned()));
    }
    Ok(scene)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_complete() {
        let names = builtin_names();
        let mut sorted = names.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), names.len());
        for required in [
            "cornell",
            "field-1m",
            "field-100k",
            "field-10k",
            "cornell_box",
            "sibenik",
            "dabrovic_sponza",
            "crytek_sponza",
            "conference",
            "bunny",
            "armadillo",
            "lost_empire",
            "buddha",
            "buddha_scans",
            "stacked",
            "grass",
            "hairball",
            "stadium",
        ] {
            assert!(names.contains(&required), "{required} missing");
        }
    }

    #[test]
    fn builtins_load_and_field_sizes_match_their_names() {
        for (name, min, max) in [
            ("cornell", 36, 36),
            ("field-10k", 9_000, 11_000),
            ("field-100k", 90_000, 110_000),
            ("stacked", 100_000, 105_000),
            ("grass", 245_000, 255_000),
            ("hairball", 295_000, 305_000),
            ("stadium", 198_000, 210_000),
        ] {
            let scene = load_scene(name).expect(name);
            assert_eq!(scene.name, name);
            let n = scene.triangles.len();
            assert!((min..=max).contains(&n), "{name}: {n} triangles");
            let entry = SCENES.iter().find(|e| e.name == name).expect(name);
            assert!(
                entry.description.contains(&format_thousands(n)),
                "{name}: description '{}' vs {n}",
                entry.description
            );
        }
    }

    fn format_thousands(n: usize) -> String {
        let digits = n.to_string();
        let mut out = String::new();
        for (i, c) in digits.chars().enumerate() {
            if i > 0 && (digits.len() - i).is_multiple_of(3) {
                out.push(',');
            }
            out.push(c);
        }
        out
    }

    #[test]
    fn unknown_name_lists_the_known_ones() {
        match load_scene("no-such-scene") {
            Err(Error::UnknownScene { name, known }) => {
                assert_eq!(name, "no-such-scene");
                assert!(known.contains("cornell") && known.contains("crytek_sponza"));
            }
            other => panic!("expected UnknownScene, got {other:?}"),
        }
    }

    #[test]
    fn path_like_arguments_give_io_errors() {
        for arg in ["does/not/exist", "missing-file.obj", "missing.OBJ"] {
            match load_scene(arg) {
                Err(Error::Io { path, .. }) => assert_eq!(path, Path::new(arg)),
                other => panic!("{arg}: expected Error::Io, got {other:?}"),
            }
        }
    }

    #[test]
    fn interior_presets_are_inside_their_scenes() {
        for entry in SCENES {
            let SceneSource::Shared {
                path,
                camera: Some(camera),
            } = entry.source
            else {
                continue;
            };
            if !shared_scenes_dir().is_some_and(|d| d.join(path).is_file()) {
                eprintln!("skipping {}: shared scene not found", entry.name);
                continue;
            }
            let scene = load_scene(entry.name).expect(entry.name);
            assert_eq!(scene.camera, Camera::from(camera));
            let b = scene.bounds();
            for p in [scene.camera.eye, scene.camera.target] {
                assert!(
                    p.cmpgt(b.min).all() && p.cmplt(b.max).all(),
                    "{}: {p} outside {b:?}",
                    entry.name
                );
            }
        }
    }

    #[test]
    fn presets_become_cameras() {
        let p = preset([1.0, 2.0, 3.0], [0.0, 2.0, 0.0], 60.0);
        let c = Camera::from(p);
        assert_eq!(c.eye, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(c.target, Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(c.up, Vec3::Y);
        assert_eq!(c.fov_y_degrees, 60.0);
    }
}
