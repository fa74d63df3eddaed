//! glTF 2.0 scenes (issue 48): a `.gltf` or `.glb` read as a whole scene. The file becomes the
//! same [`SceneFile`] a TOML scene parses to, checked by the same checks: an object per node's
//! primitives of one material, the first camera, the `KHR_lights_punctual` lights, and materials
//! from `KHR_materials_volume` and `KHR_materials_diffuse_transmission` (docs/SCENES.md, "glTF
//! scenes", has the mapping). What glTF cannot say (a measured medium, the sample count) comes
//! from [`GltfOverrides`], a TOML file beside the scene.
//!
//! The reading itself needs the crate's `gltf` feature; without it, [`Scene::from_gltf`] says so.

#[cfg(feature = "gltf")]
mod camera;
#[cfg(feature = "gltf")]
mod lights;
#[cfg(feature = "gltf")]
mod material;
#[cfg(feature = "gltf")]
mod read;

use super::format::{MaterialSpec, RenderSettings, Sampling};
use super::{BadValue, Location, Problem, Scene, SceneError};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Luminous efficacy, lumens per watt, by which glTF's photometric light units become the
/// radiometric ones of a scene: candela (lm/sr) to W/sr, lux (lm/m^2) to W/m^2. 683 lm/W is the
/// efficacy at 555 nm that defines the candela; the file's light colour then scales each
/// channel (a white light of 683 cd is 1 W/sr in every channel).
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Millimetres per glTF unit: glTF's unit is the metre, a translucent material's coefficients
/// are per millimetre (`mm_per_unit` of the materials a glTF scene makes).
pub const MM_PER_GLTF_UNIT: f64 = 1000.0;

/// What a glTF scene cannot say, from a TOML file beside it (`scene.glb.toml` for `scene.glb`,
/// [`GltfOverrides::beside`]): `[material."NAME"]` tables, each a scene file's `material` (a
/// preset or coefficients, or an opaque one) that replaces the material of that name; and the
/// scene file's `[sampling]` and `[render]` tables. Unknown keys are errors, as in a scene.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GltfOverrides {
    /// Materials by the name the glTF file gives them.
    #[serde(default)]
    pub material: BTreeMap<String, MaterialSpec>,
    /// `[sampling]`, as in a scene file (default: a scene file's defaults).
    #[serde(default)]
    pub sampling: Sampling,
    /// `[render]`, as in a scene file (default: a scene file's defaults).
    #[serde(default)]
    pub render: RenderSettings,
}

impl GltfOverrides {
    /// The overrides file of the glTF scene at `path`: its name with `.toml` added.
    pub fn path_beside(path: &Path) -> PathBuf {
        let mut name = path.as_os_str().to_owned();
        name.push(".toml");
        PathBuf::from(name)
    }

    /// The overrides beside the glTF scene at `path` ([`GltfOverrides::path_beside`]), or none
    /// when there is no such file.
    pub fn beside(path: &Path) -> Result<GltfOverrides, SceneError> {
        let file = GltfOverrides::path_beside(path);
        match std::fs::read_to_string(&file) {
            Ok(text) => GltfOverrides::parse(&text, &file.display().to_string()),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(GltfOverrides::default()),
            Err(source) => Err(SceneError::Read { path: file, source }),
        }
    }

    /// Parse overrides from TOML `text`; `name` appears in errors, which name the key and line
    /// as a scene file's do. Values are checked with the scene they apply to.
    pub fn parse(text: &str, name: &str) -> Result<GltfOverrides, SceneError> {
        let invalid =
            |location, problem| SceneError::Invalid { file: name.to_string(), location, problem: Box::new(problem) };
        let deserializer =
            toml::Deserializer::parse(text).map_err(|e| invalid(Location::default(), Problem::Syntax(e)))?;
        let mut overrides: GltfOverrides = serde_path_to_error::deserialize(deserializer).map_err(|e| {
            let (location, problem) = super::deserialize_error(text, e);
            invalid(location, problem)
        })?;
        let render = &mut overrides.render;
        render.gather = render.gather_given.unwrap_or_default();
        render.gather_epsilon = render.gather_epsilon_given.unwrap_or(super::DEFAULT_GATHER_EPSILON);
        Ok(overrides)
    }
}

/// A part of a glTF file, as errors name it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum GltfPart {
    /// A node (and the mesh it places).
    Node {
        /// Its index.
        index: usize,
        /// Its name, if it has one.
        name: Option<String>,
    },
    /// The camera a node places.
    Camera {
        /// The node's index.
        node: usize,
        /// The camera's index.
        camera: usize,
    },
    /// The camera made for a file without one, framing its meshes.
    DefaultCamera,
    /// A `KHR_lights_punctual` light a node places.
    Light {
        /// The light's index.
        index: usize,
        /// Its name, if it has one.
        name: Option<String>,
        /// The node's index.
        node: usize,
    },
    /// The lights given a file without any.
    DefaultLights,
    /// A material (`index` `None`: glTF's default material).
    Material {
        /// Its index.
        index: Option<usize>,
        /// Its name, if it has one.
        name: Option<String>,
    },
    /// The overrides' `[sampling]` or `[render]`.
    Overrides,
}

impl std::fmt::Display for GltfPart {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let named = |f: &mut std::fmt::Formatter<'_>, name: &Option<String>| match name {
            Some(name) => write!(f, " {name:?}"),
            None => Ok(()),
        };
        match self {
            GltfPart::Node { index, name } => {
                write!(f, "node {index}")?;
                named(f, name)
            }
            GltfPart::Camera { node, camera } => write!(f, "camera {camera} (node {node})"),
            GltfPart::DefaultCamera => f.write_str("the default camera"),
            GltfPart::Light { index, name, node } => {
                write!(f, "KHR_lights_punctual light {index}")?;
                named(f, name)?;
                write!(f, " (node {node})")
            }
            GltfPart::DefaultLights => f.write_str("the default lights"),
            GltfPart::Material { index: Some(index), name } => {
                write!(f, "material {index}")?;
                named(f, name)
            }
            GltfPart::Material { index: None, .. } => f.write_str("the default material"),
            GltfPart::Overrides => f.write_str("the overrides"),
        }
    }
}

/// What is wrong with a glTF scene, beyond what its meshes' reader refuses
/// ([`SceneError::Gltf`]); each names the part of the file.
#[derive(Debug, thiserror::Error)]
pub enum GltfSceneProblem {
    /// The first camera is orthographic; only perspective cameras are read.
    #[error("{camera} is orthographic; only perspective cameras are read")]
    Orthographic {
        /// The camera.
        camera: GltfPart,
    },
    /// A translucent material whose `KHR_materials_volume` gives no extinction in a channel
    /// (attenuationColor 1 or 0, or no finite attenuationDistance).
    #[error(
        "{material}: KHR_materials_volume gives channel {channel} no finite, positive extinction (attenuationColor \
         {color}, attenuationDistance {distance}); give attenuation, or override the material by its name"
    )]
    NoExtinction {
        /// The material.
        material: GltfPart,
        /// The channel (0 red, 1 green, 2 blue).
        channel: usize,
        /// Its attenuation colour.
        color: f32,
        /// The attenuation distance.
        distance: f32,
    },
    /// A material with `KHR_materials_diffuse_transmission` and no volume to give its medium's
    /// extinction.
    #[error(
        "{material}: KHR_materials_diffuse_transmission without KHR_materials_volume gives no extinction; add a \
         volume with attenuation, or override the material by its name"
    )]
    NoVolume {
        /// The material.
        material: GltfPart,
    },
    /// A material's colour or index of refraction the dipole cannot take.
    #[error("{material}: {source}")]
    Medium {
        /// The material.
        material: GltfPart,
        /// Why.
        source: crate::optics::OpticsError,
    },
    /// The overrides name a material the file does not have.
    #[error("the overrides name material {name:?}, and no material of the file has that name (its names: {names:?})")]
    NoSuchMaterial {
        /// The name the overrides give.
        name: String,
        /// Every material name of the file.
        names: Vec<String>,
    },
    /// A value, as the file gives it or once mapped, out of the range a scene allows.
    #[error("{part}: `{key}`: {value}")]
    Value {
        /// Where it comes from.
        part: GltfPart,
        /// The scene key it became (`intensity`, `angle`, `material.albedo`, ...).
        key: String,
        /// What is wrong.
        value: BadValue,
    },
}

impl Scene {
    /// A glTF 2.0 file (`.gltf` with its buffer files, or `.glb`) as a scene: its default scene
    /// (else its first) with its camera, lights and materials, `overrides` applied
    /// (docs/SCENES.md, "glTF scenes"). Its meshes are read when it is prepared.
    pub fn from_gltf(path: &Path, overrides: &GltfOverrides) -> Result<Scene, SceneError> {
        if cfg!(not(feature = "gltf")) {
            return Err(SceneError::Mesh(crate::mesh::MeshError::GltfDisabled { path: path.to_path_buf() }));
        }
        let bytes = std::fs::read(path).map_err(|source| SceneError::Read { path: path.to_path_buf(), source })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let file_name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        Scene::from_gltf_slice(&bytes, &path.display().to_string(), (base, &file_name), overrides)
    }

    /// A glTF 2.0 file in memory as a scene, as [`Scene::from_gltf`]: `name` appears in errors,
    /// `base` is its folder and `file_name` its name there, by which its objects load their
    /// meshes.
    pub fn from_gltf_slice(
        bytes: &[u8],
        name: &str,
        (base, file_name): (PathBuf, &str),
        overrides: &GltfOverrides,
    ) -> Result<Scene, SceneError> {
        #[cfg(feature = "gltf")]
        {
            let file = read::scene_file(bytes, name, (&base, file_name), overrides)?;
            Ok(Scene { file, base: Some(base), name: name.to_string() })
        }
        #[cfg(not(feature = "gltf"))]
        {
            let _ = (bytes, base, file_name, overrides);
            Err(SceneError::Mesh(crate::mesh::MeshError::GltfDisabled { path: PathBuf::from(name) }))
        }
    }
}
