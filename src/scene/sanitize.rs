//! The bad-geometry policy: `sanitize` removes triangles the BVH builders and the tracer cannot
//! handle and repairs material references, reporting what it changed.
//!
//! Policy, applied to every triangle in order:
//!
//! 1. **Non-finite** (`SanitizeReport::non_finite`): a triangle with any vertex coordinate that is
//!    NaN or ±infinity is dropped.
//! 2. **Overflowing** (`SanitizeReport::overflowing`): a triangle whose coordinates are finite but
//!    so large that its edges or their cross product overflow `f32` is dropped (its area, and
//!    every box or SAH cost that contains it, would be infinite).
//! 3. **Degenerate** (`SanitizeReport::degenerate`): a triangle whose edge cross product
//!    `(v1 - v0) × (v2 - v0)` is exactly the zero vector is dropped: repeated vertices, collinear
//!    vertices, or a triangle so small that its area underflows to zero in `f32`. Thin triangles
//!    with a non-zero cross product are kept.
//! 4. **Bad material** (`SanitizeReport::bad_material`): a surviving triangle whose material index
//!    is not below `materials.len()` is kept and re-pointed at a default material, a non-emissive
//!    0.75 grey (`DEFAULT_ALBEDO`) appended once to the end of the material list (only when at
//!    least one triangle needs it). Existing materials and indices are never renumbered.
//!
//! Triangle order is otherwise preserved. When anything changed, one `log::warn!` line sums it up.
//! A scene can end up with no triangles; the caller decides what that means (the registry reports
//! `Error::EmptyScene`).

use super::{Material, Scene, Triangle};
use glam::Vec3;

/// Albedo of the material that replaces out-of-range material indices (and of OBJ faces without one).
pub const DEFAULT_ALBEDO: f32 = 0.75;

/// What `sanitize` removed or repaired; all zero for a clean scene.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub struct SanitizeReport {
    /// Triangles dropped for a NaN/infinite coordinate.
    pub non_finite: usize,
    /// Triangles dropped because their edges or edge cross product overflow `f32`.
    pub overflowing: usize,
    /// Triangles dropped for zero area (edge cross product exactly zero).
    pub degenerate: usize,
    /// Triangles kept but re-pointed at the appended default material.
    pub bad_material: usize,
}

impl SanitizeReport {
    /// Whether sanitizing changed nothing.
    pub fn is_clean(&self) -> bool {
        *self == Self::default()
    }
}

enum Verdict {
    Keep,
    NonFinite,
    Overflowing,
    Degenerate,
}

fn classify(t: &Triangle) -> Verdict {
    let [a, b, c] = t.vertices();
    if !(a.is_finite() && b.is_finite() && c.is_finite()) {
        return Verdict::NonFinite;
    }
    let n = (b - a).cross(c - a);
    if !n.is_finite() {
        Verdict::Overflowing
    } else if n == Vec3::ZERO {
        Verdict::Degenerate
    } else {
        Verdict::Keep
    }
}

/// Applies the policy in the module documentation to `scene` in place and reports what it did.
pub fn sanitize(scene: &mut Scene) -> SanitizeReport {
    let mut report = SanitizeReport::default();
    scene.triangles.retain(|t| match classify(t) {
        Verdict::Keep => true,
        Verdict::NonFinite => {
            report.non_finite += 1;
            false
        }
        Verdict::Overflowing => {
            report.overflowing += 1;
            false
        }
        Verdict::Degenerate => {
            report.degenerate += 1;
            false
        }
    });

    let material_count = scene.materials.len();
    // Index of the default material, pushed on first use.
    let mut default_material: Option<u32> = None;
    for t in &mut scene.triangles {
        if (t.material as usize) < material_count {
            continue;
        }
        let index = *default_material.get_or_insert_with(|| {
            scene
                .materials
                .push(Material::diffuse(Vec3::splat(DEFAULT_ALBEDO)));
            // The scene's triangles index materials with u32, so this count fits.
            material_count as u32
        });
        t.material = index;
        report.bad_material += 1;
    }

    if !report.is_clean() {
        log::warn!(
            "scene '{}': dropped {} triangle(s) with non-finite coordinates, {} with coordinates \
             so large that their edges overflow f32, and {} zero-area triangle(s); {} triangle(s) \
             with an out-of-range material now use a default grey; {} triangle(s) left",
            scene.name,
            report.non_finite,
            report.overflowing,
            report.degenerate,
            report.bad_material,
            scene.triangles.len()
        );
    }
    report
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Camera;

    fn scene(triangles: Vec<Triangle>, materials: usize) -> Scene {
        Scene {
            name: "test".into(),
            triangles,
            materials: vec![Material::diffuse(Vec3::splat(0.5)); materials],
            camera: Camera {
                eye: Vec3::Z,
                target: Vec3::ZERO,
                up: Vec3::Y,
                fov_y_degrees: 45.0,
            },
            sky: Vec3::ONE,
            lights: Vec::new(),
        }
    }

    fn tri(a: [f32; 3], b: [f32; 3], c: [f32; 3], material: u32) -> Triangle {
        Triangle::new(a.into(), b.into(), c.into(), material)
    }

    fn good(material: u32) -> Triangle {
        tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], material)
    }

    #[test]
    fn clean_scene_is_untouched() {
        let mut s = scene(vec![good(0), good(1)], 2);
        let before = s.clone();
        let report = sanitize(&mut s);
        assert!(report.is_clean());
        assert_eq!(s.triangles, before.triangles);
        assert_eq!(s.materials, before.materials);
    }

    #[test]
    fn non_finite_and_overflowing_triangles_are_dropped() {
        let mut s = scene(
            vec![
                tri([f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 0),
                good(0),
                tri(
                    [0.0, 0.0, 0.0],
                    [f32::INFINITY, 0.0, 0.0],
                    [0.0, 1.0, 0.0],
                    0,
                ),
                tri(
                    [0.0, 0.0, 0.0],
                    [1.0, 0.0, 0.0],
                    [0.0, f32::NEG_INFINITY, 0.0],
                    0,
                ),
                // Finite, but the edges overflow f32.
                tri([-3e38, 0.0, 0.0], [3e38, 0.0, 0.0], [0.0, 3e38, 0.0], 0),
                // Finite edges whose cross product overflows.
                tri([0.0, 0.0, 0.0], [1e20, 0.0, 0.0], [0.0, 1e20, 0.0], 0),
            ],
            1,
        );
        let report = sanitize(&mut s);
        assert_eq!(
            report,
            SanitizeReport {
                non_finite: 3,
                overflowing: 2,
                ..Default::default()
            }
        );
        assert_eq!(s.triangles, vec![good(0)]);
    }

    #[test]
    fn zero_area_triangles_are_dropped() {
        let mut s = scene(
            vec![
                // Repeated vertex.
                tri([1.0, 2.0, 3.0], [1.0, 2.0, 3.0], [0.0, 1.0, 0.0], 0),
                // All three equal (an OBJ point).
                tri([1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0], 0),
                // Collinear.
                tri([0.0, 0.0, 0.0], [1.0, 1.0, 1.0], [2.0, 2.0, 2.0], 0),
                good(0),
                // Thin but not degenerate: kept.
                tri([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.5, 1e-3, 0.0], 0),
            ],
            1,
        );
        let report = sanitize(&mut s);
        assert_eq!(
            report,
            SanitizeReport {
                degenerate: 3,
                ..Default::default()
            }
        );
        assert_eq!(s.triangles.len(), 2);
        assert_eq!(s.triangles[0], good(0));
    }

    #[test]
    fn out_of_range_materials_use_one_appended_default() {
        let mut s = scene(vec![good(0), good(2), good(u32::MAX), good(1)], 2);
        let report = sanitize(&mut s);
        assert_eq!(
            report,
            SanitizeReport {
                bad_material: 2,
                ..Default::default()
            }
        );
        assert_eq!(s.materials.len(), 3);
        assert_eq!(
            s.materials[2],
            Material::diffuse(Vec3::splat(DEFAULT_ALBEDO))
        );
        let ids: Vec<u32> = s.triangles.iter().map(|t| t.material).collect();
        assert_eq!(ids, vec![0, 2, 2, 1]);
    }

    #[test]
    fn no_materials_at_all() {
        let mut s = scene(vec![good(0), good(0)], 0);
        let report = sanitize(&mut s);
        assert_eq!(report.bad_material, 2);
        assert_eq!(s.materials.len(), 1);
        assert!(s.triangles.iter().all(|t| t.material == 0));
    }

    #[test]
    fn dropped_triangles_do_not_count_as_bad_material() {
        let mut s = scene(
            vec![
                tri([f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], 7),
                tri([0.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], 7),
            ],
            1,
        );
        let report = sanitize(&mut s);
        assert_eq!(
            report,
            SanitizeReport {
                non_finite: 1,
                degenerate: 1,
                ..Default::default()
            }
        );
        assert!(s.triangles.is_empty());
        assert_eq!(s.materials.len(), 1);
    }
}
