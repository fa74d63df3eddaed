//! The scene file format (TOML). Every table rejects unknown keys, so a typo is an error that
//! names the key path and line instead of a silently ignored setting.
//!
//! Units: positions in scene units; a translucent material says how many millimetres one scene
//! unit is (`mm_per_unit`), because its coefficients are per millimetre.

use crate::sampling::Method;
use serde::Deserialize;

/// A whole scene file as deserialized: one `[camera]`, the `[[object]]` and `[[light]]` arrays,
/// and the optional `[sampling]` and `[render]` tables. [`crate::scene::Scene::parse`] checks
/// the values after this parse.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[camera]`: where the image is taken from (required).
    pub camera: Camera,
    /// `[[object]]`: the objects drawn, in file order; at least one.
    #[serde(default, rename = "object")]
    pub objects: Vec<Object>,
    /// `[[light]]`: the lights, in file order; none by default, at most one environment light.
    #[serde(default, rename = "light")]
    pub lights: Vec<Light>,
    /// `[sampling]`: how sample points are placed on translucent objects.
    #[serde(default)]
    pub sampling: Sampling,
    /// `[render]`: gather mode, exposure, shadow maps and background.
    #[serde(default)]
    pub render: RenderSettings,
}

/// The `[camera]` table: a pinhole camera looking from `eye` at `target`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Position of the camera (scene units; required, finite, not equal to `target` and at most
    /// [`crate::mesh::MAX_COORDINATE`] units from it).
    #[serde(deserialize_with = "exact_len")]
    pub eye: [f32; 3],
    /// The point looked at, at the centre of the image (scene units; required, finite).
    #[serde(deserialize_with = "exact_len")]
    pub target: [f32; 3],
    /// Which way is up in the image (any length; default `[0, 1, 0]`; finite, non-zero and not
    /// parallel to the view direction).
    #[serde(default = "up", deserialize_with = "exact_len")]
    pub up: [f32; 3],
    /// Vertical field of view in degrees (default 35; strictly between 0 and 180).
    #[serde(default = "fov")]
    pub fov_y: f32,
    /// Image size `[width, height]` in pixels (default `[512, 512]`; each 1 to 16384).
    #[serde(default = "resolution", deserialize_with = "exact_len")]
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

/// One `[[object]]`: a shape, where it goes, and what it is made of.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    /// What to draw: a mesh file or a built-in shape.
    pub shape: Shape,
    /// Placement in the world (default: none, the shape as given).
    #[serde(default)]
    pub transform: Transform,
    /// Translucent or opaque, and its parameters (required).
    pub material: MaterialSpec,
    /// Whether the object casts shadows (default true).
    #[serde(default = "yes")]
    pub casts_shadow: bool,
}

fn yes() -> bool {
    true
}

/// The `shape` of an object, chosen by its `type` key: `"mesh"`, `"plane"` or `"sphere"`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum Shape {
    /// An OBJ file, or a glTF 2.0 file (`.gltf` with its buffer files, or `.glb`: every
    /// triangle primitive of its scene, placed by its nodes); `path` is relative to the scene
    /// file (the built-in scene resolves it among the embedded assets).
    Mesh {
        /// Path of the OBJ or glTF file (required, not empty).
        path: String,
        /// glTF only: the name of the node whose mesh (and its children's) this object is,
        /// placed as the file's scene places it (default: every node of the scene, as one
        /// mesh). Several objects can each take one node of the same file, each with its own
        /// material.
        #[serde(default)]
        node: Option<String>,
        /// glTF scenes only (no key in a scene file): one node's primitives of one material,
        /// its children left out; what `Scene::from_gltf` makes each object of.
        #[serde(skip)]
        part: Option<crate::mesh::GltfNodePart>,
    },
    /// A square in the xz plane, centred at the origin, facing +y, `size` units wide,
    /// split into `divisions`^2 quads.
    Plane {
        /// Side length in scene units (required; positive, at most [`crate::mesh::MAX_COORDINATE`]).
        size: f32,
        /// Quads along each side (default 64; 1 to 2048).
        #[serde(default = "divisions")]
        divisions: u32,
    },
    /// A UV sphere of `radius` at the origin.
    Sphere {
        /// Radius in scene units (required; positive, at most [`crate::mesh::MAX_COORDINATE`]).
        radius: f32,
        /// Rings of latitude, with twice as many segments of longitude (default 64; 1 to 2048,
        /// fewer than 3 are made 3).
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
    /// Scale the mesh uniformly so its largest bounding-box side is this long (scene units),
    /// and centre it on the origin with its lowest point at y = 0 (default none; positive).
    pub fit: Option<f32>,
    /// Uniform scale factor (default none; positive).
    pub scale: Option<f32>,
    /// Rotation in degrees about x, then y, then z (default none; finite).
    #[serde(default, deserialize_with = "exact_len_option")]
    pub rotate: Option<[f32; 3]>,
    /// Offset in scene units, applied last (default none; finite).
    #[serde(default, deserialize_with = "exact_len_option")]
    pub translate: Option<[f32; 3]>,
}

/// The `material` of an object, chosen by its `type` key: `"translucent"` or `"opaque"`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum MaterialSpec {
    /// A dipole-diffusion material: a measured preset or custom coefficients (per mm).
    Translucent {
        /// Name of a measured material (`translucent material --list`), matched ignoring case,
        /// spaces and punctuation. Give either this or both `sigma_a` and `sigma_s_prime`.
        preset: Option<String>,
        /// Absorption coefficient per channel (R, G, B) in 1/mm; finite and non-negative.
        #[serde(default, deserialize_with = "exact_len_option")]
        sigma_a: Option<[f64; 3]>,
        /// Reduced scattering coefficient `sigma_s'` per channel (R, G, B) in 1/mm; finite and
        /// non-negative, and not zero together with `sigma_a` in any channel.
        #[serde(default, deserialize_with = "exact_len_option")]
        sigma_s_prime: Option<[f64; 3]>,
        /// Relative index of refraction (default: the preset's, or 1.3 for custom coefficients;
        /// from 1/3 to 3, where the `F_dr` fits hold).
        eta: Option<f64>,
        /// Millimetres per scene unit (required; positive). In every channel `sigma_a +
        /// sigma_s_prime` times this must lie in [1e-12, 1e12] per scene unit.
        mm_per_unit: f64,
        /// GGX roughness of the dielectric specular lobe (default 0.35; 0 to 1).
        #[serde(default = "roughness")]
        roughness: f32,
        /// Which model each channel takes (default `"auto"`; `"dipole"`, `"single"`,
        /// `"transport"`).
        #[serde(default)]
        model: ScatteringModel,
    },
    /// Lambertian with a GGX specular lobe.
    Opaque {
        /// Diffuse albedo per channel (R, G, B) (required; each 0 to 1).
        #[serde(deserialize_with = "exact_len")]
        albedo: [f32; 3],
        /// GGX roughness of the specular lobe (default 0.35; 0 to 1).
        #[serde(default = "roughness")]
        roughness: f32,
    },
}

fn roughness() -> f32 {
    0.35
}

/// One `[[light]]`, chosen by its `type` key: `"directional"`, `"point"`, `"spot"` or
/// `"environment"`.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields, tag = "type", rename_all = "lowercase")]
pub enum Light {
    /// Light arriving from one direction: `direction` points from the scene towards the light;
    /// `irradiance` in W/m^2 per channel on a surface facing it.
    Directional {
        /// Towards the light, any length (required; finite, non-zero).
        #[serde(deserialize_with = "exact_len")]
        direction: [f32; 3],
        /// W/m^2 per channel (R, G, B) on a surface facing the light (required; non-negative).
        #[serde(deserialize_with = "exact_len")]
        irradiance: [f32; 3],
        /// Whether the light casts shadows (default true).
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// `intensity` in W/sr per channel.
    Point {
        /// Position in scene units (required; finite).
        #[serde(deserialize_with = "exact_len")]
        position: [f32; 3],
        /// W/sr per channel (R, G, B) (required; non-negative).
        #[serde(deserialize_with = "exact_len")]
        intensity: [f32; 3],
        /// Whether the light casts shadows (default true).
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// A point light restricted to a cone of half-angle `angle` (degrees) about `direction`,
    /// with a smooth falloff over the outer `softness` fraction.
    Spot {
        /// Position in scene units (required; finite).
        #[serde(deserialize_with = "exact_len")]
        position: [f32; 3],
        /// Axis of the cone, pointing away from the light, any length (required; finite,
        /// non-zero).
        #[serde(deserialize_with = "exact_len")]
        direction: [f32; 3],
        /// W/sr per channel (R, G, B) on the axis (required; non-negative).
        #[serde(deserialize_with = "exact_len")]
        intensity: [f32; 3],
        /// Half-angle of the cone in degrees (required; strictly between 0 and 90).
        angle: f32,
        /// Fraction of `angle`, at its outer edge, over which the light fades to zero
        /// (default 0.2; above 0, at most 1).
        #[serde(default = "softness")]
        softness: f32,
        /// Whether the light casts shadows (default true).
        #[serde(default = "yes")]
        shadows: bool,
    },
    /// Light from every direction: an equirectangular map (.hdr or .exr, relative to the scene
    /// file) or the built-in procedural sky, reduced to `directions` importance-sampled
    /// directional lights, each with its own shadow map (soft shadows, seed Figure 6).
    Environment {
        /// Path of the map (default none: the procedural sky). Not available to the built-in
        /// scene, which has no folder.
        map: Option<String>,
        /// Multiplier on the map's radiance (default 1; non-negative).
        #[serde(default = "one")]
        scale: f32,
        /// How many directional lights the map becomes (default 16; 1 to 256).
        #[serde(default = "env_directions")]
        directions: u32,
        /// Whether the directions cast shadows (default true).
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

/// The `[sampling]` table: how sample points are placed on every translucent object.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sampling {
    /// Placement: `"random"`, `"turk"`, `"feature"` or `"poisson"` (default `"turk"`).
    #[serde(default = "method")]
    pub method: Method,
    /// Sample points per translucent object (1 to [`crate::scene::MAX_SAMPLE_COUNT`]). Unset
    /// (the default), each object gets as many as `render.max_error` needs
    /// (`sampling::density`); set, it overrides the error target's count.
    #[serde(default)]
    pub count: Option<usize>,
    /// Random seed (default 1); object `i` uses `seed + i`, so the same scene gives the same
    /// points.
    #[serde(default = "seed")]
    pub seed: u64,
}

impl Default for Sampling {
    fn default() -> Self {
        Self { method: method(), count: None, seed: seed() }
    }
}

fn method() -> Method {
    Method::Turk
}
fn seed() -> u64 {
    1
}

/// The `[render]` table: how the image is made from the prepared scene.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RenderSettings {
    /// Where exitance is gathered, as the scene gives it (`None`: chosen with the sample count,
    /// [`RenderSettings::gather`]).
    #[serde(default, rename = "gather")]
    pub gather_given: Option<GatherMode>,
    /// Where exitance is gathered: `render.gather` when given, else `"vertex"` until the sample
    /// count is known, then `"hierarchical"` for an object of more than
    /// [`AUTO_HIERARCHICAL_COUNT`] samples (`PreparedScene::new`).
    #[serde(skip)]
    pub gather: GatherMode,
    /// The hierarchical gather's accuracy knob (default [`DEFAULT_GATHER_EPSILON`]; 0 to
    /// [`MAX_GATHER_EPSILON`]): a cluster of samples of area `A` whose nearest member is `r`
    /// away stands in for its members when `A < epsilon r^2`. 0 is the flat sum; other gather
    /// modes ignore it.
    #[serde(skip, default = "gather_epsilon")]
    pub gather_epsilon: f32,
    /// `render.gather_epsilon` as the scene gives it (`None`: [`DEFAULT_GATHER_EPSILON`], or
    /// [`ACCURATE_GATHER_EPSILON`] when the gather is chosen with the sample count).
    #[serde(default, rename = "gather_epsilon")]
    pub gather_epsilon_given: Option<f32>,
    /// The between-points single scattering's accuracy knob (`material.model`; default
    /// [`DEFAULT_BEAM_OPENING`]; 0 to [`MAX_BEAM_OPENING`]): a cluster of samples whose bounding
    /// radius is under `beam_opening` times its distance from the receiver stands in for its
    /// members (`render::beam_gather`). 0 is the sum over every sample within reach.
    #[serde(default = "beam_opening")]
    pub beam_opening: f32,
    /// Device memory, in MiB, the between-points single scattering may keep for each vertex's
    /// walk of the sample hierarchy, taken once when the scene is uploaded (default
    /// [`DEFAULT_BEAM_WALK_MIB`]); an object whose walks do not fit is walked every frame
    /// instead, the pass then taking about 2.5 times as long on the 2 cm ketchup sphere
    /// (`render::beam_gather`). 0 walks every frame; at most [`MAX_BEAM_WALK_MIB`].
    #[serde(default = "beam_walk_mib")]
    pub beam_walk_mib: u32,
    /// How each translucent object's channels get their exitance (default `"auto"`: the
    /// planner chooses per object and channel, `render::plan`).
    #[serde(default)]
    pub transport: TransportMode,
    /// Exposure multiplier applied before the tone map (default 1; positive).
    #[serde(default = "one")]
    pub exposure: f32,
    /// Shadow-map resolution per light, in texels per side (default 1024; 16 to 8192).
    #[serde(default = "shadow_size")]
    pub shadow_map_size: u32,
    /// Linear background radiance where nothing is hit, per channel (non-negative). Default:
    /// the environment light's radiance at the horizon, or black without one.
    #[serde(default, deserialize_with = "exact_len_option")]
    pub background: Option<[f32; 3]>,
    /// Draw, shadow and gather each mesh at a level of detail chosen per frame from its size
    /// on screen (default true; `mesh::Mesh::levels_of_detail`, `render::plan`). False keeps
    /// every mesh whole, and every vertex's exitance current (what per-vertex studies need).
    #[serde(default = "yes")]
    pub level_of_detail: bool,
    /// The relative per-vertex error of the exitance against the exact dipole integral that
    /// the sample density is chosen for (default [`DEFAULT_MAX_ERROR`], 1%; [`MIN_MAX_ERROR`] to
    /// [`MAX_MAX_ERROR`]): `sampling::density` predicts each object's error per channel and
    /// places as many samples as the worst channel needs. `sampling.count` or `--samples`
    /// overrides it.
    #[serde(default = "max_error")]
    pub max_error: f64,
    /// The texture gather's importance-sampled texels per receiver (default
    /// [`DEFAULT_TEXTURE_SAMPLES`]; 0 to [`MAX_TEXTURE_SAMPLES`]; 0 keeps the local term alone).
    #[serde(default = "texture_samples")]
    pub texture_samples: u32,
    /// The texture gather's atlas resolution, texels per side (default
    /// [`DEFAULT_TEXTURE_RESOLUTION`]; `mesh::atlas::MIN_RESOLUTION` to
    /// `mesh::atlas::MAX_RESOLUTION`).
    #[serde(default = "texture_resolution")]
    pub texture_resolution: u32,
    /// How the splat finds whether a light reaches a sample (default `"hybrid"`).
    #[serde(default)]
    pub splat_visibility: SplatVisibility,
    /// Which receivers the hierarchical gather recomputes after a change (default
    /// `"visible_first"`).
    #[serde(default)]
    pub receivers: ReceiverPolicy,
}

/// Which receivers the hierarchical gather recomputes after the lights or a material change:
/// `render.receivers`, `--receivers`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ReceiverPolicy {
    /// Those on a face the eye may see at once, the rest over the next
    /// `render::plan::SWEEP_FRAMES` frames without a change; a receiver coming into view
    /// stale is gathered the frame it does. Every image equals `every`'s
    #[default]
    VisibleFirst,
    /// Every receiver of the level drawn, each time
    Every,
}

named_choices!(ReceiverPolicy, "receivers", {
    VisibleFirst => "visible_first",
    Every => "every",
});

/// How the splat finds whether a light reaches a sample: `render.splat_visibility`,
/// `--splat-visibility`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SplatVisibility {
    /// The light's shadow map where it is sure, a ray where it is not: where the map's four
    /// texels around the sample disagree (a shadow edge), or where the sample's triangle may
    /// face away from the light while its interpolated normal faces it (a coarse mesh's
    /// terminator). As exact as rays but for occluders thinner than a texel, at a fraction of
    /// their cost
    #[default]
    Hybrid,
    /// A shadow ray against the casters' triangles for every light and sample: exact, as the
    /// truth's (docs/STUDY.md, "Visibility in the splat")
    Rays,
    /// One tap of the light's shadow map: off by up to a texel at shadow edges and beside a
    /// coarse mesh's terminator
    ShadowMaps,
}

impl SplatVisibility {
    /// What it does, for `plan` and `--explain`.
    pub fn why(self) -> &'static str {
        match self {
            SplatVisibility::Hybrid => {
                "a sample takes its shadow map's answer where the map's four texels agree and its triangle faces the \
                 light, a shadow ray into the casters' triangles elsewhere (render.splat_visibility)"
            }
            SplatVisibility::Rays => {
                "a shadow ray into the casters' triangles per light and sample (render.splat_visibility)"
            }
            SplatVisibility::ShadowMaps => {
                "one tap of each light's shadow map: off by up to a texel at shadow edges and beside a coarse mesh's \
                 terminator (render.splat_visibility)"
            }
        }
    }
}

named_choices!(SplatVisibility, "splat visibility", {
    Hybrid => "hybrid",
    Rays => "rays",
    ShadowMaps => "shadow_maps",
});

/// `render.texture_samples` when a scene names none (docs/STUDY.md, "The texture-space gather").
pub const DEFAULT_TEXTURE_SAMPLES: u32 = 64;
/// The most importance-sampled texels per receiver.
pub const MAX_TEXTURE_SAMPLES: u32 = 4096;
/// `render.texture_resolution` when a scene names none.
pub const DEFAULT_TEXTURE_RESOLUTION: u32 = 256;

fn texture_samples() -> u32 {
    DEFAULT_TEXTURE_SAMPLES
}
fn texture_resolution() -> u32 {
    DEFAULT_TEXTURE_RESOLUTION
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
    /// At every mesh vertex, far clusters of samples standing in for their members
    /// (`render.gather_epsilon`)
    Hierarchical,
    /// At every mesh vertex from a texture atlas of the surface: its texels' neighbourhood
    /// summed, the rest importance-sampled by transmitted power (after Chang et al. 2008;
    /// `render.texture_samples`, `render.texture_resolution`)
    Texture,
}

named_choices!(GatherMode, "gather mode", {
    Vertex => "vertex",
    Pixel => "pixel",
    Sparse => "sparse",
    Hierarchical => "hierarchical",
    Texture => "texture",
});

/// Which light-transport model a translucent material's channels take: `material.model`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ScatteringModel {
    /// The dipole in every channel (the paper's model, and the one the study's exact integral
    /// measures the sum against)
    Dipole,
    /// Per channel: single scattering between points where the reduced albedo is under 0.3
    /// (`optics::beam_single::ALBEDO_BELOW`), where it is closer to the radiative transfer than
    /// the dipole; elsewhere the transport kernel where the dipole's predicted error against the
    /// light is over `render.max_error` in a closed mesh (`scene::model_choice`), else the dipole
    #[default]
    Auto,
    /// Single scattering between points in every channel
    Single,
    /// Per channel: single scattering between points where the reduced albedo is under 0.3, as
    /// `auto`; elsewhere the dipole scaled per patch of the surface to the radiative transfer
    /// through this object's own mesh, by a transport kernel walked once per mesh and medium
    /// (`optics::transport`; the dipole until the kernel is attached)
    Transport,
}

named_choices!(ScatteringModel, "scattering model", {
    Dipole => "dipole",
    Auto => "auto",
    Single => "single",
    Transport => "transport",
});

impl ScatteringModel {
    /// Per channel, whether it takes single scattering between points rather than the dipole:
    /// `alpha'` is each channel's reduced albedo.
    pub fn single_channels(self, alpha_prime: [f64; 3]) -> [bool; 3] {
        match self {
            ScatteringModel::Dipole => [false; 3],
            ScatteringModel::Single => [true; 3],
            ScatteringModel::Auto | ScatteringModel::Transport => {
                alpha_prime.map(|a| a < crate::optics::beam_single::ALBEDO_BELOW)
            }
        }
    }
}

/// How translucent channels get their exitance: `render.transport`, `--transport`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum TransportMode {
    /// The planner chooses per object and channel, from the profile's width against what the
    /// samples, the mesh and the pixels can show (`render::plan`)
    #[default]
    Auto,
    /// Every channel gathered from the samples (the dipole sum)
    Gather,
    /// Every channel local: `M = R_d,total E_t` at the receiver, no splat or gather
    Local,
}

named_choices!(TransportMode, "transport", {
    Auto => "auto",
    Gather => "gather",
    Local => "local",
});

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            gather_given: None,
            gather: GatherMode::default(),
            gather_epsilon: gather_epsilon(),
            gather_epsilon_given: None,
            beam_opening: DEFAULT_BEAM_OPENING,
            beam_walk_mib: DEFAULT_BEAM_WALK_MIB,
            transport: TransportMode::default(),
            exposure: 1.0,
            shadow_map_size: shadow_size(),
            background: None,
            level_of_detail: true,
            max_error: DEFAULT_MAX_ERROR,
            texture_samples: DEFAULT_TEXTURE_SAMPLES,
            texture_resolution: DEFAULT_TEXTURE_RESOLUTION,
            splat_visibility: SplatVisibility::default(),
            receivers: ReceiverPolicy::default(),
        }
    }
}

/// `render.beam_opening` when a scene names none: on the 2 cm ketchup sphere the cut is within
/// 0.5% of the brightest vertex of the sum over every sample (docs/optics.md, "Single
/// scattering between points in the renderer").
pub const DEFAULT_BEAM_OPENING: f32 = 0.2;
/// The largest `render.beam_opening`: past it a cluster reaches over the kernel's own decay and
/// the cut is off by tens of percent.
pub const MAX_BEAM_OPENING: f32 = 0.5;
fn beam_opening() -> f32 {
    DEFAULT_BEAM_OPENING
}

/// `render.beam_walk_mib` when a scene names none: the bunny in ketchup (54,347 vertices,
/// 125,574 samples) keeps 34 MiB of walks.
pub const DEFAULT_BEAM_WALK_MIB: u32 = 64;
/// The largest `render.beam_walk_mib`: the walks' items are indexed by 32-bit offsets.
pub const MAX_BEAM_WALK_MIB: u32 = 4095;
fn beam_walk_mib() -> u32 {
    DEFAULT_BEAM_WALK_MIB
}

/// `render.gather_epsilon` when a scene names none. 4 until receiver groups shrank from 32 to 8
/// (a smaller group's sphere lies farther from more nodes, so the same epsilon clusters more),
/// then 2; since each receiver gets its own cut (the bound now holds at the receiver itself,
/// not at the nearest point of its group's sphere) 0.5: on the default scene at 400 samples
/// 0.16% RMS from the flat gather (2 gave 0.57%, 1 kept the RMS but moved skim milk's red on a
/// lit plane by 1.2e-3 from the flat sum; `tests/hierarchy.rs` holds 0.5% and 1e-3).
pub const DEFAULT_GATHER_EPSILON: f32 = 0.5;
/// `render.gather_epsilon` when the gather is chosen with the sample count, at the default
/// target: [`accurate_gather_epsilon`] of [`DEFAULT_MAX_ERROR`].
pub const ACCURATE_GATHER_EPSILON: f32 = 0.3;
/// [`accurate_gather_epsilon`]'s slope: epsilon per unit of `render.max_error`.
pub const ACCURATE_EPSILON_PER_ERROR: f64 = 30.0;

/// `render.gather_epsilon` when the gather is chosen with the sample count for the target
/// `max_error`: `30 max_error`, at most 2. The clusters' own error must stay a small part of the
/// target: with each receiver's own cut, 0.3 adds 0.01 to 0.03 points at a 1% target on the
/// built-in scene, but 0.1 to 0.3 points at 0.3% on the spheres (docs/STUDY.md, "What a
/// group's list costs, and a list per receiver").
pub fn accurate_gather_epsilon(max_error: f64) -> f32 {
    (ACCURATE_EPSILON_PER_ERROR * max_error).clamp(0.0, 2.0) as f32
}
/// Above this many samples on an object, a gather the scene does not name is the hierarchical
/// one: the flat sum's cost grows with samples times receivers.
pub const AUTO_HIERARCHICAL_COUNT: usize = 1600;
/// The largest `render.gather_epsilon`: a node seen under more than this solid angle is never
/// a good stand-in.
pub const MAX_GATHER_EPSILON: f32 = 10.0;

fn gather_epsilon() -> f32 {
    DEFAULT_GATHER_EPSILON
}

/// `render.max_error` when a scene names none: 1% per vertex against the exact integral.
pub const DEFAULT_MAX_ERROR: f64 = 0.01;
/// The smallest `render.max_error`: below it the model's fit has no data (docs/STUDY.md).
pub const MIN_MAX_ERROR: f64 = 0.001;
/// The largest `render.max_error`: 50% is already a different picture.
pub const MAX_MAX_ERROR: f64 = 0.5;

fn max_error() -> f64 {
    DEFAULT_MAX_ERROR
}

fn shadow_size() -> u32 {
    1024
}

/// A fixed-size array key read as a list of exactly `N` values: serde's own array reading
/// stops after `N` and ignores the rest, so `resolution = [32, 32, 32]` would read as 32x32.
/// The error ("invalid length 3, expected a list of 2 values") comes with the file, line and key.
fn exact_len<'de, D, T, const N: usize>(deserializer: D) -> Result<[T; N], D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let values = Vec::<T>::deserialize(deserializer)?;
    let len = values.len();
    values.try_into().map_err(|_| serde::de::Error::invalid_length(len, &format!("a list of {N} values").as_str()))
}

/// `exact_len` for an optional key (absent is `None`).
fn exact_len_option<'de, D, T, const N: usize>(deserializer: D) -> Result<Option<[T; N]>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    exact_len(deserializer).map(Some)
}
