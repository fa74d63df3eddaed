//! Scenes: the TOML format (`format`), loading with errors that name the file, key path and
//! line, value checks, and the built-in default scene.

pub mod accuracy;
pub mod build;
mod camera;
pub mod format;
pub mod lights;
pub mod needs;
mod object;
mod warnings;

pub use format::*;
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
    #[error("{file}: {message}")]
    Invalid {
        /// The scene's name: its path or "built-in scene".
        file: String,
        /// What is wrong, with the line and key path where they are known.
        message: String,
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

    /// Read, parse and check a scene file; its relative paths resolve from its folder.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text =
            std::fs::read_to_string(path).map_err(|source| SceneError::Read { path: path.to_path_buf(), source })?;
        let base = path.parent().map(Path::to_path_buf).unwrap_or_default();
        Scene::parse(&text, &path.display().to_string(), Some(base))
    }

    /// Parse and check `text`; `name` appears in errors.
    pub fn parse(text: &str, name: &str, base: Option<PathBuf>) -> Result<Scene, SceneError> {
        let invalid = |message: String| SceneError::Invalid { file: name.to_string(), message };
        let deserializer = toml::Deserializer::parse(text).map_err(|e| invalid(e.to_string()))?;
        let mut file: SceneFile = serde_path_to_error::deserialize(deserializer).map_err(|e| {
            let path = e.path().to_string();
            let inner = e.into_inner().to_string();
            // Inside internally tagged tables toml can only point at the table header; find
            // the offending key's own line (an unknown key by its name, a value of the wrong
            // type by its text).
            let unknown = inner
                .split("unknown field `")
                .nth(1)
                .and_then(|rest| rest.split('`').next())
                .and_then(|key| line_of(text, key))
                .map(|l| (l, None));
            let wrong = wrong_value(text, &inner);
            // Found by its value: toml's excerpt of the table header says nothing more.
            let inner = match (&wrong, inner.lines().last()) {
                (Some(_), Some(last)) if unknown.is_none() => last.to_string(),
                _ => inner,
            };
            let (line, key) = unknown.or(wrong).unzip();
            let line = line.map(|l| format!("line {l}: ")).unwrap_or_default();
            let path = match key.flatten() {
                // A plain table's path already ends with the key; a tagged table's stops at it.
                Some(key) if path == key || path.ends_with(&format!(".{key}")) => path,
                Some(key) if !path.is_empty() && path != "." => format!("{path}.{key}"),
                Some(key) => key,
                None => path,
            };
            if path.is_empty() || path == "." {
                invalid(format!("{line}{inner}"))
            } else {
                invalid(format!("{line}at key `{path}`: {inner}"))
            }
        })?;
        file.render.gather = file.render.gather_given.unwrap_or_default();
        file.render.gather_epsilon = file.render.gather_epsilon_given.unwrap_or(DEFAULT_GATHER_EPSILON);
        check(&file).map_err(|(key, message)| {
            let line = line_of(text, &key).map(|l| format!("line {l}: ")).unwrap_or_default();
            invalid(format!("{line}`{key}`: {message}"))
        })?;
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
                .ok_or_else(|| SceneError::Invalid {
                    file: self.name.clone(),
                    message: format!("no embedded asset named {relative:?}"),
                }),
        }
    }
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

type Check = Result<(), (String, String)>;

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

/// Finite, and within [`MAX_SCENE_COORDINATE`] of the origin on every axis.
fn coordinates(key: &str, values: &[f32]) -> Check {
    finite(key, values)?;
    match values.iter().find(|v| v.abs() > MAX_SCENE_COORDINATE) {
        Some(v) => Err((key.into(), format!("{v} is beyond the limit of {MAX_SCENE_COORDINATE:e} scene units"))),
        None => Ok(()),
    }
}

fn finite(key: &str, values: &[f32]) -> Check {
    match values.iter().find(|v| !v.is_finite()) {
        Some(v) => Err((key.into(), format!("{v} is not a finite number"))),
        None => Ok(()),
    }
}

fn nonzero(key: &str, v: [f32; 3]) -> Check {
    finite(key, &v)?;
    if v.iter().all(|c| *c == 0.0) { Err((key.into(), "must not be the zero vector".into())) } else { Ok(()) }
}

fn non_negative(key: &str, values: &[f32]) -> Check {
    finite(key, values)?;
    match values.iter().find(|v| **v < 0.0) {
        Some(v) => Err((key.into(), format!("{v} is negative"))),
        None => Ok(()),
    }
}

fn unit_interval(key: &str, v: f32) -> Check {
    if (0.0..=1.0).contains(&v) { Ok(()) } else { Err((key.into(), format!("{v} must be between 0 and 1"))) }
}

/// Every value of a parsed scene in range, section by section; the first that is not, as its
/// key path and what is wrong.
fn check(scene: &SceneFile) -> Check {
    check_camera(&scene.camera)?;
    if scene.objects.is_empty() {
        return Err(("object".into(), "the scene has no [[object]]".into()));
    }
    for (i, o) in scene.objects.iter().enumerate() {
        let key = |k: &str| format!("object[{i}].{k}");
        check_shape(&key, &o.shape)?;
        check_transform(&key, &o.transform)?;
        check_material(&key, &o.material)?;
    }
    check_lights(&scene.lights)?;
    let s = &scene.sampling;
    if let Some(count) = s.count
        && (count == 0 || count > MAX_SAMPLE_COUNT)
    {
        return Err(("sampling.count".into(), format!("{count} must be 1 to {MAX_SAMPLE_COUNT}")));
    }
    check_render(&scene.render)
}

/// `[camera]`: eye and target apart by a distance f32 can square, an up vector off the view
/// direction, a field of view a projection can use, 1 to 16384 pixels each way.
fn check_camera(c: &Camera) -> Check {
    coordinates("camera.eye", &c.eye)?;
    coordinates("camera.target", &c.target)?;
    nonzero("camera.up", c.up)?;
    if c.eye == c.target {
        return Err(("camera.target".into(), "equals camera.eye".into()));
    }
    // In f64: the f32 difference of two allowed points can still overflow when squared.
    let view = glam::Vec3::from(c.target).as_dvec3() - glam::Vec3::from(c.eye).as_dvec3();
    let distance = view.length();
    if !(MIN_CAMERA_DISTANCE as f64..=MAX_SCENE_COORDINATE as f64).contains(&distance) {
        return Err((
            "camera.target".into(),
            format!(
                "is {distance:e} from camera.eye; the distance must be {MIN_CAMERA_DISTANCE:e} to {MAX_SCENE_COORDINATE:e} \
                 scene units"
            ),
        ));
    }
    if view.normalize().cross(glam::Vec3::from(c.up).as_dvec3().normalize()).length() < 1e-4 {
        return Err(("camera.up".into(), format!("{:?} is parallel to the view direction", c.up)));
    }
    if !(c.fov_y >= MIN_FOV_Y && c.fov_y < 180.0) {
        return Err(("camera.fov_y".into(), format!("{} must be at least {MIN_FOV_Y} and below 180 degrees", c.fov_y)));
    }
    if c.resolution.iter().any(|r| *r == 0 || *r > 16384) {
        return Err(("camera.resolution".into(), format!("{:?} must be 1 to 16384 pixels each", c.resolution)));
    }
    Ok(())
}

/// An object's `shape`, `key` making its key paths: a mesh path that names something, a
/// built-in shape's size positive and within [`crate::mesh::MAX_COORDINATE`], 1 to 2048
/// divisions.
fn check_shape(key: &impl Fn(&str) -> String, shape: &Shape) -> Check {
    match shape {
        Shape::Mesh { path } if path.trim().is_empty() => Err((key("shape.path"), "is empty".into())),
        Shape::Plane { size, divisions } | Shape::Sphere { radius: size, divisions } => {
            if !(size.is_finite() && *size > 0.0) {
                return Err((key("shape"), format!("size/radius {size} must be positive")));
            }
            if *size > crate::mesh::MAX_COORDINATE {
                return Err((key("shape"), format!("size/radius {size:e} is above {:e}", crate::mesh::MAX_COORDINATE)));
            }
            if *divisions == 0 || *divisions > 2048 {
                return Err((key("shape.divisions"), format!("{divisions} must be 1 to 2048")));
            }
            Ok(())
        }
        _ => Ok(()),
    }
}

/// An object's `transform`: fit and scale positive, rotation finite, translation a coordinate.
fn check_transform(key: &impl Fn(&str) -> String, t: &Transform) -> Check {
    for (name, v) in [("transform.fit", t.fit), ("transform.scale", t.scale)] {
        if let Some(v) = v
            && !(v.is_finite() && v > 0.0)
        {
            return Err((key(name), format!("{v} must be positive")));
        }
    }
    finite(&key("transform.rotate"), &t.rotate.unwrap_or_default())?;
    coordinates(&key("transform.translate"), &t.translate.unwrap_or_default())
}

/// An object's `material`: a translucent one given by a preset or by both coefficients (not
/// both ways) with a positive scale, an opaque one's albedo at most 1 (it reflects no more
/// than it receives); roughness 0 to 1 for either.
fn check_material(key: &impl Fn(&str) -> String, material: &MaterialSpec) -> Check {
    match material {
        MaterialSpec::Translucent { preset, sigma_a, sigma_s_prime, mm_per_unit, roughness, .. } => {
            if preset.is_none() && (sigma_a.is_none() || sigma_s_prime.is_none()) {
                return Err((key("material"), "needs `preset` or both `sigma_a` and `sigma_s_prime`".into()));
            }
            if preset.is_some() && (sigma_a.is_some() || sigma_s_prime.is_some()) {
                return Err((key("material"), "give `preset` or coefficients, not both".into()));
            }
            if !(mm_per_unit.is_finite() && *mm_per_unit > 0.0) {
                return Err((key("material.mm_per_unit"), format!("{mm_per_unit} must be positive")));
            }
            unit_interval(&key("material.roughness"), *roughness)
        }
        MaterialSpec::Opaque { albedo, roughness } => {
            non_negative(&key("material.albedo"), albedo)?;
            if albedo.iter().any(|a| *a > 1.0) {
                return Err((key("material.albedo"), format!("{albedo:?} must be at most 1 (energy)")));
            }
            unit_interval(&key("material.roughness"), *roughness)
        }
    }
}

/// `[[light]]`: each light's values in range, and at most one environment light (there is one
/// environment map).
fn check_lights(lights: &[Light]) -> Check {
    let mut environments = 0;
    for (i, l) in lights.iter().enumerate() {
        let key = |k: &str| format!("light[{i}].{k}");
        match l {
            Light::Directional { direction, irradiance, .. } => {
                nonzero(&key("direction"), *direction)?;
                non_negative(&key("irradiance"), irradiance)?;
            }
            Light::Point { position, intensity, .. } => {
                coordinates(&key("position"), position)?;
                non_negative(&key("intensity"), intensity)?;
            }
            Light::Spot { position, direction, intensity, angle, softness, .. } => {
                coordinates(&key("position"), position)?;
                nonzero(&key("direction"), *direction)?;
                non_negative(&key("intensity"), intensity)?;
                if !(*angle > 0.0 && *angle < 90.0) {
                    return Err((key("angle"), format!("{angle} must be between 0 and 90 degrees")));
                }
                if !(*softness > 0.0 && *softness <= 1.0) {
                    return Err((key("softness"), format!("{softness} must be above 0 and at most 1")));
                }
            }
            Light::Environment { scale, directions, .. } => {
                environments += 1;
                non_negative(&key("scale"), &[*scale])?;
                if *directions == 0 || *directions > 256 {
                    return Err((key("directions"), format!("{directions} must be 1 to 256")));
                }
            }
        }
    }
    if environments > 1 {
        return Err(("light".into(), "at most one environment light".into()));
    }
    Ok(())
}

/// `[render]`: exposure positive, gather epsilon 0 to [`format::MAX_GATHER_EPSILON`], beam
/// opening 0 to [`format::MAX_BEAM_OPENING`], beam walks' memory at most
/// [`format::MAX_BEAM_WALK_MIB`], a shadow-map size of 16 to 8192 texels, a background that
/// emits nothing negative.
fn check_render(r: &RenderSettings) -> Check {
    if !(r.exposure.is_finite() && r.exposure > 0.0) {
        return Err(("render.exposure".into(), format!("{} must be positive", r.exposure)));
    }
    if !(r.gather_epsilon >= 0.0 && r.gather_epsilon <= format::MAX_GATHER_EPSILON) {
        return Err((
            "render.gather_epsilon".into(),
            format!("{} must be 0 to {}", r.gather_epsilon, format::MAX_GATHER_EPSILON),
        ));
    }
    if !(r.beam_opening >= 0.0 && r.beam_opening <= format::MAX_BEAM_OPENING) {
        return Err((
            "render.beam_opening".into(),
            format!("{} must be 0 to {}", r.beam_opening, format::MAX_BEAM_OPENING),
        ));
    }
    if r.beam_walk_mib > format::MAX_BEAM_WALK_MIB {
        return Err((
            "render.beam_walk_mib".into(),
            format!("{} must be 0 to {}", r.beam_walk_mib, format::MAX_BEAM_WALK_MIB),
        ));
    }
    if !(16..=8192).contains(&r.shadow_map_size) {
        return Err(("render.shadow_map_size".into(), format!("{} must be 16 to 8192", r.shadow_map_size)));
    }
    non_negative("render.background", &r.background.unwrap_or_default())?;
    check_texture("render.texture_samples", "render.texture_resolution", r.texture_samples, r.texture_resolution)
        .map_err(|e| (e.key.to_string(), format!("{} must be {} to {}", e.value, e.min, e.max)))?;
    check_max_error("render.max_error", r.max_error)
}

/// The texture gather's sample count (0 to [`format::MAX_TEXTURE_SAMPLES`]) and atlas
/// resolution (`mesh::atlas::MIN_RESOLUTION` to `MAX_RESOLUTION`), under the keys or flags named.
pub fn check_texture(
    samples_key: &'static str,
    resolution_key: &'static str,
    samples: u32,
    resolution: u32,
) -> Result<(), OutOfRange> {
    use crate::mesh::atlas::{MAX_RESOLUTION, MIN_RESOLUTION};
    if samples > format::MAX_TEXTURE_SAMPLES {
        return Err(OutOfRange { key: samples_key, value: samples, min: 0, max: format::MAX_TEXTURE_SAMPLES });
    }
    if !(MIN_RESOLUTION..=MAX_RESOLUTION).contains(&resolution) {
        return Err(OutOfRange { key: resolution_key, value: resolution, min: MIN_RESOLUTION, max: MAX_RESOLUTION });
    }
    Ok(())
}

/// A relative error target (`render.max_error`, `--max-error`) within
/// [`format::MIN_MAX_ERROR`] to [`format::MAX_MAX_ERROR`].
pub fn check_max_error(key: &str, e: f64) -> Check {
    if !(format::MIN_MAX_ERROR..=format::MAX_MAX_ERROR).contains(&e) {
        return Err((
            key.into(),
            format!(
                "{e} must be {} to {} (a relative error: 0.01 is 1%)",
                format::MIN_MAX_ERROR,
                format::MAX_MAX_ERROR
            ),
        ));
    }
    Ok(())
}
