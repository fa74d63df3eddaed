//! The value checks of a parsed scene: every value in range, section by section. A value out
//! of range is a [`BadValue`]; with the key path that gives it, a [`CheckError`].

use super::format::{self, Camera, Light, MaterialSpec, RenderSettings, SceneFile, Shape, Transform};
use super::lights::LightKind;
use super::{MAX_SAMPLE_COUNT, MAX_SCENE_COORDINATE, MIN_CAMERA_DISTANCE, MIN_FOV_Y, OutOfRange};

/// A number as a scene gives it, shown as its own type shows it (an `f32` of 0.1 as `0.1`, not
/// as the `f64` it widens to).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Number {
    /// A single-precision value.
    F32(f32),
    /// A double-precision value.
    F64(f64),
    /// A whole number (a count or a size).
    Int(u64),
}

impl std::fmt::Display for Number {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Number::F32(v) => v.fmt(f),
            Number::F64(v) => v.fmt(f),
            Number::Int(v) => v.fmt(f),
        }
    }
}

impl From<f32> for Number {
    fn from(v: f32) -> Number {
        Number::F32(v)
    }
}

impl From<f64> for Number {
    fn from(v: f64) -> Number {
        Number::F64(v)
    }
}

impl From<u32> for Number {
    fn from(v: u32) -> Number {
        Number::Int(u64::from(v))
    }
}

impl From<usize> for Number {
    fn from(v: usize) -> Number {
        Number::Int(v as u64)
    }
}

/// What is wrong with a scene's value (its key path aside): the value, and the limit it breaks
/// where the limit is not a constant of the check.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BadValue {
    /// A component is infinite or NaN.
    #[error("{0} is not a finite number")]
    NotFinite(f32),
    /// A coordinate's magnitude is above [`MAX_SCENE_COORDINATE`].
    #[error("{0} is beyond the limit of {MAX_SCENE_COORDINATE:e} scene units")]
    BeyondCoordinateLimit(f32),
    /// A direction (or up vector) of length zero.
    #[error("must not be the zero vector")]
    ZeroVector,
    /// A component below zero where none may be.
    #[error("{0} is negative")]
    Negative(f32),
    /// Zero, negative or not finite where a positive number is needed.
    #[error("{0} must be positive")]
    NotPositive(Number),
    /// Outside `min` to `max`, both allowed.
    #[error("{value} must be {min} to {max}")]
    OutOfRange {
        /// The value given.
        value: Number,
        /// The least allowed.
        min: Number,
        /// The most allowed.
        max: Number,
    },
    /// A fraction (roughness) outside 0 to 1.
    #[error("{0} must be between 0 and 1")]
    NotAFraction(f32),
    /// A spot light's cone angle, in degrees, not strictly between 0 and 90.
    #[error("{0} must be between 0 and 90 degrees")]
    SpotAngle(f32),
    /// A spot light's softness not above 0 and at most 1.
    #[error("{0} must be above 0 and at most 1")]
    Softness(f32),
    /// A vertical field of view, in degrees, under [`MIN_FOV_Y`] or from 180 up.
    #[error("{0} must be at least {MIN_FOV_Y} and below 180 degrees")]
    FieldOfView(f32),
    /// A relative error target outside [`format::MIN_MAX_ERROR`] to [`format::MAX_MAX_ERROR`].
    #[error("{0} must be {min} to {max} (a relative error: 0.01 is 1%)", min = format::MIN_MAX_ERROR, max = format::MAX_MAX_ERROR)]
    RelativeError(f64),
    /// An image size with a side of 0 or above 16384 pixels.
    #[error("{0:?} must be 1 to 16384 pixels each")]
    Resolution([u32; 2]),
    /// `camera.target` is `camera.eye`.
    #[error("equals camera.eye")]
    TargetAtEye,
    /// The eye's distance from the target (this) outside [`MIN_CAMERA_DISTANCE`] to
    /// [`MAX_SCENE_COORDINATE`].
    #[error(
        "is {0:e} from camera.eye; the distance must be {MIN_CAMERA_DISTANCE:e} to {MAX_SCENE_COORDINATE:e} scene units"
    )]
    CameraDistance(f64),
    /// `camera.up` (this) along the view direction.
    #[error("{0:?} is parallel to the view direction")]
    ParallelToView([f32; 3]),
    /// No `[[object]]` at all.
    #[error("the scene has no [[object]]")]
    NoObjects,
    /// A mesh path of nothing but white space.
    #[error("is empty")]
    EmptyPath,
    /// A `node` given for a mesh that is not a glTF file.
    #[error("names a glTF node, and the mesh is not a .gltf or .glb file")]
    NodeOutsideGltf,
    /// A built-in shape's size or radius zero, negative or not finite.
    #[error("size/radius {0} must be positive")]
    SizeNotPositive(f32),
    /// A built-in shape's size or radius above [`crate::mesh::MAX_COORDINATE`].
    #[error("size/radius {0:e} is above {max:e}", max = crate::mesh::MAX_COORDINATE)]
    SizeTooLarge(f32),
    /// A translucent material with neither a preset nor both coefficients.
    #[error("needs `preset` or both `sigma_a` and `sigma_s_prime`")]
    NoCoefficients,
    /// A translucent material with a preset and coefficients.
    #[error("give `preset` or coefficients, not both")]
    PresetAndCoefficients,
    /// An opaque albedo (this) with a channel above 1: it would reflect more than it receives.
    #[error("{0:?} must be at most 1 (energy)")]
    AlbedoAboveOne([f32; 3]),
    /// More than one environment light.
    #[error("at most one environment light")]
    SeveralEnvironments,
    /// A light whose values are finite but not once prepared (an environment's scale times the
    /// irradiance of one of its directions overflows): the light as prepared.
    #[error("the light is not finite once prepared ({0:?}); lower it")]
    LightNotFinite(LightKind),
    /// An object that, placed by its shape and transform, reaches further than
    /// [`MAX_SCENE_COORDINATE`] from the origin.
    #[error(
        "placed by its shape and transform it reaches {reach:e} scene units from the origin, beyond the limit \
         of {MAX_SCENE_COORDINATE:e}"
    )]
    BeyondReach {
        /// The object's name (its mesh file or shape).
        object: String,
        /// How far it reaches on its farthest axis, in scene units.
        reach: f32,
    },
}

/// A value refused, with the key path (or command-line flag) that gives it.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{key} {value}")]
pub struct CheckError {
    /// The key path (`camera.fov_y`, `object[0].material.roughness`) or flag (`--max-error`).
    pub key: String,
    /// What is wrong with its value.
    pub value: BadValue,
}

/// A check's verdict: the first value refused, if any.
pub type Check = Result<(), CheckError>;

/// Refuse `key`'s value for `value`.
fn refuse(key: impl Into<String>, value: BadValue) -> Check {
    Err(CheckError { key: key.into(), value })
}

/// Finite, and within [`MAX_SCENE_COORDINATE`] of the origin on every axis.
fn coordinates(key: &str, values: &[f32]) -> Check {
    finite(key, values)?;
    match values.iter().find(|v| v.abs() > MAX_SCENE_COORDINATE) {
        Some(v) => refuse(key, BadValue::BeyondCoordinateLimit(*v)),
        None => Ok(()),
    }
}

fn finite(key: &str, values: &[f32]) -> Check {
    match values.iter().find(|v| !v.is_finite()) {
        Some(v) => refuse(key, BadValue::NotFinite(*v)),
        None => Ok(()),
    }
}

fn nonzero(key: &str, v: [f32; 3]) -> Check {
    finite(key, &v)?;
    if v.iter().all(|c| *c == 0.0) { refuse(key, BadValue::ZeroVector) } else { Ok(()) }
}

fn non_negative(key: &str, values: &[f32]) -> Check {
    finite(key, values)?;
    match values.iter().find(|v| **v < 0.0) {
        Some(v) => refuse(key, BadValue::Negative(*v)),
        None => Ok(()),
    }
}

fn unit_interval(key: &str, v: f32) -> Check {
    if (0.0..=1.0).contains(&v) { Ok(()) } else { refuse(key, BadValue::NotAFraction(v)) }
}

/// `value` positive and finite.
fn positive(key: &str, value: impl Into<Number>) -> Check {
    let value = value.into();
    let positive = match value {
        Number::F32(v) => v.is_finite() && v > 0.0,
        Number::F64(v) => v.is_finite() && v > 0.0,
        Number::Int(v) => v > 0,
    };
    if positive { Ok(()) } else { refuse(key, BadValue::NotPositive(value)) }
}

/// `value` within `min` to `max`, both allowed (a NaN is not).
fn within<T: Into<Number> + PartialOrd + Copy>(key: &str, value: T, min: T, max: T) -> Check {
    if value >= min && value <= max {
        return Ok(());
    }
    refuse(key, BadValue::OutOfRange { value: value.into(), min: min.into(), max: max.into() })
}

/// Every value of a parsed scene in range, section by section; the first that is not, as its
/// key path and what is wrong.
pub(super) fn check(scene: &SceneFile) -> Check {
    check_camera(&scene.camera)?;
    if scene.objects.is_empty() {
        return refuse("object", BadValue::NoObjects);
    }
    for (i, o) in scene.objects.iter().enumerate() {
        let key = |k: &str| format!("object[{i}].{k}");
        check_shape(&key, &o.shape)?;
        check_transform(&key, &o.transform)?;
        check_material(&key, &o.material)?;
    }
    check_lights(&scene.lights)?;
    if let Some(count) = scene.sampling.count {
        within("sampling.count", count, 1, MAX_SAMPLE_COUNT)?;
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
        return refuse("camera.target", BadValue::TargetAtEye);
    }
    // In f64: the f32 difference of two allowed points can still overflow when squared.
    let view = glam::Vec3::from(c.target).as_dvec3() - glam::Vec3::from(c.eye).as_dvec3();
    let distance = view.length();
    if !(MIN_CAMERA_DISTANCE as f64..=MAX_SCENE_COORDINATE as f64).contains(&distance) {
        return refuse("camera.target", BadValue::CameraDistance(distance));
    }
    if view.normalize().cross(glam::Vec3::from(c.up).as_dvec3().normalize()).length() < 1e-4 {
        return refuse("camera.up", BadValue::ParallelToView(c.up));
    }
    if !(c.fov_y >= MIN_FOV_Y && c.fov_y < 180.0) {
        return refuse("camera.fov_y", BadValue::FieldOfView(c.fov_y));
    }
    if c.resolution.iter().any(|r| *r == 0 || *r > 16384) {
        return refuse("camera.resolution", BadValue::Resolution(c.resolution));
    }
    Ok(())
}

/// An object's `shape`, `key` making its key paths: a mesh path that names something, a
/// built-in shape's size positive and within [`crate::mesh::MAX_COORDINATE`], 1 to 2048
/// divisions.
fn check_shape(key: &impl Fn(&str) -> String, shape: &Shape) -> Check {
    match shape {
        Shape::Mesh { path, .. } if path.trim().is_empty() => refuse(key("shape.path"), BadValue::EmptyPath),
        Shape::Mesh { path, node: Some(_), .. } if !crate::mesh::is_gltf(std::path::Path::new(path)) => {
            refuse(key("shape.node"), BadValue::NodeOutsideGltf)
        }
        Shape::Plane { size, divisions } | Shape::Sphere { radius: size, divisions } => {
            if !(size.is_finite() && *size > 0.0) {
                return refuse(key("shape"), BadValue::SizeNotPositive(*size));
            }
            if *size > crate::mesh::MAX_COORDINATE {
                return refuse(key("shape"), BadValue::SizeTooLarge(*size));
            }
            within(&key("shape.divisions"), *divisions, 1, 2048)
        }
        _ => Ok(()),
    }
}

/// An object's `transform`: fit and scale positive, rotation finite, translation a coordinate.
fn check_transform(key: &impl Fn(&str) -> String, t: &Transform) -> Check {
    for (name, v) in [("transform.fit", t.fit), ("transform.scale", t.scale)] {
        if let Some(v) = v {
            positive(&key(name), v)?;
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
                return refuse(key("material"), BadValue::NoCoefficients);
            }
            if preset.is_some() && (sigma_a.is_some() || sigma_s_prime.is_some()) {
                return refuse(key("material"), BadValue::PresetAndCoefficients);
            }
            positive(&key("material.mm_per_unit"), *mm_per_unit)?;
            unit_interval(&key("material.roughness"), *roughness)
        }
        MaterialSpec::Opaque { albedo, roughness } => {
            non_negative(&key("material.albedo"), albedo)?;
            if albedo.iter().any(|a| *a > 1.0) {
                return refuse(key("material.albedo"), BadValue::AlbedoAboveOne(*albedo));
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
                    return refuse(key("angle"), BadValue::SpotAngle(*angle));
                }
                if !(*softness > 0.0 && *softness <= 1.0) {
                    return refuse(key("softness"), BadValue::Softness(*softness));
                }
            }
            Light::Environment { scale, directions, .. } => {
                environments += 1;
                non_negative(&key("scale"), &[*scale])?;
                within(&key("directions"), *directions, 1, 256)?;
            }
        }
    }
    if environments > 1 {
        return refuse("light", BadValue::SeveralEnvironments);
    }
    Ok(())
}

/// `[render]`: exposure positive, gather epsilon 0 to [`format::MAX_GATHER_EPSILON`], beam
/// opening 0 to [`format::MAX_BEAM_OPENING`], beam walks' memory at most
/// [`format::MAX_BEAM_WALK_MIB`], a shadow-map size of 16 to 8192 texels, a background that
/// emits nothing negative.
fn check_render(r: &RenderSettings) -> Check {
    positive("render.exposure", r.exposure)?;
    within("render.gather_epsilon", r.gather_epsilon, 0.0, format::MAX_GATHER_EPSILON)?;
    within("render.beam_opening", r.beam_opening, 0.0, format::MAX_BEAM_OPENING)?;
    within("render.beam_walk_mib", r.beam_walk_mib, 0, format::MAX_BEAM_WALK_MIB)?;
    within("render.shadow_map_size", r.shadow_map_size, 16, 8192)?;
    non_negative("render.background", &r.background.unwrap_or_default())?;
    check_texture("render.texture_samples", "render.texture_resolution", r.texture_samples, r.texture_resolution)
        .map_err(|e| CheckError {
            key: e.key.into(),
            value: BadValue::OutOfRange { value: e.value.into(), min: e.min.into(), max: e.max.into() },
        })?;
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
        return refuse(key, BadValue::RelativeError(e));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_show_as_their_own_type() {
        assert_eq!(Number::from(0.1f32).to_string(), "0.1");
        assert_eq!(Number::from(0.1f64).to_string(), "0.1");
        assert_eq!(Number::from(7usize).to_string(), "7");
        assert_eq!(Number::from(f32::NAN).to_string(), "NaN");
    }

    #[test]
    fn a_refused_flag_reads_as_flag_then_value() {
        let e = check_max_error("--max-error", 0.7).unwrap_err();
        assert_eq!(e.value, BadValue::RelativeError(0.7));
        assert_eq!(e.to_string(), "--max-error 0.7 must be 0.001 to 0.5 (a relative error: 0.01 is 1%)");
        assert!(check_max_error("--max-error", 0.01).is_ok());
    }

    #[test]
    fn range_checks_keep_the_limits() {
        let e = within("sampling.count", 0usize, 1, MAX_SAMPLE_COUNT).unwrap_err();
        assert_eq!(
            e.value,
            BadValue::OutOfRange { value: Number::Int(0), min: Number::Int(1), max: Number::Int(1_000_000) }
        );
        assert_eq!(e.value.to_string(), "0 must be 1 to 1000000");
        let e = within("render.gather_epsilon", f32::NAN, 0.0, 10.0).unwrap_err();
        assert_eq!(e.value.to_string(), "NaN must be 0 to 10");
        let e = positive("render.exposure", 0.0f32).unwrap_err();
        assert_eq!(e.value, BadValue::NotPositive(Number::F32(0.0)));
    }
}
