//! The scene file format (TOML). Every table rejects unknown keys, so a typo is an error that
//! names the key path and line instead of a silently ignored setting.
//!
//! Units: positions in scene units; a translucent material says how many millimetres one scene
//! unit is (`mm_per_unit`), because its coefficients are per millimetre.

use crate::sampling::Method;
use serde::Deserialize;

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub camera: Camera,
    #[serde(default, rename = "object")]
    pub objects: Vec<Object>,
    #[serde(default, rename = "light")]
    pub lights: Vec<Light>,
    #[serde(default)]
    pub sampling: Sampling,
    #[serde(default)]
    pub render: RenderSettings,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub eye: [f32; 3],
    pub target: [f32; 3],
    #[serde(default = "up")]
    pub up: [f32; 3],
    /// Vertical field of view in degrees.
    #[serde(default = "fov")]
    pub fov_y: f32,
    #[serde(default = "resolution")]
    pub resolution: [u32; 2],
}

fn up() -> [f32; 3] {
    [0.0, 1.0, 0.0]
}
fn fov() -> f32 {
    35.0
}
fn resolution() -> [u32; 2] {
    [512, 512]
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    /// What to draw: a mesh file or a built-in shape.
    pub shape: Shape,
    #[serde(default)]
    pub transform: Transform,
    pub material: MaterialSpec,
    /// Whether the object casts shadows (default true).
    #[serde(default = "yes")]
    pub casts_shadow: bool,
}

fn yes() -> bool {
    true
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum Shape {
    /// An OBJ file; `path` is relative to the scene file (the built-in scene resolves it among
    /// the embedded assets).
    Mesh { path: String },
    /// A square in the xz plane, centred at the origin, facing +y, `size` units wide,
    /// split into `divisions`^2 quads.
    Plane {
        size: f32,
        #[serde(default = "divisions")]
        divisions: u32,
    },
    /// A UV sphere of `radius` at the origin.
    Sphere {
        radius: f32,
        #[serde(default = "divisions")]
        divisions: u32,
    },
}

fn divisions() -> u32 {
    64
}

/// Applied in the order: fit, scale, rotate (degrees about x, then y, then z), translate.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    /// Scale the mesh uniformly so its largest bounding-box side is this long, and centre it on
    /// the origin with its lowest point at y = 0.
    pub fit: Option<f32>,
    pub scale: Option<f32>,
    pub rotate: Option<[f32; 3]>,
    pub translate: Option<[f32; 3]>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum MaterialSpec {
    /// A dipole-diffusion material: a measured preset or custom coefficients (per mm).
    Translucent {
        preset: Option<String>,
        sigma_a: Option<[f64; 3]>,
        sigma_s_prime: Option<[f64; 3]>,
        eta: Option<f64>,
        /// Millimetres per scene unit.
        mm_per_unit: f64,
        /// GGX roughness of the dielectric specular lobe.
        #[serde(default = "roughness")]
        roughness: f32,
    },
    /// Lambertian with a GGX specular lobe.
    Opaque {
        albedo: [f32; 3],
        #[serde(default = "roughness")]
        roughness: f32,
    },
}

fn roughness() -> f32 {
    0.35
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum Light {
    /// Light arriving from one direction: `direction` points from the scene towards the light;
    /// `irradiance` in W/m^2 per channel on a surface facing it.
    Directional {
        direction: [f32; 3],
        irradiance: [f32; 3],
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// `intensity` in W/sr per channel.
    Point {
        position: [f32; 3],
        intensity: [f32; 3],
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// A point light restricted to a cone of half-angle `angle` (degrees) about `direction`,
    /// with a smooth falloff over the outer `softness` fraction.
    Spot {
        position: [f32; 3],
        direction: [f32; 3],
        intensity: [f32; 3],
        angle: f32,
        #[serde(default = "softness")]
        softness: f32,
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// Light from every direction: an equirectangular map (.hdr or .exr, relative to the scene
    /// file) or the built-in procedural sky, reduced to `directions` importance-sampled
    /// directional lights, each with its own shadow map (soft shadows, seed Figure 6).
    Environment {
        map: Option<String>,
        #[serde(default = "one")]
        scale: f32,
        #[serde(default = "env_directions")]
        directions: u32,
        #[serde(default = "yes")]
        shadows: bool,
    },
}

fn softness() -> f32 {
    0.2
}
fn one() -> f32 {
    1.0
}
fn env_directions() -> u32 {
    16
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sampling {
    #[serde(default = "method")]
    pub method: Method,
    #[serde(default = "count")]
    pub count: usize,
    #[serde(default = "seed")]
    pub seed: u64,
}

impl Default for Sampling {
    fn default() -> Self {
        Self { method: method(), count: count(), seed: seed() }
    }
}

fn method() -> Method {
    Method::Turk
}
fn count() -> usize {
    400
}
fn seed() -> u64 {
    1
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSettings {
    /// Where exitance is gathered.
    #[serde(default)]
    pub gather: GatherMode,
    /// Exposure multiplier applied before the tone map.
    #[serde(default = "one")]
    pub exposure: f32,
    /// Shadow-map resolution per light.
    #[serde(default = "shadow_size")]
    pub shadow_map_size: u32,
    /// Linear background radiance where nothing is hit (the sky is drawn when it is a light).
    pub background: Option<[f32; 3]>,
}

/// Where exitance is gathered: `render.gather` in a scene, `--gather` on the command line.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum GatherMode {
    /// At every mesh vertex, interpolated when shading
    #[default]
    Vertex,
    /// At every visible pixel
    Pixel,
    /// At the sample points, blended to the vertices: fastest, smooths detail finer than the
    /// sample spacing
    Sparse,
}

impl GatherMode {
    pub const ALL: [GatherMode; 3] = [GatherMode::Vertex, GatherMode::Pixel, GatherMode::Sparse];

    pub fn name(self) -> &'static str {
        match self {
            GatherMode::Vertex => "vertex",
            GatherMode::Pixel => "pixel",
            GatherMode::Sparse => "sparse",
        }
    }
}

impl std::str::FromStr for GatherMode {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        GatherMode::ALL
            .into_iter()
            .find(|m| m.name().eq_ignore_ascii_case(s))
            .ok_or_else(|| format!("unknown gather mode `{s}` (expected vertex, pixel or sparse)"))
    }
}

impl std::fmt::Display for GatherMode {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self { gather: GatherMode::default(), exposure: 1.0, shadow_map_size: shadow_size(), background: None }
    }
}

fn shadow_size() -> u32 {
    1024
}
