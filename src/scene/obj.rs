//! Wavefront OBJ loading with `tobj`: every model of the file becomes triangles (polygons are
//! fan-triangulated, points and lines are skipped), MTL diffuse colours become albedos and MTL
//! emission (`Ke`) makes a material a light.
//!
//! Errors: a file that cannot be opened is `Error::Io` (with the path); anything `tobj` rejects, or
//! a face that refers to a vertex the file does not have, is `Error::Obj` (with the path and the
//! reason). A missing, unreadable or malformed material library is only a warning: the faces then
//! get the default 0.75 grey. The result is NOT sanitized (the registry does that).

use super::sanitize::DEFAULT_ALBEDO;
use super::{Camera, Material, Scene, Triangle};
use crate::geometry::Aabb;
use crate::{Error, Result};
use glam::Vec3;
use std::io::BufReader;
use std::path::Path;

/// A file whose materials emit at least this much in some channel is taken to bring its own
/// light sources (a closed, self-lit scene such as the Cornell box) and gets a black sky. Weak
/// glow (lava in Lost Empire, `Ke 0.3 0.05 0.01`) does not count, and those scenes keep the
/// bright sky that open scenes need.
const LIGHT_SOURCE_EMISSION: f32 = 1.0;

/// Sky radiance for scenes without their own light sources.
const OPEN_SKY: Vec3 = Vec3::splat(1.0);

/// Loads the OBJ file at `path` (all models) into a scene named after the file stem, framed by
/// `Camera::framing` of its finite vertices.
///
/// Materials: `Kd` is the albedo (default 0.75 grey when absent, when a face has no material or
/// when the `.mtl` is missing); `Ke` is the emission. `tobj` 4.0.5 parses `Ke` itself into
/// `tobj::Material::emissive`; it does not end up in `unknown_param`. Non-finite or negative
/// colours fall back to the defaults and albedos are clamped to [0, 1].
pub fn load_obj(path: &Path) -> Result<Scene> {
    let io_error = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let obj_error = |message: String| Error::Obj {
        path: path.to_path_buf(),
        message,
    };

    let metadata = std::fs::metadata(path).map_err(io_error)?;
    if metadata.is_dir() {
        return Err(io_error(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "is a directory, not an OBJ file",
        )));
    }
    let file = std::fs::File::open(path).map_err(io_error)?;
    let mut reader = BufReader::new(file);

    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let base_dir = path.parent().unwrap_or(Path::new(""));
    let material_loader = |mtl: &Path| load_material_library(path, &base_dir.join(mtl));
    // tobj 4.0.5 computes some indices with unchecked arithmetic that overflows (and panics with
    // overflow checks on) for absurd relative indices; turn such a panic into an error as well.
    let parsed = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut reader, &options, material_loader)
    }))
    .map_err(|_| obj_error("the OBJ parser failed on malformed input".into()))?;
    let (models, mtl_result) = parsed.map_err(|e| match e {
        tobj::LoadError::ReadError => {
            obj_error("cannot read the file as text (I/O error or invalid UTF-8)".into())
        }
        e => obj_error(e.to_string()),
    })?;

    // Failures of the material libraries were already reported by `load_material_library`.
    let mtl_materials = mtl_result.unwrap_or_default();
    let mut materials: Vec<Material> = mtl_materials.iter().map(convert_material).collect();
    let default_index = materials.len() as u32;
    let mut uses_default = false;

    let mut triangles = Vec::new();
    for model in &models {
        let mesh = &model.mesh;
        let material = match mesh.material_id {
            Some(id) if id < materials.len() => id as u32,
            _ => {
                uses_default = true;
                default_index
            }
        };
        if !mesh.indices.len().is_multiple_of(3) {
            return Err(obj_error(format!(
                "object '{}' has {} face indices, not a whole number of triangles",
                model.name,
                mesh.indices.len()
            )));
        }
        let vertex_count = mesh.positions.len() / 3;
        let vertex = |index: u32| -> Result<Vec3> {
            let i = index as usize;
            if i >= vertex_count {
                return Err(obj_error(format!(
                    "object '{}' has a face with vertex index {} but only {} vertices",
                    model.name,
                    i + 1,
                    vertex_count
                )));
            }
            Ok(Vec3::new(
                mesh.positions[3 * i],
                mesh.positions[3 * i + 1],
                mesh.positions[3 * i + 2],
            ))
        };
        triangles.reserve(mesh.indices.len() / 3);
        for face in mesh.indices.chunks_exact(3) {
            triangles.push(Triangle::new(
                vertex(face[0])?,
                vertex(face[1])?,
                vertex(face[2])?,
                material,
            ));
        }
    }
    if uses_default {
        materials.push(Material::diffuse(Vec3::splat(DEFAULT_ALBEDO)));
    }

    let has_lights = triangles.iter().any(|t| {
        materials
            .get(t.material as usize)
            .is_some_and(|m| Vec3::from(m.emission).max_element() >= LIGHT_SOURCE_EMISSION)
    });
    let sky = if has_lights { Vec3::ZERO } else { OPEN_SKY };

    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| path.display().to_string());
    Ok(Scene {
        name,
        camera: Camera::framing(&finite_bounds(&triangles)),
        triangles,
        materials,
        sky,
        lights: Vec::new(),
    })
}

/// Bounds of the finite vertices (NaN/inf vertices must not wreck the default camera); a unit box
/// at the origin when there are none.
fn finite_bounds(triangles: &[Triangle]) -> Aabb {
    let bounds = triangles
        .iter()
        .flat_map(|t| t.vertices())
        .filter(|v| v.is_finite())
        .fold(Aabb::EMPTY, Aabb::grow);
    if bounds.is_empty() {
        Aabb::new(Vec3::splat(-0.5), Vec3::splat(0.5))
    } else {
        bounds
    }
}

fn convert_material(m: &tobj::Material) -> Material {
    let albedo = m
        .diffuse
        .map(Vec3::from)
        .filter(|c| c.is_finite() && c.min_element() >= 0.0)
        .map_or(Vec3::splat(DEFAULT_ALBEDO), |c| c.min(Vec3::ONE));
    let emission = m
        .emissive
        .map(Vec3::from)
        .filter(|c| c.is_finite() && c.min_element() >= 0.0)
        .unwrap_or(Vec3::ZERO);
    Material::new(albedo, emission)
}

/// The material loader handed to tobj: reads `mtl_path`, repairs what tobj would choke on and
/// parses it. Every failure is logged as a warning (the OBJ still loads, with default materials).
fn load_material_library(obj_path: &Path, mtl_path: &Path) -> tobj::MTLLoadResult {
    let warn = |reason: &dyn std::fmt::Display| {
        log::warn!(
            "{}: material library {} not used ({reason}); its faces get the default grey",
            obj_path.display(),
            mtl_path.display()
        );
    };
    let bytes = match std::fs::read(mtl_path) {
        Ok(bytes) => bytes,
        Err(e) => {
            warn(&e);
            return Err(tobj::LoadError::OpenFileFailed);
        }
    };
    let text = String::from_utf8_lossy(&bytes);
    let text = match normalize_colour_lines(&text) {
        Ok(text) => text,
        Err(reason) => {
            warn(&reason);
            return Err(tobj::LoadError::MaterialParseError);
        }
    };
    let result = tobj::load_mtl_buf(&mut text.as_bytes());
    if let Err(e) = &result {
        warn(e);
    }
    result
}

/// tobj 4.0.5 panics on a colour statement (`Ka`/`Kd`/`Ks`/`Ke`) with fewer than three values.
/// The MTL format allows a single value meaning grey, so `Kd 0.5` is expanded to `Kd 0.5 0.5 0.5`;
/// any other short colour statement (`Kd`, `Kd 1 0`, `Kd spectral file.rfl`) is an error.
fn normalize_colour_lines(text: &str) -> std::result::Result<String, String> {
    let mut out = String::with_capacity(text.len() + 64);
    for (number, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next();
        let values: Vec<&str> = words.collect();
        match key {
            Some(key @ ("Ka" | "Kd" | "Ks" | "Ke")) if values.len() < 3 => {
                if let [value] = values[..] {
                    out.push_str(&format!("{key} {value} {value} {value}"));
                } else {
                    return Err(format!(
                        "line {}: '{}' needs three colour values",
                        number + 1,
                        line.trim()
                    ));
                }
            }
            _ => out.push_str(line),
        }
        out.push('\n');
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    /// A fresh directory under the system temp dir for one test.
    fn temp_dir(test: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!(
            "treelet-obj-{}-{}-{test}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_nanos())
                .unwrap_or(0)
        ));
        std::fs::create_dir_all(&dir).expect("create temp dir");
        dir
    }

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        let path = dir.join(name);
        std::fs::write(&path, text).expect("write temp file");
        path
    }

    const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";

    #[test]
    fn loads_quad_with_materials_and_light() {
        let dir = temp_dir("materials");
        write(
            &dir,
            "m.mtl",
            "newmtl red\nKd 0.8 0.1 0.1\nnewmtl lamp\nKd 0.5\nKe 10 10 10\n",
        );
        let path = write(
            &dir,
            "quad.obj",
            &format!("mtllib m.mtl\n{QUAD}usemtl red\nf 1 2 3 4\nusemtl lamp\nf 1 3 4\n"),
        );
        let scene = load_obj(&path).expect("loads");
        assert_eq!(scene.name, "quad");
        assert_eq!(scene.triangles.len(), 3);
        assert_eq!(scene.materials.len(), 2);
        assert_eq!(scene.materials[0].albedo, [0.8, 0.1, 0.1]);
        assert_eq!(scene.materials[1].albedo, [0.5; 3]);
        assert_eq!(scene.materials[1].emission, [10.0; 3]);
        assert_eq!(scene.triangles[0].material, 0);
        assert_eq!(scene.triangles[2].material, 1);
        assert_eq!(scene.sky, Vec3::ZERO, "a self-lit scene has a black sky");
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn missing_mtl_is_a_warning_and_faces_get_grey() {
        let dir = temp_dir("nomtl");
        let path = write(
            &dir,
            "a.obj",
            &format!("mtllib nowhere.mtl\n{QUAD}usemtl red\nf 1 2 3\n"),
        );
        let scene = load_obj(&path).expect("loads without its .mtl");
        assert_eq!(scene.triangles.len(), 1);
        assert_eq!(
            scene.materials,
            vec![Material::diffuse(Vec3::splat(DEFAULT_ALBEDO))]
        );
        assert_eq!(scene.triangles[0].material, 0);
        assert_eq!(scene.sky, OPEN_SKY);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn malformed_mtl_is_a_warning() {
        let dir = temp_dir("badmtl");
        write(&dir, "m.mtl", "newmtl x\nKd 1 0\n");
        let path = write(
            &dir,
            "a.obj",
            &format!("mtllib m.mtl\n{QUAD}usemtl x\nf 1 2 3\n"),
        );
        let scene = load_obj(&path).expect("loads despite a broken .mtl");
        assert_eq!(scene.triangles.len(), 1);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn errors_never_panic() {
        let dir = temp_dir("errors");
        for (name, text) in [
            ("short_vertex.obj", "v 1 2\nf 1 1 1\n"),
            ("out_of_range.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99\n"),
            ("zero_index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n"),
            ("negative.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -1 -2 -9\n"),
            ("text.obj", "v a b c\n"),
            ("face_text.obj", "v 0 0 0\nf x y z\n"),
            (
                "tex_range.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/5 2/1 3/1\n",
            ),
            ("w_zero.obj", "v 1 2 3 0\n"),
            // Overflows tobj's index arithmetic (a panic with overflow checks, caught).
            (
                "tex_overflow.obj",
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-5 2/1 3/1\n",
            ),
        ] {
            let path = write(&dir, name, text);
            match load_obj(&path) {
                Err(Error::Obj { path: p, message }) => {
                    assert_eq!(p, path);
                    assert!(!message.is_empty());
                }
                other => panic!("{name}: expected Error::Obj, got {other:?}"),
            }
        }
        let missing = dir.join("missing.obj");
        assert!(matches!(load_obj(&missing), Err(Error::Io { path, .. }) if path == missing));
        assert!(matches!(load_obj(&dir), Err(Error::Io { .. })));
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn points_and_lines_are_skipped_and_polygons_fanned() {
        let dir = temp_dir("fan");
        let path = write(
            &dir,
            "p.obj",
            "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\np 1\nl 1 2\nf 1 2 3 4 5\n",
        );
        let scene = load_obj(&path).expect("loads");
        assert_eq!(scene.triangles.len(), 3);
        let _ = std::fs::remove_dir_all(dir);
    }

    #[test]
    fn colour_lines_are_normalized() {
        assert_eq!(
            normalize_colour_lines("Kd 0.5\n  Ke 1 2 3\n").as_deref(),
            Ok("Kd 0.5 0.5 0.5\n  Ke 1 2 3\n")
        );
        assert!(normalize_colour_lines("Ka\n").is_err());
        assert!(normalize_colour_lines("Ks spectral a.rfl\n").is_err());
    }
}
