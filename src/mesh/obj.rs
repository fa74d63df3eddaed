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

    fn validate(&self) -> Result<(), MeshError> {
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
    fn mirrors(&self) -> bool {
        (self.transform.determinant() as f64) * (self.scale as f64).powi(3) < 0.0
    }
}

pub(super) struct Loaded {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
    pub flip_winding: bool,
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
    for model in &models {
        let base = positions.len() as u32;
        positions.extend(model.mesh.positions.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])));
        triangles.extend(model.mesh.indices.chunks_exact(3).map(|c| [c[0] + base, c[1] + base, c[2] + base]));
    }
    if triangles.is_empty() {
        return Err(MeshError::NoFaces { source_name });
    }
    if options.scale != 1.0 || options.transform != Mat4::IDENTITY {
        for p in &mut positions {
            *p = options.transform.transform_point3(*p * options.scale);
        }
    }
    Ok(Loaded { positions, triangles, flip_winding: options.mirrors() })
}

fn parse_error(source_name: &str, line: usize, message: String, text: &str) -> MeshError {
    // Long lines are cut so one bad line cannot flood the terminal.
    let mut shown: String = text.trim().chars().take(80).collect();
    if text.trim().chars().count() > 80 {
        shown.push('…');
    }
    MeshError::Parse { source_name: source_name.to_string(), line, message, text: shown }
}

/// What a face vertex's `v/vt/vn` indices refer to, in that order, for messages.
const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];

/// One line of the file, to quote in its errors.
#[derive(Clone, Copy)]
struct Line<'a> {
    source_name: &'a str,
    /// Line number, from 1.
    no: usize,
    text: &'a str,
}

impl Line<'_> {
    fn error(self, message: String) -> MeshError {
        parse_error(self.source_name, self.no, message, self.text)
    }
}

/// A positive face index beyond the elements defined so far: OBJ lets it refer forward, so it
/// is checked against the final counts.
struct ForwardRef<'a> {
    line: Line<'a>,
    index: i64,
    /// Index into [`KINDS`].
    kind: usize,
}

/// The pre-scan's state: elements of each of [`KINDS`] defined so far, and the forward
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
        let (kind, needed) = match keyword {
            "v" => (0, 3),
            "vt" => (1, 2),
            "vn" => (2, 3),
            "f" | "l" => {
                scan.face(line, keyword == "f", words)?;
                continue;
            }
            _ => continue,
        };
        check_numbers(line, keyword, needed, &mut words)?;
        if keyword == "v" {
            check_vertex_extras(line, words)?;
        }
        scan.counts[kind] += 1;
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
            return Err(line.error(format!("a face needs at least 3 vertices, this one has {vertices}")));
        }
        Ok(())
    }

    /// One index `part` (the `kind`th, 0 for the position) of face vertex `word`: present for
    /// the position, a non-zero integer, a relative one reaching no further back than the
    /// first element, a positive one beyond those defined so far kept for [`Self::finish`].
    fn face_index(&mut self, line: Line<'a>, word: &str, kind: usize, part: &str) -> Result<(), MeshError> {
        if kind >= 3 {
            return Err(line.error(format!("face vertex `{word}` has more than three indices")));
        }
        if part.is_empty() {
            if kind == 0 {
                return Err(line.error(format!("face vertex `{word}` has no position index")));
            }
            return Ok(());
        }
        let index: i64 = part.parse().map_err(|_| line.error(format!("face index `{part}` is not an integer")))?;
        if index == 0 {
            return Err(line.error("face index 0 is invalid (OBJ indices start at 1)".into()));
        }
        if index < 0 && -index > self.counts[kind] {
            return Err(line.error(format!(
                "relative {} index {index} reaches before the first of the {} defined so far",
                KINDS[kind], self.counts[kind]
            )));
        }
        if index > self.counts[kind] {
            self.forward.push(ForwardRef { line, index, kind });
        }
        Ok(())
    }

    /// Positive indices may point forward in the file; check them against the final counts.
    fn finish(self) -> Result<(), MeshError> {
        if let Some(bad) = self.forward.iter().find(|f| f.index > self.counts[f.kind]) {
            return Err(bad.line.error(format!(
                "{} index {} is out of range: the file defines {}",
                KINDS[bad.kind], bad.index, self.counts[bad.kind]
            )));
        }
        Ok(())
    }
}

/// The first `needed` numbers after `keyword` (`v`, `vt`, `vn`): present, parsing and finite
/// in f32. Leaves `words` at what follows them.
fn check_numbers<'a>(
    line: Line<'_>,
    keyword: &str,
    needed: usize,
    words: &mut impl Iterator<Item = &'a str>,
) -> Result<(), MeshError> {
    let mut values = 0;
    for word in words.by_ref().take(needed) {
        let value: f32 = word.parse().map_err(|_| line.error(format!("`{word}` is not a number")))?;
        if !value.is_finite() {
            return Err(line.error(format!("coordinate `{word}` is not a finite f32 number")));
        }
        values += 1;
    }
    if values < needed {
        return Err(line.error(format!("`{keyword}` needs {needed} numbers, found {values}")));
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
            let w: f32 = rest[0].parse().map_err(|_| line.error(format!("weight `{}` is not a number", rest[0])))?;
            if !w.is_finite() || w == 0.0 {
                return Err(line.error(format!("weight w = `{}` must be finite and non-zero", rest[0])));
            }
            Ok(())
        }
        k => Err(line.error(format!("`v` takes 3, 4 or 6 numbers, found {}", 3 + k))),
    }
}
