//! OBJ reading: a light pre-scan of the text that reports malformed lines with their line
//! number (tobj's errors carry none), then tobj for the actual parse and triangulation.

use std::io::Cursor;
use std::path::Path;

use glam::{Mat4, Vec3};

use super::MeshError;

/// How to place a loaded mesh: each position p becomes `transform * (scale * p)`.
#[derive(Clone, Debug, PartialEq)]
pub struct LoadOptions {
    /// Uniform scale applied first (default 1; finite, non-zero).
    pub scale: f32,
    /// Placement applied after the scale (default identity; finite, invertible).
    pub transform: Mat4,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions { scale: 1.0, transform: Mat4::IDENTITY }
    }
}

impl LoadOptions {
    /// The same options with another `scale`.
    pub fn with_scale(mut self, scale: f32) -> Self {
        self.scale = scale;
        self
    }

    /// The same options with another `transform`.
    pub fn with_transform(mut self, transform: Mat4) -> Self {
        self.transform = transform;
        self
    }

    pub(super) fn validate(&self) -> Result<(), MeshError> {
        if !self.scale.is_finite() || self.scale == 0.0 {
            return Err(MeshError::InvalidOptions(super::LoadOptionsError::Scale(self.scale)));
        }
        if !self.transform.is_finite() || self.transform.determinant() == 0.0 {
            return Err(MeshError::InvalidOptions(super::LoadOptionsError::Transform(self.transform)));
        }
        Ok(())
    }

    /// A mirroring placement turns counter-clockwise triangles clockwise; the loader swaps
    /// their winding back so normals keep pointing outwards.
    pub(super) fn mirrors(&self) -> bool {
        (self.transform.determinant() as f64) * (self.scale as f64).powi(3) < 0.0
    }
}

pub(super) struct Loaded {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub flip_winding: bool,
    /// Per triangle, its corners' texture coordinates and normals, where every triangle has them.
    pub corners: super::corners::Corners,
}

pub(super) fn load(path: &Path, options: &LoadOptions) -> Result<Loaded, MeshError> {
    options.validate()?;
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io { path: path.to_path_buf(), source })?;
    parse(&String::from_utf8_lossy(&bytes), &path.display().to_string(), options)
}

/// Parse OBJ text already in memory; `source_name` names it in errors.
pub(super) fn parse(text: &str, source_name: &str, options: &LoadOptions) -> Result<Loaded, MeshError> {
    options.validate()?;
    let source_name = source_name.to_string();
    prescan(text, &source_name)?;

    let tobj_options =
        tobj::LoadOptions { single_index: true, triangulate: true, ignore_points: true, ignore_lines: true };
    // Materials are not used: refuse to open .mtl files instead of reading them.
    let (models, _materials) =
        tobj::load_obj_buf(&mut Cursor::new(text.as_bytes()), &tobj_options, |_| Err(tobj::LoadError::GenericFailure))
            .map_err(|error| MeshError::Obj { source_name: source_name.clone(), error })?;

    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    // tobj's single index splits a vertex wherever its texture coordinate or normal differs, so
    // each vertex it gives has one of each the file has; welding later joins the positions, and
    // the corners keep theirs.
    let mut corners = super::corners::Corners::collecting();
    for model in &models {
        let base = positions.len() as u32;
        let (mesh, count) = (&model.mesh, model.mesh.positions.len() / 3);
        let faces = || mesh.indices.chunks_exact(3);
        if mesh.texcoords.len() != 2 * count {
            corners.uvs = None;
        }
        if let Some(uvs) = corners.uvs.as_mut() {
            let uv = |i: u32| glam::Vec2::new(mesh.texcoords[2 * i as usize], mesh.texcoords[2 * i as usize + 1]);
            uvs.extend(faces().map(|c| [uv(c[0]), uv(c[1]), uv(c[2])]));
        }
        if mesh.normals.len() != 3 * count {
            corners.normals = None;
        }
        if let Some(normals) = corners.normals.as_mut() {
            let n = |i: u32| Vec3::from_slice(&mesh.normals[3 * i as usize..3 * i as usize + 3]);
            normals.extend(faces().map(|c| [n(c[0]), n(c[1]), n(c[2])]));
        }
        positions.extend(mesh.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        triangles.extend(faces().map(|c| [c[0] + base, c[1] + base, c[2] + base]));
    }
    if triangles.is_empty() {
        return Err(MeshError::NoFaces { source_name });
    }
    if options.scale != 1.0 || options.transform != Mat4::IDENTITY {
        for p in &mut positions {
            *p = options.transform.transform_point3(*p * options.scale);
        }
        corners.transform_normals(options.transform);
    }
    Ok(Loaded { positions, triangles, flip_winding: options.mirrors(), corners })
}

fn parse_error(source_name: &str, line: usize, problem: ObjProblem, text: &str) -> MeshError {
    // Long lines are cut so one bad line cannot flood the terminal.
    let mut shown: String = text.trim().chars().take(80).collect();
    if text.trim().chars().count() > 80 {
        shown.push('…');
    }
    MeshError::Parse { source_name: source_name.to_string(), line, problem, text: shown }
}

/// An element an OBJ file lists and faces index: a face vertex's `v/vt/vn` indices refer to
/// them in that order.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Element {
    /// A position, `v`.
    Vertex,
    /// A texture coordinate, `vt`.
    TextureCoordinate,
    /// A normal, `vn`.
    Normal,
}

impl Element {
    /// In the order of a face vertex's indices.
    const ALL: [Element; 3] = [Element::Vertex, Element::TextureCoordinate, Element::Normal];

    /// The statement that defines one.
    pub fn keyword(self) -> &'static str {
        match self {
            Element::Vertex => "v",
            Element::TextureCoordinate => "vt",
            Element::Normal => "vn",
        }
    }
}

impl std::fmt::Display for Element {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Element::Vertex => "vertex",
            Element::TextureCoordinate => "texture coordinate",
            Element::Normal => "normal",
        })
    }
}

/// What is wrong with an OBJ line ([`MeshError::Parse`]). The words quoted are the line's own.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ObjProblem {
    /// A `v`, `vt` or `vn` value (this) that does not parse as a number.
    #[error("`{0}` is not a number")]
    NotANumber(String),
    /// A coordinate (this) that is not finite as an f32 (NaN, infinite, or too large).
    #[error("coordinate `{0}` is not a finite f32 number")]
    NotFinite(String),
    /// A `v`, `vt` or `vn` statement with too few numbers.
    #[error("`{}` needs {needed} numbers, found {found}", element.keyword())]
    TooFewNumbers {
        /// What the statement defines.
        element: Element,
        /// How many numbers it needs.
        needed: usize,
        /// How many it has.
        found: usize,
    },
    /// A `v` statement's fourth number, the weight w (this), does not parse.
    #[error("weight `{0}` is not a number")]
    WeightNotANumber(String),
    /// A `v` statement's weight w (this) is zero or not finite: positions are divided by it.
    #[error("weight w = `{0}` must be finite and non-zero")]
    BadWeight(String),
    /// A `v` statement with this many numbers: neither 3, 4 (a weight) nor 6 (a colour).
    #[error("`v` takes 3, 4 or 6 numbers, found {0}")]
    VertexNumbers(usize),
    /// A face with this many vertices, under 3.
    #[error("a face needs at least 3 vertices, this one has {0}")]
    TooFewFaceVertices(usize),
    /// A face vertex (this) with more than `v/vt/vn`.
    #[error("face vertex `{0}` has more than three indices")]
    TooManyIndices(String),
    /// A face vertex (this) without its position index.
    #[error("face vertex `{0}` has no position index")]
    NoPositionIndex(String),
    /// A face index (this) that is not an integer.
    #[error("face index `{0}` is not an integer")]
    IndexNotAnInteger(String),
    /// A face index of 0.
    #[error("face index 0 is invalid (OBJ indices start at 1)")]
    ZeroIndex,
    /// A negative (relative) index reaching before the first element.
    #[error("relative {element} index {index} reaches before the first of the {defined} defined so far")]
    BeforeFirst {
        /// What it indexes.
        element: Element,
        /// The index.
        index: i64,
        /// How many of them the file defines before this line.
        defined: i64,
    },
    /// A positive index beyond the elements of the whole file.
    #[error("{element} index {index} is out of range: the file defines {defined}")]
    OutOfRange {
        /// What it indexes.
        element: Element,
        /// The index.
        index: i64,
        /// How many of them the file defines.
        defined: i64,
    },
}

/// One line of the file, to quote in its errors.
#[derive(Clone, Copy)]
struct Line<'a> {
    source_name: &'a str,
    /// Line number, from 1.
    no: usize,
    text: &'a str,
}

impl Line<'_> {
    fn error(self, problem: ObjProblem) -> MeshError {
        parse_error(self.source_name, self.no, problem, self.text)
    }
}

/// A positive face index beyond the elements defined so far: OBJ lets it refer forward, so it
/// is checked against the final counts.
struct ForwardRef<'a> {
    line: Line<'a>,
    index: i64,
    /// What it indexes.
    element: Element,
}

/// The pre-scan's state: elements of each [`Element`] (in [`Element::ALL`]'s order) defined so far, and the forward
/// references still to check.
struct Prescan<'a> {
    counts: [i64; 3],
    forward: Vec<ForwardRef<'a>>,
}

/// Check every `v`, `vt`, `vn`, `f` and `l` line: numbers that parse and are finite in f32, faces
/// of at least three vertices, indices that are non-zero and inside the lists they refer to
/// (negative indices count back from the last element defined so far, positive ones may refer
/// forward). Other statements are left to tobj, which ignores what it does not know.
fn prescan(text: &str, source_name: &str) -> Result<(), MeshError> {
    let mut scan = Prescan { counts: [0; 3], forward: Vec::new() };
    for (n, text) in text.lines().enumerate() {
        let line = Line { source_name, no: n + 1, text };
        let mut words = text.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let (element, needed) = match keyword {
            "v" => (Element::Vertex, 3),
            "vt" => (Element::TextureCoordinate, 2),
            "vn" => (Element::Normal, 3),
            "f" | "l" => {
                scan.face(line, keyword == "f", words)?;
                continue;
            }
            _ => continue,
        };
        check_numbers(line, element, needed, &mut words)?;
        if element == Element::Vertex {
            check_vertex_extras(line, words)?;
        }
        scan.counts[element as usize] += 1;
    }
    scan.finish()
}

impl<'a> Prescan<'a> {
    /// An `f` (`is_face`) or `l` statement's vertices, `words` after the keyword; a face needs
    /// three.
    fn face(&mut self, line: Line<'a>, is_face: bool, words: impl Iterator<Item = &'a str>) -> Result<(), MeshError> {
        let mut vertices = 0;
        for word in words {
            vertices += 1;
            for (kind, part) in word.split('/').enumerate() {
                self.face_index(line, word, kind, part)?;
            }
        }
        if is_face && vertices < 3 {
            return Err(line.error(ObjProblem::TooFewFaceVertices(vertices)));
        }
        Ok(())
    }

    /// One index `part` (the `kind`th, 0 for the position) of face vertex `word`: present for
    /// the position, a non-zero integer, a relative one reaching no further back than the
    /// first element, a positive one beyond those defined so far kept for [`Self::finish`].
    fn face_index(&mut self, line: Line<'a>, word: &str, kind: usize, part: &str) -> Result<(), MeshError> {
        let Some(&element) = Element::ALL.get(kind) else {
            return Err(line.error(ObjProblem::TooManyIndices(word.to_string())));
        };
        if part.is_empty() {
            if element == Element::Vertex {
                return Err(line.error(ObjProblem::NoPositionIndex(word.to_string())));
            }
            return Ok(());
        }
        let index: i64 = part.parse().map_err(|_| line.error(ObjProblem::IndexNotAnInteger(part.to_string())))?;
        if index == 0 {
            return Err(line.error(ObjProblem::ZeroIndex));
        }
        let defined = self.counts[kind];
        if index < 0 && -index > defined {
            return Err(line.error(ObjProblem::BeforeFirst { element, index, defined }));
        }
        if index > defined {
            self.forward.push(ForwardRef { line, index, element });
        }
        Ok(())
    }

    /// Positive indices may point forward in the file; check them against the final counts.
    fn finish(self) -> Result<(), MeshError> {
        if let Some(bad) = self.forward.iter().find(|f| f.index > self.counts[f.element as usize]) {
            let (element, index, defined) = (bad.element, bad.index, self.counts[bad.element as usize]);
            return Err(bad.line.error(ObjProblem::OutOfRange { element, index, defined }));
        }
        Ok(())
    }
}

/// The first `needed` numbers of the statement that defines `element` (`v`, `vt`, `vn`):
/// present, parsing and finite in f32. Leaves `words` at what follows them.
fn check_numbers<'a>(
    line: Line<'_>,
    element: Element,
    needed: usize,
    words: &mut impl Iterator<Item = &'a str>,
) -> Result<(), MeshError> {
    let mut values = 0;
    for word in words.by_ref().take(needed) {
        let value: f32 = word.parse().map_err(|_| line.error(ObjProblem::NotANumber(word.to_string())))?;
        if !value.is_finite() {
            return Err(line.error(ObjProblem::NotFinite(word.to_string())));
        }
        values += 1;
    }
    if values < needed {
        return Err(line.error(ObjProblem::TooFewNumbers { element, needed, found: values }));
    }
    Ok(())
}

/// What follows a `v` line's three coordinates: nothing, a homogeneous w (positions are divided
/// by it, so finite and non-zero) or three values of a vertex colour.
fn check_vertex_extras<'a>(line: Line<'_>, words: impl Iterator<Item = &'a str>) -> Result<(), MeshError> {
    let rest: Vec<&str> = words.collect();
    match rest.len() {
        0 | 3 => Ok(()),
        1 => {
            let w: f32 = rest[0].parse().map_err(|_| line.error(ObjProblem::WeightNotANumber(rest[0].to_string())))?;
            if !w.is_finite() || w == 0.0 {
                return Err(line.error(ObjProblem::BadWeight(rest[0].to_string())));
            }
            Ok(())
        }
        k => Err(line.error(ObjProblem::VertexNumbers(3 + k))),
    }
}
