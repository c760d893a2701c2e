//! The registry of animated scenes, by name (in the style of `scene::registry`): the procedural
//! built-ins, the BART scenes and the BART reference frames as an OBJ sequence of the shared
//! scenes folder (`scene::shared_scenes_dir`). Any folder path names an OBJ sequence too.

use std::path::{Path, PathBuf};

use glam::Vec3;

use super::{Animation, BartAnimation, Explosion, Flag, ObjSequence, RigidBodies};
use crate::scene::{load_scene, shared_scenes_dir, Camera, Scene};
use crate::{Error, Result};

/// The animated scene `treelet view` (and `treelet` on a display) opens by default.
pub const DEFAULT_ANIMATION: &str = "explosion";

/// Where a registered animation comes from.
#[derive(Clone, Copy, Debug)]
pub enum AnimationSource {
    /// Generated in code, animated by a GPU kernel.
    Builtin(fn() -> Box<dyn Animation>),
    /// A BART scene: the AFF entry file, relative to the shared scenes folder.
    Bart(&'static str),
    /// A folder of frame OBJs relative to the shared scenes folder, seen from `camera` (or the
    /// framing of the first frame).
    ObjSequence {
        folder: &'static str,
        camera: Option<fn() -> Camera>,
    },
}

/// One named animated scene.
#[derive(Clone, Copy, Debug)]
pub struct AnimationEntry {
    pub name: &'static str,
    pub description: &'static str,
    pub source: AnimationSource,
}

fn explosion() -> Box<dyn Animation> {
    Box::new(Explosion::standard())
}

fn flag() -> Box<dyn Animation> {
    Box::new(Flag::standard())
}

fn bodies() -> Box<dyn Animation> {
    Box::new(RigidBodies::standard())
}

/// The view of BART's kitchen.aff at t = 0 (the `v` block of the file).
fn kitchen_camera() -> Camera {
    Camera {
        eye: Vec3::new(1.05369, 1.13876, 1.36377),
        target: Vec3::new(0.965979, 1.11824, 1.32034),
        up: Vec3::Y,
        fov_y_degrees: 40.0,
    }
}

/// All animated scenes known by name, built-ins first.
pub static ANIMATIONS: &[AnimationEntry] = &[
    AnimationEntry {
        name: "explosion",
        description: "procedural: a lumpy sphere bursts into flying triangles, 82,336 triangles (GPU kernel)",
        source: AnimationSource::Builtin(explosion),
    },
    AnimationEntry {
        name: "flag",
        description: "procedural: a cloth flag waving on a pole, 32,220 triangles (GPU kernel)",
        source: AnimationSource::Builtin(flag),
    },
    AnimationEntry {
        name: "bodies",
        description: "procedural: 36 rigid bodies moving through a room, 41,216 triangles (GPU kernel)",
        source: AnimationSource::Builtin(bodies),
    },
    AnimationEntry {
        name: "bart-kitchen",
        description: "BART kitchen, 110,561 triangles (CPU evaluation + upload)",
        source: AnimationSource::Bart("bart/kitchen/aff/kitchen.aff"),
    },
    AnimationEntry {
        name: "bart-robots",
        description: "BART robots, 71,708 triangles (CPU evaluation + upload)",
        source: AnimationSource::Bart("bart/robots/aff/Robot.aff"),
    },
    AnimationEntry {
        name: "bart-museum",
        description: "BART museum (museum5), 11,564 triangles (CPU evaluation + upload)",
        source: AnimationSource::Bart("bart/museum5/aff/museum5.aff"),
    },
    AnimationEntry {
        name: "bart-kitchen-frames",
        description: "BART kitchen reference frames 0 and 400 as an OBJ sequence, interpolated (CPU + upload)",
        source: AnimationSource::ObjSequence {
            folder: "bart/kitchen/frames",
            camera: Some(kitchen_camera),
        },
    },
];

/// The names of all registered animated scenes, in registry order.
pub fn animation_names() -> Vec<&'static str> {
    ANIMATIONS.iter().map(|e| e.name).collect()
}

/// Whether `name_or_path` names an animated scene: a registered name, a BART `.aff` file or a
/// folder (OBJ sequence).
pub fn is_animation(name_or_path: &str) -> bool {
    ANIMATIONS.iter().any(|e| e.name == name_or_path)
        || has_aff_extension(name_or_path)
        || Path::new(name_or_path).is_dir()
}

fn has_aff_extension(path: &str) -> bool {
    Path::new(path)
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("aff"))
}

/// A shared scene's path, or an error saying where we looked.
fn shared_path(name: &str, relative: &str) -> Result<PathBuf> {
    let missing = |path: PathBuf, looked: String| Error::Io {
        path,
        source: std::io::Error::new(
            std::io::ErrorKind::NotFound,
            format!(
                "shared scene '{name}' not found ({looked}); set TREELET_SCENES_DIR to the folder \
                 that holds the shared scenes (the one with bart/, cornell_box/, ...)"
            ),
        ),
    };
    match shared_scenes_dir() {
        Some(dir) => {
            let path = dir.join(relative);
            if path.exists() {
                Ok(path)
            } else {
                Err(missing(path, format!("looked in {}", dir.display())))
            }
        }
        None => Err(missing(PathBuf::from(relative), "no scenes folder".into())),
    }
}

/// Loads an animated scene by registry name (`ANIMATIONS`), from the path of a BART `.aff` file
/// (its includes relative to it), or as the OBJ sequence in a folder.
///
/// Errors: an unknown name that is no `.aff` file or folder gives `Error::UnknownScene` (listing
/// the animated scenes); a missing shared scene gives `Error::Io` (saying where it looked); BART
/// and OBJ problems (a missing `.aff` file among them) come from their loaders.
pub fn load_animation(name_or_path: &str) -> Result<Box<dyn Animation>> {
    let Some(entry) = ANIMATIONS.iter().find(|e| e.name == name_or_path) else {
        let path = Path::new(name_or_path);
        if has_aff_extension(name_or_path) {
            let name = path
                .file_stem()
                .map_or(name_or_path.into(), |s| s.to_string_lossy());
            return Ok(Box::new(BartAnimation::load(&name, path)?));
        }
        if path.is_dir() {
            return Ok(Box::new(ObjSequence::load(name_or_path, path)?));
        }
        return Err(Error::UnknownScene {
            name: name_or_path.to_owned(),
            known: animation_names().join(", "),
        });
    };
    Ok(match entry.source {
        AnimationSource::Builtin(make) => make(),
        AnimationSource::Bart(file) => Box::new(BartAnimation::load(
            entry.name,
            &shared_path(entry.name, file)?,
        )?),
        AnimationSource::ObjSequence { folder, camera } => {
            let sequence = ObjSequence::load(entry.name, &shared_path(entry.name, folder)?)?;
            Box::new(match camera {
                Some(camera) => sequence.with_camera(camera()),
                None => sequence,
            })
        }
    })
}

/// A scene to render or measure as a still: a static scene by name or path (`load_scene`), or an
/// animated scene's first frame (by name, `.aff` file or OBJ-sequence folder).
pub fn load_still(name_or_path: &str) -> Result<Scene> {
    if is_animation(name_or_path) {
        let animation = load_animation(name_or_path)?;
        return Ok(animation.scene_at(animation.time_range().start));
    }
    load_scene(name_or_path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_are_unique_and_builtins_match_their_descriptions() {
        let mut names = animation_names();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), ANIMATIONS.len());
        assert!(names.contains(&DEFAULT_ANIMATION));
        for entry in ANIMATIONS {
            if let AnimationSource::Builtin(make) = entry.source {
                let animation = make();
                assert_eq!(animation.name(), entry.name);
                let count = animation.triangle_count();
                let formatted = count
                    .to_string()
                    .as_bytes()
                    .rchunks(3)
                    .rev()
                    .map(|c| std::str::from_utf8(c).unwrap())
                    .collect::<Vec<_>>()
                    .join(",");
                assert!(
                    entry.description.contains(&formatted),
                    "{}: {count} triangles, description '{}'",
                    entry.name,
                    entry.description
                );
                assert!(count <= 100_000, "{}: keep built-ins small", entry.name);
            }
        }
    }

    #[test]
    fn unknown_names_list_the_animations() {
        match load_animation("no-such-animation") {
            Err(Error::UnknownScene { known, .. }) => assert!(known.contains("explosion")),
            Err(e) => panic!("expected UnknownScene, got {e}"),
            Ok(_) => panic!("expected UnknownScene"),
        }
    }
}
