//! BART scenes: the animated benchmark scenes of Lext, Assarsson and Möller, "BART: A Benchmark
//! for Animated Ray Tracing" (IEEE CG&A, 2001), in their AFF format, an extension of Eric
//! Haines' NFF. `BartScene::load` parses a scene file with its includes; `BartScene::evaluate`
//! writes the triangles at any time, always the same number in the same order (for BVH refits).
//!
//! Files: `parser` (AFF text → tree of transforms and shapes, animations, materials, view),
//! `spline` (Kochanek–Bartels key-frame tracks), `evaluate` (`BartScene`).
//!
//! Supported commands:
//! * geometry: `p` and `pp` polygons (fan-triangulated: (0, k+1, k+2); normals dropped), `tt`
//!   and `ttp` textured triangles (one triangle; texture data dropped), `m` indexed meshes
//!   (`vertices`, optional `normals` and `texturecoords`, `triangles`), `c` cones/cylinders
//!   (open frusta of `CONE_SIDES` = 16 sides, 32 triangles), `tpa` animated triangles (linear
//!   interpolation between their keys, clamped outside them);
//! * structure: `i detail file` includes (relative to the including file's folder; skipped when
//!   `detail` exceeds the level set with `d`, 0 by default), `xs sx sy sz  rx ry rz degrees
//!   tx ty tz { … }` static transforms (scale, then rotation about the axis, then translation:
//!   T·R·S; this is the order in the files and in BART's `parse.c`), `x name { … }` animated
//!   transforms and `k name { … }` key frames (`transl`, `rot`, `scale`, `visibility` tracks);
//! * materials: `f r g b Kd Ks shine T ior` (albedo = Kd·rgb) and `fm ambient diffuse specular
//!   shine T ior` (albedo = diffuse), clamped to [0, 1]; AFF has no emissive material, so no
//!   triangle emits. As in BART, the current material carries over to everything that follows,
//!   across transform blocks and files; before the first one it is 0.75 grey;
//! * `v` view (camera; animated by the key frames named `camera`: position from `transl`,
//!   looking down the rotated −z axis with the rotated +y up), `a t0 t1 N` animation range, `b`
//!   background colour (used as the sky);
//! * `l x y z [r g b]` static point lights (white without a colour), in world coordinates, lit
//!   as BART's Whitted-style renderer does (see `PointLight`).
//!
//! Ignored (read, checked and dropped): animated lights `la` and spheres `s` (each with a
//! warning; neither occurs in the BART scenes), ambient light `am`. Comments start with `#` or `%`
//! and run to the end of the line. Unknown commands are errors (`Error::Aff`), as in BART's
//! reader: their length is unknown, so skipping them would misread what follows.
//!
//! Evaluation conventions: those of the reference frames in the shared scenes folder
//! (`scenes/bart/<scene>/frames`), which `tests/bart.rs` matches to their print precision (about
//! 6e-7 of the scene's diagonal):
//! * frame f is at t = t0 + (t1 − t0)·f/(N − 1);
//! * an animated transform is T·R·S of its tracks at t (identity for a missing track), applied
//!   below its parent's transform; each track is a Kochanek–Bartels spline per component with
//!   the tangents (and the uneven-spacing correction) of BART's `kbsplpos.c`, through all keys,
//!   clamped before the first and after the last (see `spline`);
//! * `rot` tracks are splined on (axis x, axis y, axis z, angle in degrees), and the axis is
//!   normalised afterwards;
//! * an `x` transform whose name has no `k` keys is the identity (with a warning), as in BART's
//!   code (`GetMatrix`); the robots scene has five. When a name has keys twice (the kitchen
//!   includes one wheel file twice), the last definition counts, as in BART;
//! * visibility tracks (none occurs in the BART scenes) keep the triangle count fixed: the
//!   triangles of an invisible subtree collapse to a point;
//! * cameras, lights and materials do not affect the geometry.
//!
//! Deliberate differences from BART's reference code (`parse.c`, `animation.c`, `kbsplpos.c`,
//! `kbsplrot.c`), all to match the reference frames:
//! * BART uses the first and the last key of a track only to shape the tangents (its curve runs
//!   from the second key to the next-to-last one and clamps there); here the curve runs through
//!   every key, and a missing neighbour of an end key is that key itself. This changes the
//!   motion only before the second key and after the next-to-last one;
//! * BART interpolates rotations as quaternions (a Kochanek–Bartels squad spline); here the
//!   axis-angle components are splined. The two agree at the keys and differ a little between;
//! * static `xs` transforms read scale, rotation and translation in THAT order on the line
//!   (`xs sx sy sz  rx ry rz degrees  tx ty tz`), as in BART's `parse.c` and the scene files.
//!
//! Key times that go backwards (a gun rotation track of the robots scene) are accepted and
//! handled as in BART's code: the first segment whose end time lies beyond t is used.

mod evaluate;
mod parser;
mod spline;

pub use evaluate::{BartScene, CONE_SIDES};
