//! `BartScene`: a parsed BART scene flattened for fast per-frame evaluation.
//!
//! Loading turns the node tree into a list of transforms (parents before children) and the
//! shapes into triangles with fixed slots, in file order. Triangles under static transforms only
//! are transformed once, at load time, into a template; each evaluation copies the template and
//! rewrites just the slots of the animated geometry (rigid parts under `x` transforms, and the
//! `tpa` morphing triangles). The triangle count and order never change with time.

use super::parser::{parse_file, AnimationRange, MorphKey, Node, ParsedAff, Shape, View};
use super::spline::Animation;
use crate::geometry::Aabb;
use crate::scene::{Camera, Material, PointLight, Scene, Triangle};
use crate::Result;
use glam::{Affine3A, DAffine3, DVec3, Vec3};
use std::collections::HashMap;
use std::path::Path;

/// Cones and cylinders (`c`) are open frusta with this many sides (2 triangles per side).
pub const CONE_SIDES: usize = 16;

/// Sky radiance when the file sets no background colour (`b`).
const DEFAULT_SKY: Vec3 = Vec3::ONE;

/// A transform of the flattened tree. Index 0 is the root (identity).
#[derive(Clone, Debug)]
struct Xform {
    /// `None` only for the root; otherwise an index below this one.
    parent: Option<usize>,
    local: Local,
    /// True if this transform or one of its ancestors is animated.
    dynamic: bool,
}

#[derive(Clone, Debug)]
enum Local {
    Static(DAffine3),
    /// Index into `BartScene::animations`.
    Animated(usize),
}

/// Consecutive rigid triangles (polygons, meshes, cones) under one animated transform.
#[derive(Clone, Debug)]
struct RigidChunk {
    xform: usize,
    /// Slot of the first triangle in the output.
    first: usize,
    /// Local (untransformed) vertex positions.
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    materials: Vec<u32>,
}

/// One `tpa` triangle.
#[derive(Clone, Debug)]
struct MorphTriangle {
    xform: usize,
    slot: usize,
    material: u32,
    keys: Vec<MorphKey>,
}

/// A BART (AFF) scene ready to be evaluated at any time. See the `bart` module documentation
/// for the supported commands and the conventions.
#[derive(Clone, Debug)]
pub struct BartScene {
    name: String,
    xforms: Vec<Xform>,
    animations: Vec<Animation>,
    /// All triangles with the static ones in place (the animated slots are overwritten).
    template: Vec<Triangle>,
    rigid: Vec<RigidChunk>,
    morphs: Vec<MorphTriangle>,
    materials: Vec<Material>,
    view: Option<View>,
    /// Index of the animation named `camera`, if any.
    camera_animation: Option<usize>,
    range: AnimationRange,
    sky: Vec3,
    lights: Vec<PointLight>,
}

impl BartScene {
    /// Parses the AFF file at `path` (and its includes) and prepares it for evaluation.
    ///
    /// Errors: `Error::Io` if `path` cannot be read; `Error::Aff` (file and line) for any syntax
    /// error in it or in an included file, and for an include that cannot be read. An `x`
    /// transform whose name has no `k` keys is the identity (with a warning), as in BART.
    pub fn load(path: &Path) -> Result<BartScene> {
        let parsed = parse_file(path)?;
        let name = path
            .file_stem()
            .map_or_else(|| "bart".to_string(), |s| s.to_string_lossy().into_owned());
        Ok(Flattener::run(name, parsed))
    }

    /// `(start time, end time, number of frames)` from the file's `a` line; `(0, 0, 1)` without one.
    pub fn time_range(&self) -> (f32, f32, u32) {
        (
            self.range.start as f32,
            self.range.end as f32,
            self.range.frames,
        )
    }

    /// Time of `frame`: t0 + (t1 − t0)·frame/(N − 1) (t0 for a one-frame animation). Frames past
    /// the last one continue the same step (all tracks clamp at their ends).
    pub fn frame_time(&self, frame: u32) -> f32 {
        let AnimationRange { start, end, frames } = self.range;
        if frames <= 1 {
            return start as f32;
        }
        (start + (end - start) * f64::from(frame) / f64::from(frames - 1)) as f32
    }

    /// Number of triangles every evaluation produces.
    pub fn triangle_count(&self) -> usize {
        self.template.len()
    }

    /// The materials the triangles' `material` fields index.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// The camera at time `t`, as `to_scene(t)` sets it (the triangles are evaluated only for a
    /// file without a view, whose camera frames their bounds).
    pub fn camera(&self, t: f32) -> Camera {
        if self.view.is_some() {
            self.camera_at(f64::from(t), &Aabb::EMPTY)
        } else {
            self.to_scene(t).camera
        }
    }

    /// The background colour (`b`), used as the sky; white without one.
    pub fn sky(&self) -> Vec3 {
        self.sky
    }

    /// The static point lights (`l`).
    pub fn lights(&self) -> &[PointLight] {
        &self.lights
    }

    /// Writes the scene's triangles at time `t` into `out` (cleared first): always
    /// `triangle_count()` triangles in the same order with the same materials, so consecutive
    /// frames can refit one BVH. Triangles under a transform that is invisible at `t` (a
    /// `visibility` track) collapse to a point.
    pub fn evaluate(&self, t: f32, out: &mut Vec<Triangle>) {
        let t = f64::from(t);
        out.clear();
        out.extend_from_slice(&self.template);
        if self.rigid.is_empty() && self.morphs.is_empty() {
            return;
        }
        let (world, visible) = self.world_transforms(t);
        for chunk in &self.rigid {
            let m = world[chunk.xform];
            let slots = &mut out[chunk.first..chunk.first + chunk.triangles.len()];
            if visible[chunk.xform] {
                let p = &chunk.positions;
                for ((slot, tri), &material) in
                    slots.iter_mut().zip(&chunk.triangles).zip(&chunk.materials)
                {
                    *slot = Triangle::new(
                        m.transform_point3(p[tri[0] as usize]),
                        m.transform_point3(p[tri[1] as usize]),
                        m.transform_point3(p[tri[2] as usize]),
                        material,
                    );
                }
            } else {
                let point = Vec3::from(m.translation);
                for (slot, &material) in slots.iter_mut().zip(&chunk.materials) {
                    *slot = Triangle::new(point, point, point, material);
                }
            }
        }
        let tf = t as f32;
        for morph in &self.morphs {
            let m = world[morph.xform];
            let [a, b, c] = if visible[morph.xform] {
                morph_vertices(&morph.keys, tf).map(|v| m.transform_point3(v))
            } else {
                [Vec3::from(m.translation); 3]
            };
            out[morph.slot] = Triangle::new(a, b, c, morph.material);
        }
    }

    /// The scene at time `t`: triangles, materials, the camera of the file's `v` view (moved by
    /// the `camera` animation when there is one; `Camera::framing` of the bounds without a
    /// view) and the background colour as the sky (white without a `b` line). Not sanitized.
    pub fn to_scene(&self, t: f32) -> Scene {
        let mut triangles = Vec::with_capacity(self.template.len());
        self.evaluate(t, &mut triangles);
        let bounds = triangles
            .iter()
            .fold(Aabb::EMPTY, |b, tri| b.union(tri.bounds()));
        Scene {
            name: self.name.clone(),
            camera: self.camera_at(f64::from(t), &bounds),
            triangles,
            materials: self.materials.clone(),
            sky: self.sky,
            lights: self.lights.clone(),
        }
    }

    fn camera_at(&self, t: f64, bounds: &Aabb) -> Camera {
        let mut camera = match self.view {
            Some(view) => Camera {
                eye: view.from,
                target: view.at,
                up: view.up,
                fov_y_degrees: view.angle,
            },
            None => Camera::framing(bounds),
        };
        if let Some(animation) = self.camera_animation.map(|i| &self.animations[i]) {
            let focus = (camera.target - camera.eye).length().max(1e-3);
            let mut dir = (camera.target - camera.eye).normalize_or(Vec3::NEG_Z);
            if animation.translation.is_some() {
                camera.eye = animation.translation_at(t).as_vec3();
            }
            if animation.rotation.is_some() {
                // BART's viewer looks down its −z axis with +y up.
                let rotation = animation.rotation_at(t);
                dir = (rotation * DVec3::NEG_Z).as_vec3();
                camera.up = (rotation * DVec3::Y).as_vec3();
            }
            camera.target = camera.eye + dir * focus;
        }
        camera
    }

    /// World transform (f32, for vertices) and visibility of every transform at time `t`.
    fn world_transforms(&self, t: f64) -> (Vec<Affine3A>, Vec<bool>) {
        let mut world = Vec::with_capacity(self.xforms.len());
        let mut world32 = Vec::with_capacity(self.xforms.len());
        let mut visible = Vec::with_capacity(self.xforms.len());
        for xform in &self.xforms {
            let (parent, parent_visible) = match xform.parent {
                Some(p) => (world[p], visible[p]),
                None => (DAffine3::IDENTITY, true),
            };
            let (local, local_visible) = match &xform.local {
                Local::Static(m) => (*m, true),
                Local::Animated(a) => {
                    let animation = &self.animations[*a];
                    (animation.transform_at(t), animation.visible_at(t))
                }
            };
            let m = parent * local;
            world.push(m);
            world32.push(m.as_affine3a());
            visible.push(parent_visible && local_visible);
        }
        (world32, visible)
    }
}

/// Linear interpolation between the two keys around `t`, clamped to the first/last key.
fn morph_vertices(keys: &[MorphKey], t: f32) -> [Vec3; 3] {
    let next = keys.partition_point(|k| k.time <= t);
    if next == 0 {
        return keys[0].vertices;
    }
    if next == keys.len() {
        return keys[keys.len() - 1].vertices;
    }
    let (a, b) = (&keys[next - 1], &keys[next]);
    let s = (t - a.time) / (b.time - a.time);
    std::array::from_fn(|i| a.vertices[i].lerp(b.vertices[i], s))
}

/// Vertices and triangles of an open frustum with `CONE_SIDES` sides: a ring of vertices around
/// the base and one around the apex, both starting in the direction axis × (the coordinate axis
/// least aligned with the cone's axis) and turning counter-clockwise about the axis; side k gives
/// the triangles (base k, base k+1, apex k) and (apex k, base k+1, apex k+1).
fn cone_mesh(
    base: Vec3,
    base_radius: f32,
    apex: Vec3,
    apex_radius: f32,
) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let axis = (apex - base).normalize();
    let least = axis.abs().min_position();
    let u = axis.cross(Vec3::AXES[least]).normalize();
    let v = axis.cross(u);
    let n = CONE_SIDES;
    let mut positions = Vec::with_capacity(2 * n);
    for (center, radius) in [(base, base_radius), (apex, apex_radius)] {
        for k in 0..n {
            let angle = std::f32::consts::TAU * k as f32 / n as f32;
            positions.push(center + radius * (angle.cos() * u + angle.sin() * v));
        }
    }
    let mut triangles = Vec::with_capacity(2 * n);
    for k in 0..n {
        let next = (k + 1) % n;
        let (b0, b1, a0, a1) = (k as u32, next as u32, (n + k) as u32, (n + next) as u32);
        triangles.push([b0, b1, a0]);
        triangles.push([a0, b1, a1]);
    }
    (positions, triangles)
}

/// Builds a `BartScene` from the parsed tree.
struct Flattener {
    animation_ids: HashMap<String, usize>,
    xforms: Vec<Xform>,
    /// World transform of each static transform (identity placeholder for dynamic ones).
    static_world: Vec<DAffine3>,
    template: Vec<Triangle>,
    rigid: Vec<RigidChunk>,
    morphs: Vec<MorphTriangle>,
}

impl Flattener {
    fn run(name: String, parsed: ParsedAff) -> BartScene {
        let ParsedAff {
            nodes,
            animations,
            materials,
            view,
            range,
            background,
            lights,
        } = parsed;
        let mut names: Vec<String> = animations.keys().cloned().collect();
        names.sort();
        let animation_ids: HashMap<String, usize> = names
            .iter()
            .enumerate()
            .map(|(i, n)| (n.clone(), i))
            .collect();
        let mut animations_by_name = animations;
        let animations: Vec<Animation> = names
            .iter()
            .filter_map(|n| animations_by_name.remove(n))
            .collect();
        let camera_animation = animation_ids.get("camera").copied();
        let mut flat = Flattener {
            animation_ids,
            xforms: vec![Xform {
                parent: None,
                local: Local::Static(DAffine3::IDENTITY),
                dynamic: false,
            }],
            static_world: vec![DAffine3::IDENTITY],
            template: Vec::new(),
            rigid: Vec::new(),
            morphs: Vec::new(),
        };
        flat.walk(&nodes, 0);
        BartScene {
            name,
            xforms: flat.xforms,
            animations,
            template: flat.template,
            rigid: flat.rigid,
            morphs: flat.morphs,
            materials,
            view,
            camera_animation,
            range: range.unwrap_or(AnimationRange {
                start: 0.0,
                end: 0.0,
                frames: 1,
            }),
            sky: background.unwrap_or(DEFAULT_SKY),
            lights,
        }
    }

    fn walk(&mut self, nodes: &[Node], xform: usize) {
        for node in nodes {
            match node {
                Node::Static {
                    transform,
                    children,
                } => {
                    let dynamic = self.xforms[xform].dynamic;
                    let world = if dynamic {
                        DAffine3::IDENTITY
                    } else {
                        self.static_world[xform] * *transform
                    };
                    let child = self.push_xform(xform, Local::Static(*transform), dynamic, world);
                    self.walk(children, child);
                }
                Node::Animated {
                    name,
                    location,
                    children,
                } => {
                    let child = match self.animation_ids.get(name) {
                        Some(&id) => {
                            self.push_xform(xform, Local::Animated(id), true, DAffine3::IDENTITY)
                        }
                        None => {
                            // BART's GetMatrix gives the identity for a name without keys (the
                            // robots scene has five such transforms).
                            log::warn!(
                                "{}:{}: transform '{name}' has no 'k {name}' keys; using the \
                                 identity",
                                location.file.display(),
                                location.line
                            );
                            let dynamic = self.xforms[xform].dynamic;
                            let world = self.static_world[xform];
                            let local = Local::Static(DAffine3::IDENTITY);
                            self.push_xform(xform, local, dynamic, world)
                        }
                    };
                    self.walk(children, child);
                }
                Node::Shape { shape, material } => self.add_shape(shape, *material, xform),
            }
        }
    }

    fn push_xform(&mut self, parent: usize, local: Local, dynamic: bool, world: DAffine3) -> usize {
        self.xforms.push(Xform {
            parent: Some(parent),
            local,
            dynamic,
        });
        self.static_world.push(world);
        self.xforms.len() - 1
    }

    fn add_shape(&mut self, shape: &Shape, material: u32, xform: usize) {
        let cone;
        let (positions, triangles): (&[Vec3], Vec<[u32; 3]>) = match shape {
            Shape::Polygon(vertices) => {
                let fan = (1..vertices.len() as u32 - 1)
                    .map(|k| [0, k, k + 1])
                    .collect();
                (vertices, fan)
            }
            Shape::Mesh {
                positions,
                triangles,
            } => (positions, triangles.clone()),
            Shape::Cone {
                base,
                base_radius,
                apex,
                apex_radius,
            } => {
                cone = cone_mesh(*base, *base_radius, *apex, *apex_radius);
                (&cone.0, cone.1)
            }
            Shape::Morph(keys) => {
                let slot = self.template.len();
                self.template
                    .push(Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, material));
                self.morphs.push(MorphTriangle {
                    xform,
                    slot,
                    material,
                    keys: keys.clone(),
                });
                return;
            }
        };
        let first = self.template.len();
        if self.xforms[xform].dynamic {
            self.template.extend(std::iter::repeat_n(
                Triangle::new(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, material),
                triangles.len(),
            ));
            let chunk = match self.rigid.last_mut() {
                Some(c) if c.xform == xform && c.first + c.triangles.len() == first => c,
                _ => {
                    self.rigid.push(RigidChunk {
                        xform,
                        first,
                        positions: Vec::new(),
                        triangles: Vec::new(),
                        materials: Vec::new(),
                    });
                    self.rigid.last_mut().expect("just pushed")
                }
            };
            let offset = chunk.positions.len() as u32;
            chunk.positions.extend_from_slice(positions);
            chunk
                .triangles
                .extend(triangles.iter().map(|t| t.map(|i| i + offset)));
            chunk
                .materials
                .extend(std::iter::repeat_n(material, triangles.len()));
        } else {
            let m = self.static_world[xform];
            let world: Vec<Vec3> = positions
                .iter()
                .map(|p| m.transform_point3(p.as_dvec3()).as_vec3())
                .collect();
            self.template.extend(triangles.iter().map(|t| {
                Triangle::new(
                    world[t[0] as usize],
                    world[t[1] as usize],
                    world[t[2] as usize],
                    material,
                )
            }));
        }
    }
}
