//! Scenes: the TOML format (`format`), loading with errors that name the file, key path and
//! line, value checks, and the built-in default scene.

pub mod accuracy;
pub mod build;
mod camera;
mod check;
pub mod format;
pub mod gltf;
pub mod lights;
pub mod model_choice;
pub mod needs;
mod object;
mod warnings;

pub use check::{BadValue, Check, CheckError, Number, check_max_error, check_texture};
pub use format::*;
pub use gltf::{GltfOverrides, GltfPart, GltfSceneProblem};
use std::path::{Path, PathBuf};

/// The built-in scene that `translucent render` draws with no arguments.
pub const DEFAULT_SCENE: &str = include_str!("../../assets/scenes/default.toml");

/// Assets embedded in the binary, so the default scene renders from any working directory.
pub const EMBEDDED_ASSETS: &[(&str, &[u8])] = &[("../bunny-37k.obj", include_bytes!("../../assets/bunny-37k.obj"))];

/// Why a scene could not be read, checked or prepared. A prepared scene's errors come wrapped in
/// [`SceneError::Context`], which says where (scene file, object, key); the cause is its
/// source, shown after it by `{:#}` and error reporters.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    // The io::Error is the source, not repeated here.
    /// The scene file could not be read.
    #[error("cannot read scene {}", path.display())]
    Read {
        /// The scene file.
        path: PathBuf,
        /// Why reading failed.
        source: std::io::Error,
    },
    /// The text is not a valid scene: TOML syntax, an unknown key, a wrong type or a value out
    /// of range.
    #[error("{file}: {}", Located(location, problem))]
    Invalid {
        /// The scene's name: its path or "built-in scene".
        file: String,
        /// The line and key path, where they are known.
        location: Location,
        /// What is wrong (boxed: toml's errors are large, and every error of a prepared scene
        /// and of a renderer carries this type).
        problem: Box<Problem>,
    },
    /// The built-in scene names an asset that is not embedded in the binary.
    #[error("{file}: no embedded asset named {name:?}")]
    NoEmbeddedAsset {
        /// The scene's name ("built-in scene").
        file: String,
        /// The asset's path as the scene gives it.
        name: String,
    },
    /// `--samples 0` on the command line.
    #[error("--samples must be at least 1")]
    ZeroSamples,
    /// `--samples` above [`MAX_SAMPLE_COUNT`].
    #[error("--samples {0} is above the limit of {MAX_SAMPLE_COUNT} (as for sampling.count)")]
    TooManySamples(usize),
    /// `--gather-epsilon` outside its range.
    #[error("--gather-epsilon {0} must be 0 to {MAX_GATHER_EPSILON} (as for render.gather_epsilon)")]
    GatherEpsilon(f32),
    /// `--texture-samples` or `--texture-resolution` outside its range.
    #[error(transparent)]
    Flag(#[from] OutOfRange),
    /// A mesh got no texture atlas (`render.gather = "texture"`); `{:#}` shows where, by
    /// [`SceneError::Context`], and this the cause.
    #[error(transparent)]
    Atlas(#[from] crate::mesh::atlas::AtlasError),
    /// `--max-error` outside its range.
    #[error("--max-error {0} must be {MIN_MAX_ERROR} to {MAX_MAX_ERROR} (as for render.max_error; 0.01 is 1%)")]
    MaxError(f64),
    /// `transform.fit` on a mesh whose bounding box has no extent.
    #[error("cannot fit a mesh with an empty bounding box")]
    EmptyBounds,
    /// An OBJ file embedded in the binary is not valid UTF-8.
    #[error("embedded mesh is not UTF-8")]
    EmbeddedMeshNotUtf8(#[source] std::str::Utf8Error),
    /// The built-in scene names an environment map, and none are embedded.
    #[error("embedded environment maps are not supported")]
    EmbeddedEnvironment,
    /// A mesh could not be loaded or built.
    #[error(transparent)]
    Mesh(#[from] crate::mesh::MeshError),
    /// A material was refused.
    #[error(transparent)]
    Optics(#[from] crate::optics::OpticsError),
    /// Sample points could not be placed.
    #[error(transparent)]
    Sampling(#[from] crate::sampling::SamplingError),
    /// An environment map was refused.
    #[error(transparent)]
    Environment(#[from] lights::EnvironmentError),
    /// A glTF scene the file's parts cannot make: a camera, light, material or value, named.
    #[error("{file}: {problem}")]
    Gltf {
        /// The glTF file.
        file: String,
        /// What is wrong, and where in the file.
        problem: Box<GltfSceneProblem>,
    },
    /// `context` names where (e.g. `scene.toml: object[0] (bunny.obj): sampling`).
    #[error("{context}")]
    Context {
        /// Where the error happened: scene file, object, key.
        context: String,
        /// The error itself.
        source: Box<SceneError>,
    },
}

impl SceneError {
    /// This error as the source of a [`SceneError::Context`] that names where it happened.
    pub(crate) fn in_context(self, context: String) -> SceneError {
        SceneError::Context { context, source: Box::new(self) }
    }
}

/// Where in a scene file a [`Problem`] is: the 1-based line and the key path, where known.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Location {
    /// The 1-based line.
    pub line: Option<usize>,
    /// The key path, e.g. `object[0].material.roughness`.
    pub key: Option<String>,
}

impl Location {
    /// At key path `key`, on the line of `text` that assigns its last segment if one does.
    fn of_key(text: &str, key: String) -> Location {
        Location { line: line_of(text, &key), key: Some(key) }
    }

    /// At key path `key`, line unknown.
    pub(crate) fn key(key: String) -> Location {
        Location { line: None, key: Some(key) }
    }
}

/// What makes a scene text invalid ([`SceneError::Invalid`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum Problem {
    /// Not TOML; toml's error shows the line and an excerpt.
    #[error("{0}")]
    Syntax(toml::de::Error),
    /// TOML, but not a scene: an unknown key or variant, a missing key, a value of the wrong
    /// type or length.
    #[error("{}", deserialize_message(error, *brief))]
    Deserialize {
        /// toml's (serde's) error.
        error: toml::de::Error,
        /// Show only its last line, the message: the line was found by the offending value,
        /// and toml's excerpt (of the table's header) says nothing more.
        brief: bool,
    },
    /// A value out of range.
    #[error(transparent)]
    Value(#[from] BadValue),
}

impl From<BadValue> for Box<Problem> {
    fn from(value: BadValue) -> Box<Problem> {
        Box::new(Problem::Value(value))
    }
}

/// A deserialisation error as shown: all of toml's text, or (`brief`) its last line.
fn deserialize_message(error: &toml::de::Error, brief: bool) -> String {
    let text = error.to_string();
    match text.lines().last() {
        Some(last) if brief => last.to_string(),
        _ => text,
    }
}

/// A [`Problem`] after its [`Location`]: `line N: ` where known, then the key path as the kind
/// of problem reads it (``at key `k`: `` for deserialisation, `` `k`: `` for a value, with the
/// object's name after it where it has one).
struct Located<'a>(&'a Location, &'a Problem);

impl std::fmt::Display for Located<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let Located(location, problem) = *self;
        if let Some(line) = location.line {
            write!(f, "line {line}: ")?;
        }
        match (&location.key, problem) {
            (Some(key), Problem::Deserialize { .. }) => write!(f, "at key `{key}`: ")?,
            (Some(key), Problem::Value(BadValue::BeyondReach { object, .. })) => write!(f, "`{key}` ({object}): ")?,
            (Some(key), _) => write!(f, "`{key}`: ")?,
            (None, _) => {}
        }
        write!(f, "{problem}")
    }
}

/// A whole-number setting outside its range, named by its key or flag: what
/// [`check_texture`] refuses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{key} {value} must be {min} to {max}")]
pub struct OutOfRange {
    /// The scene key (`render.texture_samples`) or command-line flag (`--texture-samples`).
    pub key: &'static str,
    /// The value given.
    pub value: u32,
    /// The least allowed.
    pub min: u32,
    /// The most allowed.
    pub max: u32,
}

/// Most sample points per translucent object (`sampling.count`, `--samples`).
pub const MAX_SAMPLE_COUNT: usize = 1_000_000;

/// A parsed, checked scene and where its relative paths resolve.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The scene file's contents, checked.
    pub file: SceneFile,
    /// Folder of the scene file; `None` for the built-in scene (paths resolve to embedded assets).
    pub base: Option<PathBuf>,
    /// For messages: the scene file's path or "built-in scene".
    pub name: String,
}

/// Where an asset named in a scene comes from.
pub enum AssetSource {
    /// A file on disk, relative to the scene file's folder.
    File(PathBuf),
    /// The bytes of an asset embedded in the binary ([`EMBEDDED_ASSETS`]).
    Embedded(&'static [u8]),
}

impl Scene {
    /// The built-in scene ([`DEFAULT_SCENE`]), whose assets are embedded.
    pub fn builtin() -> Scene {
        Scene::parse(DEFAULT_SCENE, "built-in scene", None).expect("the built-in scene is valid")
    }

    /// Read, parse and check a scene file; its relative paths resolve from its folder. A
    /// `.gltf` or `.glb` is read as a glTF scene ([`Scene::from_gltf`]) with the overrides
    /// beside it, if any ([`GltfOverrides::beside`]).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        if crate::mesh::is_gltf(path) {
            return Scene::from_gltf(path, &GltfOverrides::beside(path)?);
        }
        let text =
            std::fs::read_to_string(path).map_err(|source| SceneError::Read { path: path.to_path_buf(), source })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse(&text, &path.display().to_string(), Some(base))
    }

    /// Parse and check `text`; `name` appears in errors.
    pub fn parse(text: &str, name: &str, base: Option<PathBuf>) -> Result<Scene, SceneError> {
        let invalid =
            |location, problem| SceneError::Invalid { file: name.to_string(), location, problem: Box::new(problem) };
        let deserializer =
            toml::Deserializer::parse(text).map_err(|e| invalid(Location::default(), Problem::Syntax(e)))?;
        let mut file: SceneFile = serde_path_to_error::deserialize(deserializer).map_err(|e| {
            let (location, problem) = deserialize_error(text, e);
            invalid(location, problem)
        })?;
        file.render.gather = file.render.gather_given.unwrap_or_default();
        file.render.gather_epsilon = file.render.gather_epsilon_given.unwrap_or(DEFAULT_GATHER_EPSILON);
        check::check(&file)
            .map_err(|CheckError { key, value }| invalid(Location::of_key(text, key), Problem::Value(value)))?;
        Ok(Scene { file, base, name: name.to_string() })
    }

    /// Resolve a path named in the scene: relative to the scene file, or among embedded assets.
    pub fn resolve(&self, relative: &str) -> Result<AssetSource, SceneError> {
        match &self.base {
            Some(base) => Ok(AssetSource::File(base.join(relative))),
            None => EMBEDDED_ASSETS
                .iter()
                .find(|(n, _)| *n == relative)
                .map(|(_, bytes)| AssetSource::Embedded(bytes))
                .ok_or_else(|| SceneError::NoEmbeddedAsset { file: self.name.clone(), name: relative.to_string() }),
        }
    }
}

/// Where a deserialisation error of `text` is and what it says. Inside internally tagged tables
/// toml can only point at the table header; the offending key's own line is found instead (an
/// unknown key by its name, a value of the wrong type by its text), and then toml's excerpt of
/// the header is left out.
fn deserialize_error(text: &str, e: serde_path_to_error::Error<toml::de::Error>) -> (Location, Problem) {
    let path = e.path().to_string();
    let error = e.into_inner();
    let inner = error.to_string();
    let unknown = inner
        .split("unknown field `")
        .nth(1)
        .and_then(|rest| rest.split('`').next())
        .and_then(|key| line_of(text, key))
        .map(|l| (l, None));
    let wrong = wrong_value(text, &inner);
    let brief = wrong.is_some() && unknown.is_none();
    let (line, key) = unknown.or(wrong).unzip();
    let path = match key.flatten() {
        // A plain table's path already ends with the key; a tagged table's stops at it.
        Some(key) if path == key || path.ends_with(&format!(".{key}")) => path,
        Some(key) if !path.is_empty() && path != "." => format!("{path}.{key}"),
        Some(key) => key,
        None => path,
    };
    let key = (!path.is_empty() && path != ".").then_some(path);
    (Location { line, key }, Problem::Deserialize { error, brief })
}

/// The 1-based line where the last segment of a dotted key path is assigned, if it is found.
/// For a serde "invalid type: string \"x\", expected ..." error inside a table toml reports only
/// by its header: the line after that header where a key is given that value, and the key.
fn wrong_value(text: &str, message: &str) -> Option<(usize, Option<String>)> {
    let value = message.split("invalid type: ").nth(1)?.split(", expected").next()?;
    // `string "x"`, `integer `5``, `floating point `1.5``, `boolean `true``.
    let literal = match value.split_once('"') {
        Some((_, rest)) => format!("\"{}", rest),
        None => value.split('`').nth(1)?.to_string(),
    };
    let header =
        message.split("at line ").nth(1)?.split(|c: char| !c.is_ascii_digit()).next()?.parse::<usize>().ok()?;
    text.lines().enumerate().skip(header.saturating_sub(1)).find_map(|(i, l)| {
        let code = l.split('#').next()?;
        let at = code.find(&format!("= {literal}")).or_else(|| code.find(&format!("={literal}")))?;
        let before = code[..at].trim_end();
        let key = before.rsplit(|c: char| !(c.is_alphanumeric() || c == '_')).next()?.to_string();
        Some((i + 1, (!key.is_empty()).then_some(key)))
    })
}

fn line_of(text: &str, key: &str) -> Option<usize> {
    let last = key.rsplit('.').next()?.split('[').next()?;
    text.lines()
        .position(|l| {
            let l = l.trim_start();
            l.strip_prefix(last).is_some_and(|rest| rest.trim_start().starts_with('='))
        })
        .map(|i| i + 1)
}

/// The largest coordinate (and camera distance) a scene may use, in scene units: squared
/// lengths of positions and distances up to this stay finite in f32 (they overflow near
/// 1.8e19), so the camera, the light frusta and the bounding spheres stay finite.
pub const MAX_SCENE_COORDINATE: f32 = 1e18;
/// The smallest distance between `camera.eye` and `camera.target`: below it the view
/// direction's squared length underflows f32.
pub const MIN_CAMERA_DISTANCE: f32 = 1e-18;
/// The smallest vertical field of view, in degrees: below it the projection's focal length
/// is not finite.
pub const MIN_FOV_Y: f32 = 1e-3;

#[cfg(test)]
mod tests {
    use super::*;

    const MINIMAL: &str = r#"
[camera]
eye = [0.0, 1.0, 3.0]
target = [0.0, 0.0, 0.0]

[[object]]
shape = { type = "sphere", radius = 1.0 }
material = { type = "translucent", preset = "skimmilk", mm_per_unit = 10.0 }
"#;

    fn invalid(text: &str) -> (Location, Problem, String) {
        match Scene::parse(text, "t.toml", None) {
            Err(e @ SceneError::Invalid { .. }) => {
                let message = e.to_string();
                let SceneError::Invalid { location, problem, .. } = e else { unreachable!() };
                (location, *problem, message)
            }
            other => panic!("expected SceneError::Invalid, got {other:?}"),
        }
    }

    #[test]
    fn a_value_out_of_range_is_typed_with_its_line_and_key() {
        let (location, problem, message) =
            invalid(&MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfov_y = 190.0"));
        assert_eq!(location, Location { line: Some(5), key: Some("camera.fov_y".into()) });
        assert_eq!(problem, Problem::Value(BadValue::FieldOfView(190.0)));
        assert_eq!(message, "t.toml: line 5: `camera.fov_y`: 190 must be at least 0.001 and below 180 degrees");
    }

    #[test]
    fn syntax_and_deserialisation_errors_carry_toml_s_error() {
        let (location, problem, message) = invalid("[camera]\neye = [0.0, 1.0\n");
        assert_eq!(location, Location::default());
        assert!(matches!(problem, Problem::Syntax(_)), "{problem:?}");
        assert!(message.starts_with("t.toml: TOML parse error at line 2"), "{message}");

        // A wrong type in an inline table: found by its value, so only toml's message is shown.
        let (location, problem, message) = invalid(&MINIMAL.replace("radius = 1.0", "radius = \"big\""));
        assert_eq!(location, Location { line: Some(7), key: Some("object[0].shape.radius".into()) });
        assert!(matches!(problem, Problem::Deserialize { brief: true, .. }), "{problem:?}");
        assert_eq!(
            message,
            "t.toml: line 7: at key `object[0].shape.radius`: invalid type: string \"big\", expected f32"
        );

        // An unknown key: its own line, and toml's whole text.
        let (location, problem, message) =
            invalid(&MINIMAL.replace("target = [0.0, 0.0, 0.0]", "target = [0.0, 0.0, 0.0]\nfov = 1.0"));
        assert_eq!(location, Location { line: Some(5), key: Some("camera.fov".into()) });
        assert!(matches!(problem, Problem::Deserialize { brief: false, .. }), "{problem:?}");
        assert!(message.starts_with("t.toml: line 5: at key `camera.fov`: TOML parse error"), "{message}");
        assert!(message.contains("unknown field `fov`"), "{message}");
    }

    #[test]
    fn problems_found_when_prepared_read_as_before() {
        let reach = SceneError::Invalid {
            file: "s.toml".into(),
            location: Location::key("object[2]".into()),
            problem: BadValue::BeyondReach { object: "bunny.obj".into(), reach: 2e18 }.into(),
        };
        assert_eq!(
            reach.to_string(),
            "s.toml: `object[2]` (bunny.obj): placed by its shape and transform it reaches 2e18 scene units from \
             the origin, beyond the limit of 1e18"
        );
        let light = SceneError::Invalid {
            file: "s.toml".into(),
            location: Location::key("light[1].scale".into()),
            problem: BadValue::LightNotFinite(lights::LightKind::Point {
                position: glam::Vec3::ZERO,
                intensity: glam::Vec3::INFINITY,
            })
            .into(),
        };
        assert_eq!(
            light.to_string(),
            "s.toml: `light[1].scale`: the light is not finite once prepared (Point { position: Vec3(0.0, 0.0, 0.0), \
             intensity: Vec3(inf, inf, inf) }); lower it"
        );
    }

    #[test]
    fn a_missing_embedded_asset_is_its_own_error() {
        let e = Scene::builtin().resolve("missing.obj").err().expect("not embedded");
        assert!(matches!(&e, SceneError::NoEmbeddedAsset { name, .. } if name == "missing.obj"), "{e:?}");
        assert_eq!(e.to_string(), "built-in scene: no embedded asset named \"missing.obj\"");
    }
}
