//! A glTF file's scene as a [`SceneFile`]: its nodes walked with their world transforms, each
//! mapped (`camera`, `lights`, `material`), then the scene file's own checks, whose errors are
//! turned to name the part of the file a value came from.

use super::{GltfOverrides, GltfPart, GltfSceneProblem};
use crate::mesh::GltfNodePart;
use crate::scene::SceneError;
use crate::scene::check::CheckError;
use crate::scene::format::{Object, SceneFile, Shape, Transform};
use glam::Mat4;
use std::path::Path;

/// Where each object, light and the camera of a glTF scene's [`SceneFile`] came from, so that a
/// value the checks refuse is reported by its part of the file.
pub(super) struct Origins {
    /// The camera's.
    pub camera: GltfPart,
    /// Each object's node and material.
    pub objects: Vec<(GltfPart, GltfPart)>,
    /// Each light's.
    pub lights: Vec<GltfPart>,
}

/// Every node of `scene`, depth first in file order, with its world transform.
pub(super) fn walk<'a>(scene: &::gltf::Scene<'a>) -> Vec<(::gltf::Node<'a>, Mat4)> {
    fn visit<'a>(node: ::gltf::Node<'a>, parent: Mat4, out: &mut Vec<(::gltf::Node<'a>, Mat4)>) {
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        let children: Vec<_> = node.children().collect();
        out.push((node, world));
        for child in children {
            visit(child, world, out);
        }
    }
    let mut out = Vec::new();
    for root in scene.nodes() {
        visit(root, Mat4::IDENTITY, &mut out);
    }
    out
}

/// The [`SceneFile`] of the glTF in `bytes` (`name` in errors; `base` its folder and `file_name`
/// its name there, which its objects' shapes name), `overrides` applied, checked.
pub(super) fn scene_file(
    bytes: &[u8],
    name: &str,
    (base, file_name): (&Path, &str),
    overrides: &GltfOverrides,
) -> Result<SceneFile, SceneError> {
    let fail = |problem| SceneError::Gltf { file: name.to_string(), problem };
    let (document, scene) = crate::mesh::gltf_document(bytes, name)?;
    let scene = document.scenes().nth(scene).expect("gltf_document's scene");
    let nodes = walk(&scene);
    let materials = super::material::materials(&document, overrides).map_err(fail)?;
    let (objects, object_origins) = objects(&nodes, file_name, &materials);
    if objects.is_empty() {
        let problem = crate::mesh::GltfProblem::NoMesh;
        return Err(crate::mesh::MeshError::Gltf { source_name: name.to_string(), problem: Box::new(problem) }.into());
    }
    let (camera, camera_origin) = match super::camera::first(&document, &nodes).map_err(fail)? {
        Some(found) => found,
        None => (super::camera::framing(crate::mesh::gltf_bounds(bytes, name, Some(base))?), GltfPart::DefaultCamera),
    };
    let (lights, light_origins) = super::lights::lights(&nodes);
    let file =
        SceneFile { camera, objects, lights, sampling: overrides.sampling.clone(), render: overrides.render.clone() };
    let origins = Origins { camera: camera_origin, objects: object_origins, lights: light_origins };
    crate::scene::check::check(&file).map_err(|e| fail(Box::new(refused(e, &origins))))?;
    Ok(file)
}

/// An object for each node's primitives of one material (in the order the node's mesh first
/// uses each material), with its node and material as [`Origins`] keeps them.
fn objects(
    nodes: &[(::gltf::Node, Mat4)],
    file_name: &str,
    materials: &super::material::Materials,
) -> (Vec<Object>, Vec<(GltfPart, GltfPart)>) {
    let mut objects = Vec::new();
    let mut origins = Vec::new();
    for (node, _) in nodes {
        let Some(mesh) = node.mesh() else { continue };
        let mut seen: Vec<Option<usize>> = Vec::new();
        for primitive in mesh.primitives() {
            let material = primitive.material().index();
            if seen.contains(&material) {
                continue;
            }
            seen.push(material);
            let part = GltfNodePart { node: node.index(), material };
            let (spec, material_part) = materials.get(material);
            objects.push(Object {
                shape: Shape::Mesh { path: file_name.to_string(), node: None, part: Some(part) },
                transform: Transform::default(),
                material: spec,
                casts_shadow: true,
            });
            let node_part = GltfPart::Node { index: node.index(), name: node.name().map(str::to_string) };
            origins.push((node_part, material_part));
        }
    }
    (objects, origins)
}

/// A value the scene checks refused, named by the part of the file it came from: `object[i]`'s
/// material by its material and the rest by its node, `light[i]` by its light, `camera` by the
/// camera, `render` and `sampling` by the overrides.
fn refused(CheckError { key, value }: CheckError, origins: &Origins) -> GltfSceneProblem {
    let (head, rest) = key.split_once('.').unwrap_or((&key, ""));
    let indexed = |prefix: &str| head.strip_prefix(prefix)?.strip_suffix(']')?.parse::<usize>().ok();
    let part = if let Some(i) = indexed("object[") {
        origins.objects.get(i).map(|(node, material)| if rest.starts_with("material") { material } else { node })
    } else if let Some(i) = indexed("light[") {
        origins.lights.get(i)
    } else if head == "camera" {
        Some(&origins.camera)
    } else {
        None
    };
    let key = if part.is_some() && !rest.is_empty() { rest.to_string() } else { key.clone() };
    GltfSceneProblem::Value { part: part.cloned().unwrap_or(GltfPart::Overrides), key, value }
}
