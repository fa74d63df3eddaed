//! The lights of a glTF scene: each `KHR_lights_punctual` light a node places, in glTF's
//! photometric units divided by [`super::LUMENS_PER_WATT`] and scaled by its colour per
//! channel; a file without any gets the built-in scene's key light and sky. glTF lights shine
//! down their node's -z; a directional light's `direction` is towards the light, +z. A spot's
//! `outerConeAngle` is its `angle`, and its falloff from `innerConeAngle` out is the
//! `softness` fraction `1 - inner/outer`. `range` is not read: the lights fall off with the
//! square of distance without end.

use super::{GltfPart, LUMENS_PER_WATT};
use crate::scene::format::Light;
use ::gltf::khr_lights_punctual::Kind;
use glam::{Mat4, Vec3};

/// Every light among `nodes` (walked depth first, with world transforms), with its part of the
/// file; the default lights where there are none.
pub(super) fn lights(nodes: &[(::gltf::Node, Mat4)]) -> (Vec<Light>, Vec<GltfPart>) {
    let found: Vec<(Light, GltfPart)> = nodes
        .iter()
        .filter_map(|(node, world)| {
            let light = node.light()?;
            let part =
                GltfPart::Light { index: light.index(), name: light.name().map(str::to_string), node: node.index() };
            Some((mapped(&light, *world), part))
        })
        .collect();
    if found.is_empty() {
        let defaults = default_lights();
        let parts = vec![GltfPart::DefaultLights; defaults.len()];
        return (defaults, parts);
    }
    found.into_iter().unzip()
}

/// One light placed by `world`, in a scene's units.
fn mapped(light: &::gltf::khr_lights_punctual::Light, world: Mat4) -> Light {
    let power = Vec3::from(light.color()) * light.intensity() / LUMENS_PER_WATT;
    let position = world.transform_point3(Vec3::ZERO).to_array();
    let shining = world.transform_vector3(Vec3::NEG_Z).normalize_or_zero();
    match light.kind() {
        Kind::Directional => {
            Light::Directional { direction: (-shining).to_array(), irradiance: power.to_array(), shadows: true }
        }
        Kind::Point => Light::Point { position, intensity: power.to_array(), shadows: true },
        Kind::Spot { inner_cone_angle, outer_cone_angle } => Light::Spot {
            position,
            direction: shining.to_array(),
            intensity: power.to_array(),
            angle: f64::from(outer_cone_angle).to_degrees() as f32,
            softness: 1.0 - inner_cone_angle / outer_cone_angle,
            shadows: true,
        },
    }
}

/// The built-in scene's key light and sky (`assets/scenes/default.toml`), for a file without
/// lights.
fn default_lights() -> Vec<Light> {
    vec![
        Light::Directional { direction: [0.7, 0.6, -0.4], irradiance: [3.2, 2.9, 2.5], shadows: true },
        Light::Environment { map: None, scale: 0.3, directions: 16, shadows: true },
    ]
}
