//! glTF 2.0 meshes (issue 48): a `.glb`, or a `.gltf` with its buffers in files beside it. Every
//! triangle primitive of the file's scene (the default one, else the first), placed by its
//! nodes' transforms, becomes part of one mesh, in node order, as the OBJ loader makes one mesh
//! of an OBJ's groups.

use super::corners::Corners;
use super::glb::GltfNodePart;
use super::obj::{LoadOptions, Loaded};
use super::{Mesh, MeshError};
use ::gltf::accessor::{DataType, Dimensions};
use glam::{Mat4, Vec2, Vec3};
use std::path::Path;

/// What is wrong with a glTF file ([`MeshError::Gltf`]).
#[derive(Debug, thiserror::Error)]
pub enum GltfProblem {
    /// The gltf crate could not parse or validate it.
    #[error("not a valid glTF 2.0 file: {0}")]
    Parse(#[from] ::gltf::Error),
    /// A buffer given as a `data:` URI (not read: give it as a `.bin` file or use `.glb`).
    #[error("buffer {buffer} is a data: URI; save the file as .glb or with a .bin file")]
    DataUri {
        /// The buffer's index.
        buffer: usize,
    },
    /// A buffer's file could not be read.
    #[error("buffer {buffer}: cannot read {}: {source}", path.display())]
    BufferFile {
        /// The buffer's index.
        buffer: usize,
        /// The file it names.
        path: std::path::PathBuf,
        /// Why reading failed.
        source: std::io::Error,
    },
    /// A buffer names the binary chunk, and the file has none.
    #[error("buffer {buffer} is the binary chunk, and the file has none")]
    NoBinaryChunk {
        /// The buffer's index.
        buffer: usize,
    },
    /// A buffer holds fewer bytes than its `byteLength`.
    #[error("buffer {buffer} holds {found} bytes, less than its byteLength {declared}")]
    ShortBuffer {
        /// The buffer's index.
        buffer: usize,
        /// Bytes there.
        found: usize,
        /// Its `byteLength`.
        declared: usize,
    },
    /// A primitive draws points, lines or strips instead of triangles.
    #[error("mesh {mesh} primitive {primitive} (node {node}) draws {mode:?}; only triangles are read")]
    NotTriangles {
        /// The node that places the mesh.
        node: usize,
        /// The mesh.
        mesh: usize,
        /// The primitive, within the mesh.
        primitive: usize,
        /// Its mode.
        mode: ::gltf::mesh::Mode,
    },
    /// A primitive has no POSITION accessor, or one that cannot be read.
    #[error("mesh {mesh} primitive {primitive} (node {node}): no readable POSITION accessor")]
    NoPositions {
        /// The node that places the mesh.
        node: usize,
        /// The mesh.
        mesh: usize,
        /// The primitive, within the mesh.
        primitive: usize,
    },
    /// An index is past the primitive's vertices, or the indices are not whole triangles.
    #[error("mesh {mesh} primitive {primitive} (node {node}): accessor {accessor} {why}")]
    BadIndices {
        /// The node that places the mesh.
        node: usize,
        /// The mesh.
        mesh: usize,
        /// The primitive, within the mesh.
        primitive: usize,
        /// The indices' accessor.
        accessor: usize,
        /// What is wrong.
        why: String,
    },
    /// An accessor of a type or layout that is not read.
    #[error("accessor {accessor} ({role}) {why}")]
    Accessor {
        /// The accessor.
        accessor: usize,
        /// What the primitive uses it for.
        role: &'static str,
        /// What is wrong.
        why: String,
    },
    /// Nodes that do not form trees.
    #[error("node {node} {why}; glTF nodes must form trees")]
    NotATree {
        /// The node.
        node: usize,
        /// How it breaks the trees.
        why: &'static str,
    },
    /// A GLB header whose total length is less than the header itself.
    #[error("the GLB header gives a length of {declared} bytes, less than its own 12")]
    GlbLength {
        /// The length it gives.
        declared: u32,
    },
    /// A primitive's POSITION names an accessor that is not there.
    #[error("mesh {mesh} primitive {primitive}: POSITION is accessor {accessor}, and the file has {count} accessors")]
    NoSuchAccessor {
        /// The mesh.
        mesh: usize,
        /// The primitive, within the mesh.
        primitive: usize,
        /// The accessor it names.
        accessor: usize,
        /// How many accessors there are.
        count: usize,
    },
    /// No node of the scene has the name a scene's `shape.node` gives.
    #[error("no node of its scene is named {name:?} (the file's named nodes: {names:?})")]
    NoSuchNode {
        /// The name asked for.
        name: String,
        /// Every named node of the file.
        names: Vec<String>,
    },
    /// A node a glTF scene's object names (`scene::Scene::from_gltf`) is not in the file's scene.
    #[error("node {node} is not a node of the file's scene")]
    NodeNotInScene {
        /// The node's index.
        node: usize,
    },
    /// The file has no scene, or its scene places no mesh.
    #[error("no scene places a mesh")]
    NoMesh,
}

/// Which triangles of a glTF file's scene are read.
#[derive(Clone, Copy, Debug)]
pub(super) enum Select<'a> {
    /// Every triangle primitive of the scene.
    Whole,
    /// The node of this name and its children.
    Named(&'a str),
    /// One node's primitives of one material, without its children.
    Part(GltfNodePart),
}

/// Read the glTF at `path` ([`super::Mesh::load`] for a `.gltf` or `.glb`): what `select` picks.
pub(super) fn load(path: &Path, select: Select, options: &LoadOptions) -> Result<Loaded, MeshError> {
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io { path: path.to_path_buf(), source })?;
    parse(&bytes, &path.display().to_string(), path.parent(), select, options)
}

/// A glTF file in memory parsed and validated as the mesh reader reads it (what the gltf crate
/// would panic on refused first, its nodes checked to form trees), with the scene it reads (the
/// default one, else the first); `source_name` names it in errors. For the scene reader
/// (`scene::Scene::from_gltf`), which reads cameras, lights and materials from it.
pub fn gltf_document(bytes: &[u8], source_name: &str) -> Result<(::gltf::Gltf, usize), MeshError> {
    let file = document(bytes).map_err(|p| gltf_error(source_name, p))?;
    let scene = scene_of(&file).map_err(|p| gltf_error(source_name, p))?;
    Ok((file, scene))
}

fn gltf_error(source_name: &str, problem: GltfProblem) -> MeshError {
    MeshError::Gltf { source_name: source_name.to_string(), problem: Box::new(problem) }
}

/// The file parsed and validated by the gltf crate, what it would panic on refused first.
fn document(bytes: &[u8]) -> Result<::gltf::Gltf, GltfProblem> {
    prevalidate(bytes)?;
    Ok(::gltf::Gltf::from_slice(bytes)?)
}

/// The index of the scene read (the default one, else the first), its nodes checked to form
/// trees.
fn scene_of(file: &::gltf::Gltf) -> Result<usize, GltfProblem> {
    let scene = file.default_scene().or_else(|| file.scenes().next()).ok_or(GltfProblem::NoMesh)?;
    trees(file, &scene)?;
    Ok(scene.index())
}

/// The bounding box of every triangle of a glTF file's scene, placed by its nodes (`base`: where
/// its buffer files are), for a default camera that frames it.
pub fn gltf_bounds(bytes: &[u8], source_name: &str, base: Option<&Path>) -> Result<(Vec3, Vec3), MeshError> {
    let loaded = parse(bytes, source_name, base, Select::Whole, &LoadOptions::default())?;
    Ok(loaded.positions.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p))))
}

/// Parse a glTF already in memory; `source_name` names it in errors, and `base` is where its
/// buffer files are (`None`: only a `.glb`'s own binary chunk can be read). `select` says which
/// triangles of the scene.
pub(super) fn parse(
    bytes: &[u8],
    source_name: &str,
    base: Option<&Path>,
    select: Select,
    options: &LoadOptions,
) -> Result<Loaded, MeshError> {
    options.validate()?;
    let fail = |problem| gltf_error(source_name, problem);
    // Buffers before the scene: a file's bad buffer is reported before its missing scene.
    let file = document(bytes).map_err(fail)?;
    let buffers = buffers(&file, base).map_err(fail)?;
    let scene = file.scenes().nth(scene_of(&file).map_err(fail)?).expect("scene_of's scene");
    let mut out =
        Loaded { positions: Vec::new(), triangles: Vec::new(), flip_winding: false, corners: Corners::collecting() };
    let (roots, only): (Vec<(::gltf::Node, Mat4)>, _) = match select {
        Select::Whole => (scene.nodes().map(|n| (n, Mat4::IDENTITY)).collect(), None),
        Select::Named(name) => (
            vec![find(scene.nodes(), &|n| n.name() == Some(name), Mat4::IDENTITY).ok_or_else(|| {
                let names = file.nodes().filter_map(|n| n.name().map(str::to_string)).collect();
                fail(GltfProblem::NoSuchNode { name: name.to_string(), names })
            })?],
            None,
        ),
        Select::Part(part) => (
            vec![
                find(scene.nodes(), &|n| n.index() == part.node, Mat4::IDENTITY)
                    .ok_or_else(|| fail(GltfProblem::NodeNotInScene { node: part.node }))?,
            ],
            Some(part.material),
        ),
    };
    for (root, parent) in roots {
        place(&root, parent, &buffers, only, &mut out).map_err(fail)?;
    }
    if out.triangles.is_empty() {
        return Err(fail(GltfProblem::NoMesh));
    }
    if options.scale != 1.0 || options.transform != Mat4::IDENTITY {
        for p in &mut out.positions {
            *p = options.transform.transform_point3(*p * options.scale);
        }
    }
    out.flip_winding = options.mirrors();
    Ok(out)
}

/// Refuse what the gltf crate (1.4.1) would panic on rather than report, both found by
/// `fuzz/fuzz_targets/gltf.rs`: a GLB header whose length is under the header's own 12 bytes
/// (`Glb::from_slice` subtracts 12 from it unchecked), and a primitive whose POSITION names an
/// accessor that does not exist (gltf-json's validation looks it up before checking it is
/// there). What does not parse is left for the gltf crate to report.
fn prevalidate(bytes: &[u8]) -> Result<(), GltfProblem> {
    use ::gltf::json::{mesh::Semantic, validation::Checked};
    if let Some(length) = bytes.strip_prefix(b"glTF").and_then(|b| b.get(4..8)) {
        let declared = u32::from_le_bytes(length.try_into().expect("4 bytes"));
        if declared < 12 {
            return Err(GltfProblem::GlbLength { declared });
        }
    }
    let json = match ::gltf::Glb::from_slice(bytes) {
        Ok(glb) => glb.json,
        Err(_) if bytes.starts_with(b"glTF") => return Ok(()),
        Err(_) => std::borrow::Cow::Borrowed(bytes),
    };
    let Ok(root) = serde_json::from_slice::<::gltf::json::Root>(&json) else { return Ok(()) };
    for (mesh, m) in root.meshes.iter().enumerate() {
        for (primitive, p) in m.primitives.iter().enumerate() {
            let position = p.attributes.get(&Checked::Valid(Semantic::Positions));
            if let Some(accessor) = position.map(|a| a.value()).filter(|&a| a >= root.accessors.len()) {
                return Err(GltfProblem::NoSuchAccessor { mesh, primitive, accessor, count: root.accessors.len() });
            }
        }
    }
    Ok(())
}

/// Every buffer's bytes: the binary chunk, or a file relative to `base`.
fn buffers(file: &::gltf::Gltf, base: Option<&Path>) -> Result<Vec<Vec<u8>>, GltfProblem> {
    file.buffers()
        .map(|b| {
            let buffer = b.index();
            let data = match b.source() {
                ::gltf::buffer::Source::Bin => file.blob.clone().ok_or(GltfProblem::NoBinaryChunk { buffer })?,
                ::gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                    return Err(GltfProblem::DataUri { buffer });
                }
                ::gltf::buffer::Source::Uri(uri) => {
                    let path = base.unwrap_or(Path::new(".")).join(uri);
                    std::fs::read(&path).map_err(|source| GltfProblem::BufferFile { buffer, path, source })?
                }
            };
            if data.len() < b.length() {
                return Err(GltfProblem::ShortBuffer { buffer, found: data.len(), declared: b.length() });
            }
            Ok(data)
        })
        .collect()
}

/// Check that the nodes form trees, as glTF requires and the walks below assume: no node with
/// two parents, none its own ancestor, and the scene's roots with no parent (the gltf crate
/// does not check, and a cycle would recurse without end).
fn trees(file: &::gltf::Gltf, scene: &::gltf::Scene) -> Result<(), GltfProblem> {
    let mut parent: Vec<Option<usize>> = vec![None; file.nodes().len()];
    for node in file.nodes() {
        for child in node.children() {
            if parent[child.index()].replace(node.index()).is_some() {
                return Err(GltfProblem::NotATree { node: child.index(), why: "has two parents" });
            }
        }
    }
    if let Some(root) = scene.nodes().find(|n| parent[n.index()].is_some()) {
        return Err(GltfProblem::NotATree { node: root.index(), why: "is a root of the scene and a child" });
    }
    // Walk up from each node; 1 marks the walk in progress, 2 nodes known to reach a root.
    let mut state = vec![0u8; parent.len()];
    for start in 0..parent.len() {
        let mut at = Some(start);
        while let Some(n) = at.filter(|&n| state[n] != 2) {
            if state[n] == 1 {
                return Err(GltfProblem::NotATree { node: n, why: "is its own ancestor" });
            }
            state[n] = 1;
            at = parent[n];
        }
        let mut at = Some(start);
        while let Some(n) = at.filter(|&n| state[n] == 1) {
            state[n] = 2;
            at = parent[n];
        }
    }
    Ok(())
}

/// The first node `wanted` among `nodes` and their descendants (depth first), with the
/// transform of its parents.
fn find<'a>(
    nodes: impl Iterator<Item = ::gltf::Node<'a>>,
    wanted: &dyn Fn(&::gltf::Node) -> bool,
    parent: Mat4,
) -> Option<(::gltf::Node<'a>, Mat4)> {
    for node in nodes {
        if wanted(&node) {
            return Some((node, parent));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(found) = find(node.children(), wanted, world) {
            return Some(found);
        }
    }
    None
}

/// Append `node`'s mesh and its children's, placed by `parent` times the node's own transform;
/// with `only`, the node's primitives of that material alone (`None` inside: the default
/// material), without its children. A mirroring transform has its triangles' winding swapped,
/// so that they keep facing out.
fn place(
    node: &::gltf::Node,
    parent: Mat4,
    buffers: &[Vec<u8>],
    only: Option<Option<usize>>,
    out: &mut Loaded,
) -> Result<(), GltfProblem> {
    let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
    if let Some(mesh) = node.mesh() {
        for primitive in mesh.primitives() {
            if only.is_some_and(|material| primitive.material().index() != material) {
                continue;
            }
            let at = (node.index(), mesh.index(), primitive.index());
            append(&primitive, at, world, buffers, out)?;
        }
    }
    if only.is_none() {
        for child in node.children() {
            place(&child, world, buffers, None, out)?;
        }
    }
    Ok(())
}

/// Refuse an accessor the gltf crate's reader would misread (in release builds) or assert on
/// (in debug builds, found by the fuzzer): another type than `dimensions` of one of `types`, a
/// stride shorter than an element, no element or more than its view holds, or sparse storage or
/// no buffer view (not read here).
fn readable(
    accessor: &::gltf::Accessor,
    role: &'static str,
    types: &[DataType],
    dimensions: Dimensions,
) -> Result<(), GltfProblem> {
    let bad = |why: String| GltfProblem::Accessor { accessor: accessor.index(), role, why };
    if !types.contains(&accessor.data_type()) || accessor.dimensions() != dimensions || accessor.normalized() {
        return Err(bad(format!(
            "is {:?} of {:?}{}, not {dimensions:?} of {types:?}",
            accessor.dimensions(),
            accessor.data_type(),
            if accessor.normalized() { " (normalized)" } else { "" }
        )));
    }
    if accessor.sparse().is_some() {
        return Err(bad("is sparse, which is not read".into()));
    }
    let Some(view) = accessor.view() else { return Err(bad("has no buffer view".into())) };
    let stride = view.stride().unwrap_or(accessor.size());
    if stride < accessor.size() {
        return Err(bad(format!("has a byteStride of {stride}, less than its {}-byte elements", accessor.size())));
    }
    // Its last element must end inside its view: the reader computes that end unchecked.
    let end = accessor
        .count()
        .checked_sub(1)
        .and_then(|last| stride.checked_mul(last)?.checked_add(accessor.offset())?.checked_add(accessor.size()));
    match end {
        None => Err(bad(format!("holds {} elements", accessor.count()))),
        Some(end) if end > view.length() => {
            Err(bad(format!("ends at byte {end} of its buffer view, which holds {}", view.length())))
        }
        Some(_) => Ok(()),
    }
}

/// Append one triangle primitive, its positions placed by `world`.
fn append(
    primitive: &::gltf::Primitive,
    (node, mesh, index): (usize, usize, usize),
    world: Mat4,
    buffers: &[Vec<u8>],
    out: &mut Loaded,
) -> Result<(), GltfProblem> {
    if primitive.mode() != ::gltf::mesh::Mode::Triangles {
        return Err(GltfProblem::NotTriangles { node, mesh, primitive: index, mode: primitive.mode() });
    }
    let position = primitive.get(&::gltf::Semantic::Positions);
    let position = position.ok_or(GltfProblem::NoPositions { node, mesh, primitive: index })?;
    readable(&position, "POSITION", &[DataType::F32], Dimensions::Vec3)?;
    if let Some(indices) = primitive.indices() {
        readable(&indices, "indices", &[DataType::U8, DataType::U16, DataType::U32], Dimensions::Scalar)?;
    }
    let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
    let positions: Vec<Vec3> = reader
        .read_positions()
        .ok_or(GltfProblem::NoPositions { node, mesh, primitive: index })?
        .map(|p| world.transform_point3(Vec3::from(p)))
        .collect();
    let count = positions.len();
    let indices: Vec<u32> = match reader.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..count as u32).collect(),
    };
    let bad = |why: String| GltfProblem::BadIndices {
        node,
        mesh,
        primitive: index,
        accessor: primitive.indices().map_or(usize::MAX, |a| a.index()),
        why,
    };
    if !indices.len().is_multiple_of(3) {
        return Err(bad(format!("holds {} indices, not whole triangles", indices.len())));
    }
    if let Some(&i) = indices.iter().find(|&&i| i as usize >= count) {
        return Err(bad(format!("refers to vertex {i}, but the primitive has {count}")));
    }
    let base = out.positions.len() as u32;
    let mirrored = world.determinant() < 0.0;
    out.triangles.extend(indices.chunks_exact(3).map(|t| {
        let [a, b, c] = [t[0] + base, t[1] + base, t[2] + base];
        if mirrored { [a, c, b] } else { [a, b, c] }
    }));
    out.positions.extend(positions);
    // TEXCOORD_0 and NORMAL per corner, while every primitive so far had them.
    let uvs: Option<Vec<Vec2>> = reader
        .read_tex_coords(0)
        .map(|t| t.into_f32().map(Vec2::from).collect())
        .filter(|u: &Vec<Vec2>| u.len() == count);
    match (uvs, out.corners.uvs.as_mut()) {
        (Some(uvs), Some(corners)) => corners.extend(per_corner(&indices, &uvs, mirrored)),
        _ => out.corners.uvs = None,
    }
    let turn = glam::Mat3::from_mat4(world).inverse().transpose();
    let normals: Option<Vec<Vec3>> = reader
        .read_normals()
        .map(|n| n.map(|n| turn * Vec3::from(n)).collect())
        .filter(|n: &Vec<Vec3>| n.len() == count);
    match (normals, out.corners.normals.as_mut()) {
        (Some(normals), Some(corners)) => corners.extend(per_corner(&indices, &normals, mirrored)),
        _ => out.corners.normals = None,
    }
    Ok(())
}

/// A per-vertex attribute at each triangle's corners, in the winding the triangles were given.
fn per_corner<T: Copy>(indices: &[u32], values: &[T], mirrored: bool) -> impl Iterator<Item = [T; 3]> {
    indices.chunks_exact(3).map(move |t| {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| values[i as usize]);
        if mirrored { [a, c, b] } else { [a, b, c] }
    })
}

impl Mesh {
    /// Read the mesh of the node named `node` of a glTF 2.0 file, with its children's, placed
    /// as the file's scene places it (an error listing the names there are when no node of the
    /// scene has it).
    pub fn load_gltf_node(path: impl AsRef<Path>, node: &str, options: &LoadOptions) -> Result<Mesh, MeshError> {
        let path = path.as_ref();
        let loaded = load(path, Select::Named(node), options)?;
        Mesh::build(path.display().to_string(), loaded)
    }

    /// Read one node's triangle primitives of one material from a glTF 2.0 file, placed as the
    /// file's scene places the node, its children left out: one object of a glTF scene.
    pub fn load_gltf_part(
        path: impl AsRef<Path>,
        part: GltfNodePart,
        options: &LoadOptions,
    ) -> Result<Mesh, MeshError> {
        let path = path.as_ref();
        let loaded = load(path, Select::Part(part), options)?;
        Mesh::build(path.display().to_string(), loaded)
    }

    /// Parse a glTF 2.0 file in memory (a `.glb`, or a `.gltf` whose buffers are files in
    /// `base`), with the same validation as [`Mesh::load`]; `source_name` names it in errors.
    pub fn from_gltf_slice(
        bytes: &[u8],
        source_name: &str,
        base: Option<&Path>,
        options: &LoadOptions,
    ) -> Result<Mesh, MeshError> {
        let loaded = parse(bytes, source_name, base, Select::Whole, options)?;
        Mesh::build(source_name.to_string(), loaded)
    }
}
