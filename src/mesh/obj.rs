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
            return Err(MeshError::InvalidOptions(format!("scale must be finite and non-zero, got {}", self.scale)));
        }
        if !self.transform.is_finite() || self.transform.determinant() == 0.0 {
            return Err(MeshError::InvalidOptions(format!(
                "transform must be finite and invertible, got {:?}",
                self.transform
            )));
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

/// Check every `v`, `vt`, `vn`, `f` and `l` line: numbers that parse and are finite in f32, faces
/// of at least three vertices, indices that are non-zero and inside the lists they refer to
/// (negative indices count back from the last element defined so far, positive ones may refer
/// forward). Other statements are left to tobj, which ignores what it does not know.
fn prescan(text: &str, source_name: &str) -> Result<(), MeshError> {
    struct FaceRef<'a> {
        line: usize,
        text: &'a str,
        index: i64,
        kind: usize,
    }
    const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];
    let mut counts = [0i64; 3];
    let mut forward: Vec<FaceRef> = Vec::new();

    for (n, line) in text.lines().enumerate() {
        let line_no = n + 1;
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else { continue };
        let (kind, needed) = match keyword {
            "v" => (0, 3),
            "vt" => (1, 2),
            "vn" => (2, 3),
            "f" | "l" => {
                let mut vertices = 0;
                for word in words {
                    vertices += 1;
                    for (kind, part) in word.split('/').enumerate() {
                        if kind >= 3 {
                            return Err(parse_error(
                                source_name,
                                line_no,
                                format!("face vertex `{word}` has more than three indices"),
                                line,
                            ));
                        }
                        if part.is_empty() {
                            if kind == 0 {
                                return Err(parse_error(
                                    source_name,
                                    line_no,
                                    format!("face vertex `{word}` has no position index"),
                                    line,
                                ));
                            }
                            continue;
                        }
                        let index: i64 = part.parse().map_err(|_| {
                            parse_error(source_name, line_no, format!("face index `{part}` is not an integer"), line)
                        })?;
                        if index == 0 {
                            return Err(parse_error(
                                source_name,
                                line_no,
                                "face index 0 is invalid (OBJ indices start at 1)".into(),
                                line,
                            ));
                        }
                        if index < 0 && -index > counts[kind] {
                            return Err(parse_error(
                                source_name,
                                line_no,
                                format!(
                                    "relative {} index {index} reaches before the first of the {} defined so far",
                                    KINDS[kind], counts[kind]
                                ),
                                line,
                            ));
                        }
                        if index > counts[kind] {
                            forward.push(FaceRef { line: line_no, text: line, index, kind });
                        }
                    }
                }
                if keyword == "f" && vertices < 3 {
                    return Err(parse_error(
                        source_name,
                        line_no,
                        format!("a face needs at least 3 vertices, this one has {vertices}"),
                        line,
                    ));
                }
                continue;
            }
            _ => continue,
        };
        let mut values = 0;
        for word in words.by_ref().take(needed) {
            let value: f32 = word
                .parse()
                .map_err(|_| parse_error(source_name, line_no, format!("`{word}` is not a number"), line))?;
            if !value.is_finite() {
                return Err(parse_error(
                    source_name,
                    line_no,
                    format!("coordinate `{word}` is not a finite f32 number"),
                    line,
                ));
            }
            values += 1;
        }
        if values < needed {
            return Err(parse_error(
                source_name,
                line_no,
                format!("`{keyword}` needs {needed} numbers, found {values}"),
                line,
            ));
        }
        if keyword == "v" {
            // An optional fourth value is the homogeneous w (positions are divided by it); three
            // more are a vertex colour.
            let rest: Vec<&str> = words.collect();
            match rest.len() {
                0 | 3 => {}
                1 => {
                    let w: f32 = rest[0].parse().map_err(|_| {
                        parse_error(source_name, line_no, format!("weight `{}` is not a number", rest[0]), line)
                    })?;
                    if !w.is_finite() || w == 0.0 {
                        return Err(parse_error(
                            source_name,
                            line_no,
                            format!("weight w = `{}` must be finite and non-zero", rest[0]),
                            line,
                        ));
                    }
                }
                k => {
                    return Err(parse_error(
                        source_name,
                        line_no,
                        format!("`v` takes 3, 4 or 6 numbers, found {}", 3 + k),
                        line,
                    ));
                }
            }
        }
        counts[kind] += 1;
    }

    // Positive indices may point forward in the file; check them against the final counts.
    if let Some(bad) = forward.iter().find(|f| f.index > counts[f.kind]) {
        return Err(parse_error(
            source_name,
            bad.line,
            format!("{} index {} is out of range: the file defines {}", KINDS[bad.kind], bad.index, counts[bad.kind]),
            bad.text,
        ));
    }
    Ok(())
}
