//! The camera of a glTF scene: the first camera a node places (depth first, in file order), or
//! one framing the scene's meshes. A glTF camera looks down its node's -z with +y up; the scene's
//! `target` is one unit along that axis (only its direction matters to the view).

use super::{GltfPart, GltfSceneProblem};
use crate::scene::format::Camera;
use glam::{Mat4, Vec3};

/// Image height, in pixels, of a glTF scene's camera; the width follows its `aspectRatio`
/// (square without one). `--resolution` overrides it.
pub const HEIGHT: u32 = 512;

/// The vertical field of view, in degrees, of the camera made for a file without one.
pub const DEFAULT_FOV_Y: f32 = 35.0;

/// The first perspective camera among `nodes` (walked depth first, with world transforms) and
/// its part of the file; `None` where no node places a camera. An orthographic one is refused.
pub(super) fn first(
    document: &::gltf::Document,
    nodes: &[(::gltf::Node, Mat4)],
) -> Result<Option<(Camera, GltfPart)>, Box<GltfSceneProblem>> {
    let Some((node, world, camera)) = nodes.iter().find_map(|(n, w)| Some((n, w, n.camera()?))) else {
        return Ok(None);
    };
    let part = GltfPart::Camera { node: node.index(), camera: camera.index() };
    // Read from the JSON: the gltf crate's `projection` unwraps a type whose table is missing,
    // which its validation lets through when the other type's table is there.
    let json = &document.as_json().cameras[camera.index()];
    let perspective = match (json.type_, &json.perspective) {
        (::gltf::json::validation::Checked::Valid(::gltf::json::camera::Type::Perspective), Some(p)) => p,
        _ => return Err(Box::new(GltfSceneProblem::Orthographic { camera: part })),
    };
    let eye = world.transform_point3(Vec3::ZERO);
    let forward = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(Vec3::Y);
    let width = perspective.aspect_ratio.map_or(HEIGHT as f32, |a| (a * HEIGHT as f32).round());
    let camera = Camera {
        eye: eye.to_array(),
        target: (eye + forward).to_array(),
        up: up.to_array(),
        fov_y: f64::from(perspective.yfov).to_degrees() as f32,
        resolution: [width.clamp(1.0, 16384.0) as u32, HEIGHT],
    };
    Ok(Some((camera, part)))
}

/// A camera framing the box `lo`..`hi`: looking at its centre from the front (+z, glTF's
/// forward for a model) and a little above, far enough that its bounding sphere fits the
/// vertical field of view with a tenth to spare.
pub(super) fn framing((lo, hi): (Vec3, Vec3)) -> Camera {
    let centre = 0.5 * (lo + hi);
    let radius = (0.5 * (hi - lo).length()).max(f32::MIN_POSITIVE.sqrt());
    let distance = 1.1 * radius / (0.5 * DEFAULT_FOV_Y.to_radians()).sin();
    let eye = centre + distance * Vec3::new(0.0, 0.35, 1.0).normalize();
    Camera {
        eye: eye.to_array(),
        target: centre.to_array(),
        up: [0.0, 1.0, 0.0],
        fov_y: DEFAULT_FOV_Y,
        resolution: [HEIGHT, HEIGHT],
    }
}
