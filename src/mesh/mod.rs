//! Triangle meshes: OBJ loading (tobj), validation, and the derived geometry that the samplers and
//! the renderer need: angle-weighted vertex normals, triangle areas, discrete mean and Gaussian
//! curvature with mixed Voronoi areas (Meyer et al. 2003), and edge adjacency.
//!
//! A [`Mesh`] is immutable once built. Construction goes through one pipeline whether the
//! triangles come from an OBJ file ([`Mesh::load`]) or from memory ([`Mesh::from_triangles`]):
//! validate, weld exactly coincident positions, drop zero-area triangles, remove unreferenced
//! vertices, then derive topology and geometry. What the pipeline changed or found is kept in a
//! [`MeshReport`].

pub mod atlas;
mod boundary;
pub mod bvh;
mod corners;
mod curvature;
pub(crate) mod enclosure;
pub mod facing;
mod glb;
#[cfg(feature = "gltf")]
mod gltf;
mod lod;
mod obj;
pub mod patches;
pub mod shapes;
mod topology;

use std::path::PathBuf;

use glam::{DVec3, Vec3};

pub use boundary::NO_BOUNDARY;
pub use enclosure::{Enclosure, enclosure};
pub use glb::{GltfNodePart, glb_bytes};
#[cfg(feature = "gltf")]
pub use gltf::{GltfProblem, gltf_bounds, gltf_document};
pub use lod::{LodLevel, MIN_LEVEL_TRIANGLES};
pub use obj::{Element, LoadOptions, ObjProblem};

/// Marks an edge with no single neighbouring triangle (an open boundary or a non-manifold edge).
pub const NO_NEIGHBOUR: u32 = u32::MAX;

/// Largest coordinate magnitude a mesh may have: beyond it f32 triangle areas (and the sample
/// areas and kernels built on them) lose all precision or overflow to infinity.
pub const MAX_COORDINATE: f32 = 1e9;

/// A triangle is dropped as degenerate when its area is at most this fraction of its longest
/// edge squared: below it the triangle's shape is rounding noise of f32 coordinates, and its
/// cotangents would poison the curvature of its vertices.
pub const DEGENERATE_AREA_RATIO: f64 = 1e-10;

/// Everything that can go wrong when loading or building a mesh. Each message names the file
/// (or `<memory>`), and the line, vertex or triangle at fault.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    // The io::Error is the source (shown by `{:#}` and error reporters), not repeated here.
    /// The file could not be read.
    #[error("cannot read mesh file {}", path.display())]
    Io {
        /// The mesh file.
        path: PathBuf,
        /// Why reading failed.
        source: std::io::Error,
    },
    /// A malformed OBJ line, found by the pre-scan.
    #[error("{source_name}:{line}: {problem} (line: `{text}`)")]
    Parse {
        /// The file name, or `<memory>`.
        source_name: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong with the line.
        problem: ObjProblem,
        /// The line itself, trimmed and cut to 80 characters.
        text: String,
    },
    /// tobj refused the file.
    #[error("{source_name}: OBJ parser (tobj) failed: {error}")]
    Obj {
        /// The file name, or `<memory>`.
        source_name: String,
        /// tobj's error.
        error: tobj::LoadError,
    },
    /// There are no triangles (faces) at all.
    #[error("{source_name}: the mesh has no faces")]
    NoFaces {
        /// The file name, or `<memory>`.
        source_name: String,
    },
    /// A position is infinite or NaN.
    #[error("{source_name}: vertex {vertex} has a non-finite position {value:?}")]
    NonFinite {
        /// The file name, or `<memory>`.
        source_name: String,
        /// 0-based vertex index.
        vertex: usize,
        /// Its position.
        value: [f32; 3],
    },
    /// A coordinate's magnitude is above [`MAX_COORDINATE`].
    #[error(
        "{source_name}: vertex {vertex} at {value:?} is farther than {limit:e} units from the origin \
         (f32 areas would overflow or lose all precision; scale the mesh down)"
    )]
    TooFar {
        /// The file name, or `<memory>`.
        source_name: String,
        /// 0-based vertex index.
        vertex: usize,
        /// Its position.
        value: [f32; 3],
        /// The limit, [`MAX_COORDINATE`].
        limit: f32,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("{source_name}: triangle {triangle} refers to vertex {index}, but there are only {count} vertices")]
    IndexOutOfRange {
        /// The file name, or `<memory>`.
        source_name: String,
        /// 0-based triangle index.
        triangle: usize,
        /// The vertex index it refers to.
        index: u32,
        /// How many vertices there are.
        count: usize,
    },
    /// Every triangle is degenerate (see [`DEGENERATE_AREA_RATIO`]).
    #[error("{source_name}: the mesh has no area: all {degenerate} triangles have zero area")]
    NoArea {
        /// The file name, or `<memory>`.
        source_name: String,
        /// How many triangles were dropped as degenerate.
        degenerate: usize,
    },
    /// A glTF file, and the crate was built without its `gltf` feature.
    #[error(
        "{}: glTF files are read only with the crate's `gltf` feature (a default one); build with it",
        path.display()
    )]
    GltfDisabled {
        /// The file.
        path: PathBuf,
    },
    /// A glTF file that cannot be read as a mesh.
    #[cfg(feature = "gltf")]
    #[error("{source_name}: {problem}")]
    Gltf {
        /// The file name, or `<memory>`.
        source_name: String,
        /// What is wrong with it.
        problem: Box<GltfProblem>,
    },
    /// [`LoadOptions`] with a zero or non-finite scale, or a non-finite or singular transform.
    #[error("invalid mesh load options: {0}")]
    InvalidOptions(LoadOptionsError),
}

/// The whole scene of the glTF file at `path`; without the `gltf` feature, the error that says so.
fn load_gltf(path: &std::path::Path, options: &LoadOptions) -> Result<obj::Loaded, MeshError> {
    #[cfg(feature = "gltf")]
    return gltf::load(path, gltf::Select::Whole, options);
    #[cfg(not(feature = "gltf"))]
    {
        let _ = options;
        Err(MeshError::GltfDisabled { path: path.to_path_buf() })
    }
}

/// Whether `path` names a glTF file (`.gltf` or `.glb`, any case); every other mesh is read
/// as OBJ.
pub fn is_gltf(path: &std::path::Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// What is wrong with a [`LoadOptions`] ([`MeshError::InvalidOptions`]).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum LoadOptionsError {
    /// `scale` is zero, infinite or NaN.
    #[error("scale must be finite and non-zero, got {0}")]
    Scale(f32),
    /// `transform` has a non-finite entry, or no inverse.
    #[error("transform must be finite and invertible, got {0:?}")]
    Transform(glam::Mat4),
}

/// What loading found and changed. Open boundaries and non-manifold edges are allowed; they are
/// counted here so a caller can warn about them.
#[derive(Clone, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct MeshReport {
    /// The file name, or `<memory>`.
    pub source: String,
    /// Vertices and triangles as given (after triangulation of polygons).
    pub input_vertices: usize,
    /// Triangles as given (after triangulation of polygons).
    pub input_triangles: usize,
    /// Vertices merged into another one with a bit-identical position (tobj's single index
    /// splits a position wherever its normal or texture index differs).
    pub welded_vertices: usize,
    /// Triangles dropped because their area was zero (see [`DEGENERATE_AREA_RATIO`]).
    pub degenerate_triangles: usize,
    /// Vertices removed because no remaining triangle used them.
    pub unreferenced_vertices: usize,
    /// Edges used by exactly one triangle.
    pub boundary_edges: usize,
    /// Edges used by three or more triangles.
    pub non_manifold_edges: usize,
    /// Manifold edges whose two triangles traverse them in the same direction (inconsistent
    /// winding, so some normals point inwards).
    pub inconsistently_oriented_edges: usize,
}

impl MeshReport {
    /// True when the surface is closed, manifold and consistently oriented.
    pub fn is_closed_manifold(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0 && self.inconsistently_oriented_edges == 0
    }
}

/// A validated triangle mesh with derived geometry. Positions are stored as f32 (what the GPU
/// consumes); every derived quantity was accumulated in f64.
#[derive(Clone, Debug)]
pub struct Mesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
    vertex_normals: Vec<Vec3>,
    face_normals: Vec<Vec3>,
    triangle_areas: Vec<f64>,
    total_area: f64,
    mean_curvature: Vec<f64>,
    gaussian_curvature: Vec<f64>,
    mixed_areas: Vec<f64>,
    boundary_vertex: Vec<bool>,
    boundary_edges: Vec<[u32; 2]>,
    neighbours: Vec<[u32; 3]>,
    ring_offsets: Vec<u32>,
    ring: Vec<u32>,
    bounds: (Vec3, Vec3),
    report: MeshReport,
    corners: corners::Corners,
}

impl Mesh {
    /// Load an OBJ file: polygons are triangulated (as fans, by tobj), all objects and groups are
    /// merged into one mesh with one index per vertex, then `options` scales and transforms the
    /// positions. Materials are ignored; normals (`vn`) and texture coordinates (`vt`) are kept
    /// per triangle corner where every face has them: the normals become the vertex normals
    /// (else they are computed from the faces), the coordinates the texture gather's atlas.
    pub fn load(path: impl AsRef<std::path::Path>, options: &LoadOptions) -> Result<Mesh, MeshError> {
        let path = path.as_ref();
        let loaded = if is_gltf(path) { load_gltf(path, options)? } else { obj::load(path, options)? };
        Mesh::build(path.display().to_string(), loaded)
    }

    /// Parse OBJ text in memory (e.g. an asset embedded in the binary), with the same
    /// validation as [`Mesh::load`]; `source_name` names it in errors.
    pub fn from_obj_text(text: &str, source_name: &str, options: &LoadOptions) -> Result<Mesh, MeshError> {
        let loaded = obj::parse(text, source_name, options)?;
        Mesh::build(source_name.to_string(), loaded)
    }

    /// Build a mesh from positions and triangles in memory, with the same validation and
    /// clean-up as [`Mesh::load`].
    pub fn from_triangles(positions: Vec<Vec3>, triangles: Vec<[u32; 3]>) -> Result<Mesh, MeshError> {
        let loaded = obj::Loaded { positions, triangles, flip_winding: false, corners: corners::Corners::NONE };
        Mesh::build("<memory>".to_string(), loaded)
    }

    /// This mesh moved by `m` (e.g. into the scene), with its clean-up done again: its corners'
    /// texture coordinates kept and their normals turned as the surface is (a mirroring `m`
    /// swaps the winding, so that faces keep facing out).
    pub fn transformed(&self, m: glam::Mat4) -> Result<Mesh, MeshError> {
        let mut corners = self.corners.clone();
        corners.transform_normals(m);
        let loaded = obj::Loaded {
            positions: self.positions.iter().map(|p| m.transform_point3(*p)).collect(),
            triangles: self.triangles.clone(),
            flip_winding: m.determinant() < 0.0,
            corners,
        };
        Mesh::build(self.report.source.clone(), loaded)
    }

    fn build(source: String, loaded: obj::Loaded) -> Result<Mesh, MeshError> {
        let obj::Loaded { positions, triangles, flip_winding, corners } = loaded;
        let mut corners = corners.checked(triangles.len());
        let mut report = MeshReport {
            source: source.clone(),
            input_vertices: positions.len(),
            input_triangles: triangles.len(),
            ..MeshReport::default()
        };
        if triangles.is_empty() {
            return Err(MeshError::NoFaces { source_name: source });
        }
        if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| !p.is_finite()) {
            return Err(MeshError::NonFinite { source_name: source, vertex, value: p.to_array() });
        }
        if let Some((vertex, p)) = positions.iter().enumerate().find(|(_, p)| p.abs().max_element() > MAX_COORDINATE) {
            return Err(MeshError::TooFar { source_name: source, vertex, value: p.to_array(), limit: MAX_COORDINATE });
        }
        for (triangle, tri) in triangles.iter().enumerate() {
            if let Some(&index) = tri.iter().find(|&&i| i as usize >= positions.len()) {
                return Err(MeshError::IndexOutOfRange {
                    source_name: source,
                    triangle,
                    index,
                    count: positions.len(),
                });
            }
        }

        let (positions, mut triangles, welded) = weld(positions, triangles);
        report.welded_vertices = welded;
        if flip_winding {
            for t in &mut triangles {
                t.swap(1, 2);
            }
            corners.swap_winding();
        }
        report.degenerate_triangles = drop_degenerate(&positions, &mut triangles, &mut corners);
        if triangles.is_empty() {
            return Err(MeshError::NoArea { source_name: source, degenerate: report.degenerate_triangles });
        }

        let (positions, triangles, unreferenced) = compact(positions, triangles);
        report.unreferenced_vertices = unreferenced;

        let topo = topology::build(positions.len(), &triangles);
        report.boundary_edges = topo.boundary_edges.len();
        report.non_manifold_edges = topo.non_manifold_edges;
        report.inconsistently_oriented_edges = topo.inconsistent_edges;

        let geo = curvature::compute(&positions, &triangles, &topo);
        // The file's normals where it gives them: its shading, as it was authored.
        let vertex_normals = corners.vertex_normals(&triangles, geo.vertex_normals);
        let total_area = geo.triangle_areas.iter().sum();

        let mut lo = Vec3::splat(f32::INFINITY);
        let mut hi = Vec3::splat(f32::NEG_INFINITY);
        for p in &positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }

        Ok(Mesh {
            positions,
            triangles,
            vertex_normals,
            face_normals: geo.face_normals,
            triangle_areas: geo.triangle_areas,
            total_area,
            mean_curvature: geo.mean_curvature,
            gaussian_curvature: geo.gaussian_curvature,
            mixed_areas: geo.mixed_areas,
            boundary_vertex: topo.boundary_vertex,
            boundary_edges: topo.boundary_edges,
            neighbours: topo.neighbours,
            ring_offsets: topo.ring_offsets,
            ring: topo.ring,
            bounds: (lo, hi),
            report,
            corners,
        })
    }

    /// Per triangle, the texture coordinates of its three corners, when the file gave every
    /// triangle some (OBJ `vt`, glTF `TEXCOORD_0`); what the texture gather's atlas uses when
    /// its charts do not overlap (`atlas::Atlas::new`).
    pub fn corner_uvs(&self) -> Option<&[[glam::Vec2; 3]]> {
        self.corners.uvs.as_deref()
    }

    /// Vertex positions (one per vertex, after welding and clean-up).
    pub fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    /// Triangles as three vertex indices each; their winding gives [`Mesh::face_normals`].
    pub fn triangles(&self) -> &[[u32; 3]] {
        &self.triangles
    }

    /// Unit vertex normals, each the sum of its triangles' normals weighted by the triangle's
    /// angle at the vertex (Thürmer and Wüthrich 1998), so they do not depend on how a flat
    /// region happens to be split into triangles.
    pub fn vertex_normals(&self) -> &[Vec3] {
        &self.vertex_normals
    }

    /// Unit triangle normals, following the winding (counter-clockwise seen from outside).
    pub fn face_normals(&self) -> &[Vec3] {
        &self.face_normals
    }

    /// Area of each triangle (in f64).
    pub fn triangle_areas(&self) -> &[f64] {
        &self.triangle_areas
    }

    /// Sum of the triangle areas.
    pub fn total_area(&self) -> f64 {
        self.total_area
    }

    /// Signed mean curvature H per vertex, positive where the surface is convex (a sphere of
    /// radius R with outward normals has H = 1/R). Cotangent Laplace-Beltrami with mixed areas
    /// (Meyer et al. 2003, Eq. 8 and section 3.3), projected on the vertex normal. Boundary and
    /// non-manifold vertices, where the formula does not hold, take the mixed-area-weighted
    /// mean of their neighbours.
    pub fn mean_curvature(&self) -> &[f64] {
        &self.mean_curvature
    }

    /// Gaussian curvature K per vertex: angle defect (2 pi minus the angles at the vertex) over
    /// the mixed area (Meyer et al. 2003, Eq. 9). Boundary vertices as for [`Mesh::mean_curvature`].
    pub fn gaussian_curvature(&self) -> &[f64] {
        &self.gaussian_curvature
    }

    /// Mixed Voronoi area per vertex (Meyer et al. 2003, Fig. 4); they sum to the total area.
    pub fn mixed_areas(&self) -> &[f64] {
        &self.mixed_areas
    }

    /// Edge adjacency: `neighbours()[t][e]` is the triangle across edge `e` of triangle `t`, the
    /// edge running from corner `e` to corner `(e + 1) % 3`, or [`NO_NEIGHBOUR`] when that edge
    /// is a boundary or is shared by more than two triangles.
    pub fn neighbours(&self) -> &[[u32; 3]] {
        &self.neighbours
    }

    /// The vertices sharing an edge with vertex `v`, sorted.
    pub fn vertex_neighbours(&self, v: usize) -> &[u32] {
        &self.ring[self.ring_offsets[v] as usize..self.ring_offsets[v + 1] as usize]
    }

    /// True for vertices on an open boundary or a non-manifold edge.
    pub fn is_boundary_vertex(&self, v: usize) -> bool {
        self.boundary_vertex[v]
    }

    /// Axis-aligned bounding box (min, max).
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Length of the bounding-box diagonal.
    pub fn diagonal(&self) -> f64 {
        (self.bounds.1 - self.bounds.0).as_dvec3().length()
    }

    /// What loading found and changed.
    pub fn report(&self) -> &MeshReport {
        &self.report
    }

    /// The three corners of triangle `t` in f64.
    #[inline]
    pub fn corners(&self, t: usize) -> [DVec3; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.positions[a as usize].as_dvec3(),
            self.positions[b as usize].as_dvec3(),
            self.positions[c as usize].as_dvec3(),
        ]
    }

    /// The point of triangle `t` at barycentric coordinates `bary` (weights of its corners).
    #[inline]
    pub fn point(&self, t: usize, bary: [f64; 3]) -> DVec3 {
        let [a, b, c] = self.corners(t);
        a * bary[0] + b * bary[1] + c * bary[2]
    }

    /// The unit shading normal at barycentric coordinates `bary` of triangle `t`: the
    /// interpolated vertex normals, or the face normal where they cancel out.
    #[inline]
    pub fn normal_at(&self, t: usize, bary: [f64; 3]) -> Vec3 {
        let [a, b, c] = self.triangles[t];
        let n = self.vertex_normals[a as usize].as_dvec3() * bary[0]
            + self.vertex_normals[b as usize].as_dvec3() * bary[1]
            + self.vertex_normals[c as usize].as_dvec3() * bary[2];
        let len = n.length();
        if len > 1e-6 { (n / len).as_vec3() } else { self.face_normals[t] }
    }

    /// A per-vertex scalar interpolated at barycentric coordinates `bary` of triangle `t`.
    #[inline]
    pub fn interpolate(&self, values: &[f64], t: usize, bary: [f64; 3]) -> f64 {
        let [a, b, c] = self.triangles[t];
        values[a as usize] * bary[0] + values[b as usize] * bary[1] + values[c as usize] * bary[2]
    }
}

/// Twice the area and the longest squared edge of a triangle, in f64.
fn area_and_longest_edge(p: [DVec3; 3]) -> (f64, f64) {
    let e = [p[1] - p[0], p[2] - p[1], p[0] - p[2]];
    let longest = e.iter().map(|v| v.length_squared()).fold(0.0, f64::max);
    (0.5 * e[0].cross(-e[2]).length(), longest)
}

fn is_degenerate(positions: &[Vec3], t: &[u32; 3]) -> bool {
    if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
        return true;
    }
    let p = t.map(|i| positions[i as usize].as_dvec3());
    let (area, longest) = area_and_longest_edge(p);
    // Written so that a NaN area also counts as degenerate.
    area.is_nan() || area <= DEGENERATE_AREA_RATIO * longest
}

/// Drop the triangles of zero area (and their corners' attributes); how many.
fn drop_degenerate(positions: &[Vec3], triangles: &mut Vec<[u32; 3]>, corners: &mut corners::Corners) -> usize {
    let keep: Vec<bool> = triangles.iter().map(|t| !is_degenerate(positions, t)).collect();
    corners.retain(&keep);
    let mut k = keep.iter();
    triangles.retain(|_| *k.next().unwrap_or(&false));
    keep.iter().filter(|&&k| !k).count()
}

/// Merge vertices whose positions are bit-identical (after folding -0.0 into 0.0). Returns the
/// new positions, the re-indexed triangles and how many vertices were merged away.
fn weld(positions: Vec<Vec3>, mut triangles: Vec<[u32; 3]>) -> (Vec<Vec3>, Vec<[u32; 3]>, usize) {
    use std::collections::HashMap;
    let mut first: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let mut remap = Vec::with_capacity(positions.len());
    let mut kept = Vec::with_capacity(positions.len());
    for p in &positions {
        // Adding 0.0 turns -0.0 into +0.0 so the two spellings of zero weld together.
        let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
        let idx = *first.entry(key).or_insert_with(|| {
            kept.push(*p);
            (kept.len() - 1) as u32
        });
        remap.push(idx);
    }
    let welded = positions.len() - kept.len();
    if welded > 0 {
        for t in &mut triangles {
            *t = t.map(|i| remap[i as usize]);
        }
    }
    (kept, triangles, welded)
}

/// Drop vertices that no triangle uses, keeping the order of the rest.
fn compact(positions: Vec<Vec3>, mut triangles: Vec<[u32; 3]>) -> (Vec<Vec3>, Vec<[u32; 3]>, usize) {
    let mut used = vec![false; positions.len()];
    for t in &triangles {
        for &i in t {
            used[i as usize] = true;
        }
    }
    let unreferenced = used.iter().filter(|u| !**u).count();
    if unreferenced == 0 {
        return (positions, triangles, 0);
    }
    let mut remap = vec![u32::MAX; positions.len()];
    let mut kept = Vec::with_capacity(positions.len() - unreferenced);
    for (i, p) in positions.iter().enumerate() {
        if used[i] {
            remap[i] = kept.len() as u32;
            kept.push(*p);
        }
    }
    for t in &mut triangles {
        *t = t.map(|i| remap[i as usize]);
    }
    (kept, triangles, unreferenced)
}
