//! The AFF parser: reads a BART scene file and the files it includes into a tree of nodes
//! (static `xs` transforms, animated `x` transforms by name, and shapes with their material),
//! the named animations (`k`), the materials, the view, the animation parameters and the
//! background colour.
//!
//! The file is read as a stream of whitespace-separated tokens (`{` and `}` are tokens on their
//! own; `#` and `%` start a comment that runs to the end of the line), so a command's numbers may
//! span lines, as with BART's `fscanf`-based reader. Every syntax error is `Error::Aff` with the
//! file and the line of the offending token (for a file that ends inside a command: the line
//! where that command starts; for an unclosed transform: the line of its `x`/`xs`). Unknown
//! commands are errors too, as in BART's reader: their length is unknown, so skipping them
//! would misread what follows.

use super::spline::{axis_angle, Animation, Key, Spline};
use crate::scene::sanitize::DEFAULT_ALBEDO;
use crate::scene::{Material, PointLight};
use crate::{Error, Result};
use glam::{DAffine3, DVec3, Vec3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// How deep includes may nest (a guard against runaway recursion; BART's scenes use 3 levels).
const MAX_INCLUDE_DEPTH: usize = 32;

/// Where something was written: a file and a 1-based line.
#[derive(Clone, Debug)]
pub(super) struct Location {
    pub file: Arc<Path>,
    pub line: usize,
}

fn aff_error(path: &Path, line: usize, message: impl Into<String>) -> Error {
    Error::Aff {
        path: path.to_path_buf(),
        line,
        message: message.into(),
    }
}

/// A node of the scene tree, in file order.
#[derive(Clone, Debug)]
pub(super) enum Node {
    /// `xs sx sy sz  rx ry rz degrees  tx ty tz { … }`: children transformed by T·R·S.
    Static {
        transform: DAffine3,
        children: Vec<Node>,
    },
    /// `x name { … }`: children transformed by the animation `name` (T·R·S at each time).
    Animated {
        name: String,
        location: Location,
        children: Vec<Node>,
    },
    /// A primitive with the index of its material in `ParsedAff::materials`.
    Shape { shape: Shape, material: u32 },
}

/// The primitives, in the coordinates of the enclosing transform.
#[derive(Clone, Debug)]
pub(super) enum Shape {
    /// `p`, `pp` (normals dropped), `tt`/`ttp` (one triangle; texture data dropped): a convex
    /// polygon of at least 3 vertices, fan-triangulated (0, k+1, k+2).
    Polygon(Vec<Vec3>),
    /// `m`: an indexed triangle mesh (normals and texture coordinates dropped).
    Mesh {
        positions: Vec<Vec3>,
        triangles: Vec<[u32; 3]>,
    },
    /// `c`: an open cone or cylinder from `base` (radius `base_radius`) to `apex`.
    Cone {
        base: Vec3,
        base_radius: f32,
        apex: Vec3,
        apex_radius: f32,
    },
    /// `tpa`: a triangle given at several times (non-decreasing), interpolated linearly.
    Morph(Vec<MorphKey>),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct MorphKey {
    pub time: f32,
    pub vertices: [Vec3; 3],
}

/// The `v` view.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct View {
    pub from: Vec3,
    pub at: Vec3,
    pub up: Vec3,
    /// Vertical field of view, degrees.
    pub angle: f32,
}

/// `a start end frames`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct AnimationRange {
    pub start: f64,
    pub end: f64,
    pub frames: u32,
}

/// Everything the evaluator needs from a parsed file and its includes.
#[derive(Debug)]
pub(super) struct ParsedAff {
    pub nodes: Vec<Node>,
    pub animations: HashMap<String, Animation>,
    pub materials: Vec<Material>,
    pub view: Option<View>,
    pub range: Option<AnimationRange>,
    pub background: Option<Vec3>,
    /// Static point lights (`l`), in world coordinates.
    pub lights: Vec<PointLight>,
}

/// Parses the AFF file at `path` and, recursively, the files it includes (relative to the
/// including file's folder). A top-level file that cannot be read is `Error::Io`.
pub(super) fn parse_file(path: &Path) -> Result<ParsedAff> {
    let text = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut state = State {
        parsed: ParsedAff {
            nodes: Vec::new(),
            animations: HashMap::new(),
            materials: Vec::new(),
            view: None,
            range: None,
            background: None,
            lights: Vec::new(),
        },
        material_ids: HashMap::new(),
        albedo: Vec3::splat(DEFAULT_ALBEDO),
        detail_level: 0,
        include_stack: vec![canonical(path)],
    };
    state.parsed.nodes = state.parse_text(path, &text)?;
    Ok(state.parsed)
}

fn canonical(path: &Path) -> PathBuf {
    path.canonicalize().unwrap_or_else(|_| path.to_path_buf())
}

/// Parser state shared by a file and everything it includes (materials, like BART's fill
/// colour, carry over from one command to the next regardless of transform blocks and files).
struct State {
    parsed: ParsedAff,
    material_ids: HashMap<[u32; 3], u32>,
    /// Albedo of the current material (`f`/`fm`); 0.75 grey before the first one.
    albedo: Vec3,
    /// `d level`: includes with a higher level are skipped (BART's default is 0).
    detail_level: i64,
    /// Canonical paths of the files being parsed, outermost first (cycle detection).
    include_stack: Vec<PathBuf>,
}

#[derive(Clone, Copy, Debug)]
struct Token<'a> {
    text: &'a str,
    line: usize,
}

fn tokenize(text: &str) -> Vec<Token<'_>> {
    let mut tokens = Vec::new();
    for (index, line) in text.lines().enumerate() {
        let content = line.find(['#', '%']).map_or(line, |cut| &line[..cut]);
        for word in content.split_whitespace() {
            let mut rest = word;
            while !rest.is_empty() {
                let split = match rest.find(['{', '}']) {
                    Some(0) => 1,
                    Some(at) => at,
                    None => rest.len(),
                };
                tokens.push(Token {
                    text: &rest[..split],
                    line: index + 1,
                });
                rest = &rest[split..];
            }
        }
    }
    tokens
}

/// A transform block that is open (its `{` read, its `}` not yet).
struct OpenBlock {
    kind: OpenKind,
    line: usize,
    children: Vec<Node>,
}

enum OpenKind {
    Static(DAffine3),
    Animated { name: String, location: Location },
}

/// Reads tokens of one file; knows the command being read for end-of-file errors.
struct Cursor<'a> {
    path: &'a Path,
    tokens: Vec<Token<'a>>,
    pos: usize,
    command: &'a str,
    command_line: usize,
}

impl<'a> Cursor<'a> {
    fn error(&self, line: usize, message: impl Into<String>) -> Error {
        aff_error(self.path, line, message)
    }

    fn peek(&self) -> Option<Token<'a>> {
        self.tokens.get(self.pos).copied()
    }

    fn remaining(&self) -> usize {
        self.tokens.len() - self.pos
    }

    fn next(&mut self, what: &str) -> Result<Token<'a>> {
        let token = self.peek().ok_or_else(|| {
            self.error(
                self.command_line,
                format!("the file ends inside '{}' (expected {what})", self.command),
            )
        })?;
        self.pos += 1;
        Ok(token)
    }

    fn number(&mut self, what: &str) -> Result<f64> {
        let token = self.next(what)?;
        match token.text.parse::<f64>() {
            Ok(value) if value.is_finite() => Ok(value),
            _ => Err(self.error(
                token.line,
                format!(
                    "expected {what} (a finite number) in '{}', found '{}'",
                    self.command, token.text
                ),
            )),
        }
    }

    fn float(&mut self, what: &str) -> Result<f32> {
        let value = self.number(what)?;
        if value.abs() > f64::from(f32::MAX) {
            let line = self.tokens[self.pos - 1].line;
            return Err(self.error(line, format!("{what} {value} is too large")));
        }
        Ok(value as f32)
    }

    fn vec3(&mut self, what: &str) -> Result<Vec3> {
        Ok(Vec3::new(
            self.float(what)?,
            self.float(what)?,
            self.float(what)?,
        ))
    }

    fn dvec3(&mut self, what: &str) -> Result<DVec3> {
        Ok(DVec3::new(
            self.number(what)?,
            self.number(what)?,
            self.number(what)?,
        ))
    }

    /// Skips `n` numbers (normals, texture coordinates).
    fn skip_numbers(&mut self, n: usize, what: &str) -> Result<()> {
        for _ in 0..n {
            self.number(what)?;
        }
        Ok(())
    }

    fn integer(&mut self, what: &str) -> Result<i64> {
        let token = self.next(what)?;
        token.text.parse::<i64>().map_err(|_| {
            self.error(
                token.line,
                format!(
                    "expected {what} (an integer) in '{}', found '{}'",
                    self.command, token.text
                ),
            )
        })
    }

    fn count(&mut self, what: &str) -> Result<usize> {
        let token = self.next(what)?;
        token.text.parse::<usize>().map_err(|_| {
            self.error(
                token.line,
                format!(
                    "expected {what} (a count) in '{}', found '{}'",
                    self.command, token.text
                ),
            )
        })
    }

    /// A vertex index below `limit`.
    fn index(&mut self, limit: usize) -> Result<u32> {
        let token = self.next("a vertex index")?;
        match token.text.parse::<u32>() {
            Ok(i) if (i as usize) < limit => Ok(i),
            Ok(i) => Err(self.error(
                token.line,
                format!("vertex index {i} is out of range (the mesh has {limit} vertices)"),
            )),
            Err(_) => Err(self.error(
                token.line,
                format!("expected a vertex index, found '{}'", token.text),
            )),
        }
    }

    fn word(&mut self, what: &str) -> Result<Token<'a>> {
        let token = self.next(what)?;
        if token.text == "{" || token.text == "}" {
            return Err(self.error(
                token.line,
                format!(
                    "expected {what} in '{}', found '{}'",
                    self.command, token.text
                ),
            ));
        }
        Ok(token)
    }

    fn keyword(&mut self, keyword: &str) -> Result<()> {
        let token = self.next(&format!("'{keyword}'"))?;
        if token.text != keyword {
            return Err(self.error(
                token.line,
                format!(
                    "expected '{keyword}' in '{}', found '{}'",
                    self.command, token.text
                ),
            ));
        }
        Ok(())
    }

    fn peek_is_number(&self) -> bool {
        self.peek().is_some_and(|t| t.text.parse::<f64>().is_ok())
    }

    fn location(&self, line: usize) -> Location {
        Location {
            file: Arc::from(self.path),
            line,
        }
    }
}

impl State {
    fn material(&mut self) -> u32 {
        let albedo = self.albedo;
        let key = albedo.to_array().map(f32::to_bits);
        let materials = &mut self.parsed.materials;
        *self.material_ids.entry(key).or_insert_with(|| {
            materials.push(Material::diffuse(albedo));
            (materials.len() - 1) as u32
        })
    }

    /// Parses one file's text; returns its top-level nodes.
    fn parse_text(&mut self, path: &Path, bytes: &[u8]) -> Result<Vec<Node>> {
        let text = String::from_utf8_lossy(bytes);
        let mut cur = Cursor {
            path,
            tokens: tokenize(&text),
            pos: 0,
            command: "",
            command_line: 0,
        };
        let mut top = Vec::new();
        let mut open: Vec<OpenBlock> = Vec::new();
        while let Some(token) = cur.peek() {
            cur.pos += 1;
            cur.command = token.text;
            cur.command_line = token.line;
            let line = token.line;
            let shape = match token.text {
                "}" => {
                    let block = open
                        .pop()
                        .ok_or_else(|| cur.error(line, "'}' without an open transform"))?;
                    let node = match block.kind {
                        OpenKind::Static(transform) => Node::Static {
                            transform,
                            children: block.children,
                        },
                        OpenKind::Animated { name, location } => Node::Animated {
                            name,
                            location,
                            children: block.children,
                        },
                    };
                    open.last_mut()
                        .map_or(&mut top, |b| &mut b.children)
                        .push(node);
                    None
                }
                "xs" => {
                    let scale = cur.dvec3("a scale factor")?;
                    let axis = cur.dvec3("a rotation axis component")?;
                    let degrees = cur.number("a rotation angle")?;
                    let translation = cur.dvec3("a translation component")?;
                    expect_open_brace(&mut cur, "xs")?;
                    let transform = DAffine3::from_scale_rotation_translation(
                        scale,
                        axis_angle(axis, degrees),
                        translation,
                    );
                    open.push(OpenBlock {
                        kind: OpenKind::Static(transform),
                        line,
                        children: Vec::new(),
                    });
                    None
                }
                "x" => {
                    let name = cur.word("a transform name")?.text.to_string();
                    expect_open_brace(&mut cur, "x")?;
                    open.push(OpenBlock {
                        kind: OpenKind::Animated {
                            name,
                            location: cur.location(line),
                        },
                        line,
                        children: Vec::new(),
                    });
                    None
                }
                "i" => {
                    let level = cur.integer("a detail level")?;
                    let name = cur.word("a file name")?.text;
                    if level > self.detail_level {
                        log::info!(
                            "{}:{line}: skipping include '{name}' (detail level {level} > {})",
                            path.display(),
                            self.detail_level
                        );
                    } else {
                        let nodes = self.include(&cur, line, name)?;
                        open.last_mut()
                            .map_or(&mut top, |b| &mut b.children)
                            .extend(nodes);
                    }
                    None
                }
                "k" => {
                    self.parse_keys(&mut cur, line)?;
                    None
                }
                "p" | "pp" => Some(parse_polygon(&mut cur, token.text == "pp")?),
                "tt" | "ttp" => {
                    cur.word("a texture name")?;
                    let normals = token.text == "ttp";
                    let mut vertices = Vec::with_capacity(3);
                    for _ in 0..3 {
                        vertices.push(cur.vec3("a vertex coordinate")?);
                        if normals {
                            cur.skip_numbers(3, "a normal component")?;
                        }
                        cur.skip_numbers(2, "a texture coordinate")?;
                    }
                    Some(Shape::Polygon(vertices))
                }
                "m" => Some(parse_mesh(&mut cur)?),
                "c" => {
                    let base = cur.vec3("a cone base coordinate")?;
                    let mut base_radius = cur.float("a cone base radius")?;
                    let apex = cur.vec3("a cone apex coordinate")?;
                    let mut apex_radius = cur.float("a cone apex radius")?;
                    if base_radius < 0.0 {
                        // Negative radii mark an inside-only surface; the geometry is the same.
                        base_radius = -base_radius;
                        apex_radius = -apex_radius;
                    }
                    if base == apex {
                        return Err(cur.error(line, "cone base and apex coincide"));
                    }
                    Some(Shape::Cone {
                        base,
                        base_radius,
                        apex,
                        apex_radius,
                    })
                }
                "tpa" => Some(parse_morph(&mut cur)?),
                "s" => {
                    cur.skip_numbers(4, "a sphere centre coordinate or radius")?;
                    log::warn!(
                        "{}:{line}: spheres are not supported; skipped",
                        path.display()
                    );
                    None
                }
                "f" => {
                    let colour = cur.vec3("a colour component")?;
                    let kd = cur.float("Kd")?;
                    cur.skip_numbers(4, "Ks, shine, transmittance or refraction index")?;
                    self.albedo = (colour * kd).clamp(Vec3::ZERO, Vec3::ONE);
                    None
                }
                "fm" => {
                    cur.skip_numbers(3, "an ambient colour component")?;
                    let diffuse = cur.vec3("a diffuse colour component")?;
                    cur.skip_numbers(
                        6,
                        "a specular colour component, shine, transmittance or refraction index",
                    )?;
                    self.albedo = diffuse.clamp(Vec3::ZERO, Vec3::ONE);
                    None
                }
                "v" => {
                    let mut view = View {
                        from: Vec3::ZERO,
                        at: Vec3::ZERO,
                        up: Vec3::ZERO,
                        angle: 0.0,
                    };
                    cur.keyword("from")?;
                    view.from = cur.vec3("a coordinate")?;
                    cur.keyword("at")?;
                    view.at = cur.vec3("a coordinate")?;
                    cur.keyword("up")?;
                    view.up = cur.vec3("a coordinate")?;
                    cur.keyword("angle")?;
                    view.angle = cur.float("an angle")?;
                    cur.keyword("hither")?;
                    cur.number("the hither distance")?;
                    cur.keyword("resolution")?;
                    cur.count("a resolution")?;
                    cur.count("a resolution")?;
                    self.parsed.view = Some(view);
                    None
                }
                "l" => {
                    let position = cur.vec3("a light position coordinate")?;
                    let intensity = if cur.peek_is_number() {
                        cur.vec3("a light colour component")?
                    } else {
                        Vec3::ONE
                    };
                    self.parsed
                        .lights
                        .push(PointLight::new(position, intensity));
                    None
                }
                "la" => {
                    let name = cur.word("a light name")?;
                    cur.skip_numbers(3, "a light position coordinate")?;
                    if cur.peek_is_number() {
                        cur.skip_numbers(3, "a light colour component")?;
                    }
                    log::warn!(
                        "animated light '{}' ignored (only static `l` lights are supported)",
                        name.text
                    );
                    None
                }
                "b" => {
                    self.parsed.background = Some(cur.vec3("a background colour component")?);
                    None
                }
                "am" => {
                    cur.skip_numbers(3, "an ambient light component")?;
                    None
                }
                "a" => {
                    let start = cur.number("the start time")?;
                    let end = cur.number("the end time")?;
                    let frames = cur.count("the number of frames")?;
                    let frames = u32::try_from(frames)
                        .ok()
                        .filter(|&n| n >= 1)
                        .ok_or_else(|| cur.error(line, "the number of frames must be 1 or more"))?;
                    self.parsed.range = Some(AnimationRange { start, end, frames });
                    None
                }
                "d" => {
                    self.detail_level = cur.integer("a detail level")?;
                    None
                }
                "{" => return Err(cur.error(line, "'{' without a transform ('x' or 'xs')")),
                other => return Err(cur.error(line, format!("unknown command '{other}'"))),
            };
            if let Some(shape) = shape {
                let node = Node::Shape {
                    shape,
                    material: self.material(),
                };
                open.last_mut()
                    .map_or(&mut top, |b| &mut b.children)
                    .push(node);
            }
        }
        if let Some(block) = open.last() {
            return Err(cur.error(
                block.line,
                "missing '}': this transform is not closed before the end of the file",
            ));
        }
        Ok(top)
    }

    fn include(&mut self, cur: &Cursor<'_>, line: usize, name: &str) -> Result<Vec<Node>> {
        let target = cur.path.parent().unwrap_or(Path::new("")).join(name);
        let bytes = std::fs::read(&target).map_err(|e| {
            cur.error(
                line,
                format!("cannot read included file '{}': {e}", target.display()),
            )
        })?;
        let canonical_target = canonical(&target);
        if self.include_stack.contains(&canonical_target) {
            return Err(cur.error(line, format!("'{name}' includes itself (include cycle)")));
        }
        if self.include_stack.len() > MAX_INCLUDE_DEPTH {
            return Err(cur.error(
                line,
                format!("includes nest deeper than {MAX_INCLUDE_DEPTH} levels"),
            ));
        }
        self.include_stack.push(canonical_target);
        let nodes = self.parse_text(&target, &bytes);
        self.include_stack.pop();
        nodes
    }

    /// `k name { transl|rot|scale|visibility count keys… }`.
    fn parse_keys(&mut self, cur: &mut Cursor<'_>, line: usize) -> Result<()> {
        let name = cur.word("an animation name")?.text.to_string();
        expect_open_brace(cur, "k")?;
        let mut animation = Animation::default();
        let mut seen: Vec<&str> = Vec::new();
        loop {
            let track = cur.next("a track type or '}'")?;
            if track.text == "}" {
                break;
            }
            if seen.contains(&track.text) {
                return Err(cur.error(
                    track.line,
                    format!("animation '{name}' has two '{}' tracks", track.text),
                ));
            }
            seen.push(track.text);
            let count = cur.count("the number of keys")?;
            let path = cur.path;
            let spline_error = |message: String| {
                aff_error(
                    path,
                    track.line,
                    format!("'{}' track of animation '{name}': {message}", track.text),
                )
            };
            match track.text {
                "transl" | "scale" => {
                    let keys = parse_key_list::<3>(cur, count)?;
                    let spline = Spline::new(&keys).map_err(spline_error)?;
                    if track.text == "transl" {
                        animation.translation = Some(spline);
                    } else {
                        animation.scale = Some(spline);
                    }
                }
                "rot" => {
                    let keys = parse_key_list::<4>(cur, count)?;
                    animation.rotation = Some(Spline::new(&keys).map_err(spline_error)?);
                }
                "visibility" => {
                    let mut switches = Vec::with_capacity(count.min(cur.remaining()));
                    for _ in 0..count {
                        let time = cur.number("a key time")?;
                        let flag = cur.integer("a visibility flag (0 or 1)")?;
                        switches.push((time, flag != 0));
                    }
                    if switches.windows(2).any(|w| w[1].0 < w[0].0) {
                        return Err(spline_error("key times must not decrease".into()));
                    }
                    animation.visibility = switches;
                }
                other => {
                    return Err(cur.error(
                        track.line,
                        format!(
                            "unknown track type '{other}' in animation '{name}' (expected \
                             transl, rot, scale or visibility)"
                        ),
                    ))
                }
            }
        }
        // A later definition replaces an earlier one, as in BART (the kitchen includes one
        // wheel file, with its keys, twice).
        if self
            .parsed
            .animations
            .insert(name.clone(), animation)
            .is_some()
        {
            log::debug!(
                "{}:{line}: animation '{name}' redefined; the last definition is used",
                cur.path.display()
            );
        }
        Ok(())
    }
}

fn expect_open_brace(cur: &mut Cursor<'_>, command: &str) -> Result<()> {
    let token = cur.next("'{'")?;
    if token.text != "{" {
        return Err(cur.error(
            token.line,
            format!("expected '{{' after '{command}', found '{}'", token.text),
        ));
    }
    Ok(())
}

/// `count` keys of `time v0..v(N-1) tension continuity bias`.
fn parse_key_list<const N: usize>(cur: &mut Cursor<'_>, count: usize) -> Result<Vec<Key<N>>> {
    let mut keys = Vec::with_capacity(count.min(cur.remaining()));
    for _ in 0..count {
        let time = cur.number("a key time")?;
        let mut value = [0.0; N];
        for v in &mut value {
            *v = cur.number("a key value")?;
        }
        keys.push(Key {
            time,
            value,
            tension: cur.number("a key tension")?,
            continuity: cur.number("a key continuity")?,
            bias: cur.number("a key bias")?,
        });
    }
    Ok(keys)
}

/// `p n v…` or `pp n (v n)…`.
fn parse_polygon(cur: &mut Cursor<'_>, normals: bool) -> Result<Shape> {
    let line = cur.command_line;
    let n = cur.count("the number of vertices")?;
    if n < 3 {
        return Err(cur.error(
            line,
            format!("a polygon needs 3 or more vertices, found {n}"),
        ));
    }
    let mut vertices = Vec::with_capacity(n.min(cur.remaining()));
    for _ in 0..n {
        vertices.push(cur.vec3("a vertex coordinate")?);
        if normals {
            cur.skip_numbers(3, "a normal component")?;
        }
    }
    Ok(Shape::Polygon(vertices))
}

/// `m vertices n … [normals n …] [texturecoords n texture …] triangles n (v0 v1 v2 [n…] [t…])…`.
fn parse_mesh(cur: &mut Cursor<'_>) -> Result<Shape> {
    cur.keyword("vertices")?;
    let n = cur.count("the number of vertices")?;
    let mut positions = Vec::with_capacity(n.min(cur.remaining()));
    for _ in 0..n {
        positions.push(cur.vec3("a vertex coordinate")?);
    }
    let mut section = cur.word("'normals', 'texturecoords' or 'triangles'")?;
    let mut normals = 0;
    if section.text == "normals" {
        normals = cur.count("the number of normals")?;
        cur.skip_numbers(3 * normals, "a normal component")?;
        section = cur.word("'texturecoords' or 'triangles'")?;
    }
    let mut texcoords = 0;
    if section.text == "texturecoords" {
        texcoords = cur.count("the number of texture coordinates")?;
        cur.word("a texture name")?;
        cur.skip_numbers(2 * texcoords, "a texture coordinate")?;
        section = cur.word("'triangles'")?;
    }
    if section.text != "triangles" {
        return Err(cur.error(
            section.line,
            format!("expected 'triangles' in 'm', found '{}'", section.text),
        ));
    }
    let count = cur.count("the number of triangles")?;
    let mut triangles = Vec::with_capacity(count.min(cur.remaining()));
    for _ in 0..count {
        triangles.push([
            cur.index(positions.len())?,
            cur.index(positions.len())?,
            cur.index(positions.len())?,
        ]);
        // Normal and texture-coordinate indices follow; they are not used.
        if normals > 0 {
            cur.skip_numbers(3, "a normal index")?;
        }
        if texcoords > 0 {
            cur.skip_numbers(3, "a texture coordinate index")?;
        }
    }
    Ok(Shape::Mesh {
        positions,
        triangles,
    })
}

/// `tpa n (time (v n) (v n) (v n))…`.
fn parse_morph(cur: &mut Cursor<'_>) -> Result<Shape> {
    let line = cur.command_line;
    let n = cur.count("the number of keys")?;
    if n == 0 {
        return Err(cur.error(line, "an animated triangle needs at least one key"));
    }
    let mut keys: Vec<MorphKey> = Vec::with_capacity(n.min(cur.remaining()));
    for _ in 0..n {
        let time_line = cur.peek().map_or(line, |t| t.line);
        let time = cur.float("a key time")?;
        if keys.last().is_some_and(|k| time < k.time) {
            return Err(cur.error(time_line, "key times must not decrease"));
        }
        let mut vertices = [Vec3::ZERO; 3];
        for v in &mut vertices {
            *v = cur.vec3("a vertex coordinate")?;
            cur.skip_numbers(3, "a normal component")?;
        }
        keys.push(MorphKey { time, vertices });
    }
    Ok(Shape::Morph(keys))
}
