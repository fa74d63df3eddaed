//! What a prepared scene contains that decides which passes it needs, and its backdrop: facts
//! about the scene, read by the planner (`render::plan`) and the renderer.

use super::Light;
use super::build::PreparedScene;
use glam::Vec3;

/// What a scene contains that decides its passes.
#[derive(Clone, Debug)]
pub struct SceneNeeds {
    /// Layers of the shadow-map array (0: no shadow pass).
    pub shadow_layers: u32,
    /// Objects with sample points, i.e. translucent ones (0: no splat or gather passes).
    pub translucent_objects: usize,
    /// Scene lights that own at least one shadow-map layer.
    pub shadowed_lights: Vec<usize>,
    /// The scene's environment light, if any (cached per vertex by the vertex-light pass).
    pub environment: Option<usize>,
    /// Exitance gathered per pixel (after shading, every frame) instead of per vertex.
    pub pixel_gather: bool,
    /// Drawn into a host engine's images, which the host tone-maps (set by the renderer).
    pub host_target: bool,
    /// `render.transport`: the planner chooses, or every channel is forced one way.
    pub transport: super::TransportMode,
    /// `render.splat_visibility`: how the splat finds whether a light reaches a sample.
    pub splat_visibility: super::SplatVisibility,
    /// `render.gather`: only the hierarchical gather recomputes some receivers and keeps the rest.
    pub gather: super::GatherMode,
    /// `render.receivers`: which receivers the hierarchical gather recomputes after a change.
    pub receivers: super::ReceiverPolicy,
    /// Per object, in scene order: what the planner weighs for it.
    pub objects: Vec<ObjectFacts>,
    /// Scene units a shadow-map texel spans (`PreparedScene::shadow_texel`).
    pub shadow_texel: f64,
    /// Centre of the casters' bounding sphere.
    pub caster_center: [f32; 3],
}

/// What the planner weighs for one object: where it is, how finely it is sampled and meshed, and
/// per channel how far light spreads under its surface. Lengths in scene units.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ObjectFacts {
    /// The mesh path or built-in shape.
    pub name: String,
    /// Per channel, its reduced albedo `alpha'` where `material.model` gives it single
    /// scattering between points (`ScatteringModel::single_channels`); `None` for the dipole.
    pub single: [Option<f64>; 3],
    /// Where `material.model = "transport"`: whether its kernel is attached.
    pub transport: Option<KernelState>,
    /// Centre of its bounding sphere.
    pub center: [f32; 3],
    /// Radius of its bounding sphere.
    pub radius: f32,
    /// Mean distance between sample points, `sqrt(area / samples)` (0 without samples).
    pub sample_spacing: f64,
    /// Mean edge length of its mesh.
    pub vertex_spacing: f64,
    /// Per channel (R, G, B) of a translucent object; `None` for an opaque one.
    pub channels: Option<[ChannelFacts; 3]>,
    /// Its levels of detail, finest (the mesh itself) first (`PreparedObject::levels`).
    pub levels: Vec<LevelFacts>,
    /// How its sample count was chosen and the per-vertex error predicted for it
    /// (`scene::accuracy`); `None` for an opaque object.
    pub density: Option<super::accuracy::Density>,
    /// Which model each channel takes, why, and the error predicted against the light
    /// (`scene::model_choice`); `None` for an opaque object.
    pub model: Option<super::model_choice::ModelChoice>,
}

/// Where an object's material asks for the transport kernel (`optics::transport`), what it
/// gets.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(tag = "state", rename_all = "snake_case")]
pub enum KernelState {
    /// Its kernel is attached: glsl/transport.comp scales the dipole's exitance after the
    /// gather.
    Scales {
        /// Patches of its surface.
        patches: usize,
        /// Walks per patch and channel.
        walks: u64,
    },
    /// None is attached (not yet walked, or the caller attached none): the dipole alone.
    NotAttached,
    /// Its kernel was dropped: the dipole alone until one is attached again.
    Dropped {
        /// Why.
        why: super::build::KernelDropped,
    },
}

impl std::fmt::Display for KernelState {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            KernelState::Scales { patches, walks } => write!(
                f,
                "transport kernel ({patches} patches, {walks} walks each) scales the dipole's exitance after the \
                 gather to the transport through this mesh"
            ),
            KernelState::NotAttached => {
                write!(f, "the transport kernel is chosen but none is attached: the dipole alone")
            }
            KernelState::Dropped { why } => {
                write!(f, "transport kernel dropped: {why}; the dipole alone until one is attached")
            }
        }
    }
}

/// One level of detail as the planner weighs it (`mesh::LodLevel`). Lengths in scene units.
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct LevelFacts {
    /// Triangles drawn.
    pub triangles: usize,
    /// Vertices its triangles use: the gather's receivers at this level.
    pub vertices: usize,
    /// Mean edge length.
    pub mean_edge: f64,
    /// Bound on its distance from the full mesh.
    pub error: f64,
    /// Simplified around the vertices where its per-vertex values vary (`LodLevel::locked`):
    /// judged by its distance from the full mesh alone.
    pub locked: bool,
}

/// One colour channel of a translucent material at the scene's scale (`optics::Dipole`).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct ChannelFacts {
    /// `1 / sigma_tr`: how far light travels before it is absorbed (infinite without
    /// absorption).
    pub diffusion_length: f64,
    /// Height of the virtual source `z_v`.
    pub z_v: f64,
    /// RMS radius of `R_d` (`Dipole::profile_radius`): the width of the blur transport gives.
    pub profile_radius: f64,
    /// `R_d,total`, the local answer's factor.
    pub r_d_total: f64,
}

impl ObjectFacts {
    fn of(object: &super::build::PreparedObject) -> ObjectFacts {
        let mesh = &object.mesh;
        let (lo, hi) = mesh.bounds();
        let center = (lo + hi) * 0.5;
        let radius = mesh.positions().iter().map(|p| p.distance(center)).fold(0.0f32, f32::max);
        let samples = object.samples.len();
        let channels = match &object.material {
            super::build::ResolvedMaterial::Translucent { dipoles, .. } => Some(dipoles.map(|d| ChannelFacts {
                diffusion_length: d.diffusion_length(),
                z_v: d.z_v,
                profile_radius: d.profile_radius(),
                r_d_total: d.r_d_total(),
            })),
            super::build::ResolvedMaterial::Opaque { .. } => None,
        };
        let alpha = match &object.material {
            super::build::ResolvedMaterial::Translucent { dipoles, .. } => dipoles.map(|d| d.alpha_prime),
            super::build::ResolvedMaterial::Opaque { .. } => [0.0; 3],
        };
        let chosen = object.single_channels();
        let transport = object.wants_transport().then(|| match (&object.transport, object.kernel_dropped) {
            (Some(k), _) => KernelState::Scales { patches: k.patches.len(), walks: k.walks },
            (None, Some(why)) => KernelState::Dropped { why },
            (None, None) => KernelState::NotAttached,
        });
        ObjectFacts {
            single: [0, 1, 2].map(|c| chosen[c].then_some(alpha[c])),
            transport,
            name: object.name.clone(),
            center: center.to_array(),
            radius,
            sample_spacing: if samples > 0 { (mesh.total_area() / samples as f64).sqrt() } else { 0.0 },
            // Level 0 is the whole mesh.
            vertex_spacing: object.levels[0].mean_edge,
            channels,
            levels: object
                .levels
                .iter()
                .map(|l| LevelFacts {
                    triangles: l.triangles.len(),
                    vertices: l.vertices.len(),
                    mean_edge: l.mean_edge,
                    error: l.error,
                    locked: l.locked,
                })
                .collect(),
            density: object.density.clone(),
            model: object.model.clone(),
        }
    }
}

impl PreparedScene {
    /// The passes' view of this scene (see `render::plan`).
    pub fn needs(&self) -> SceneNeeds {
        let mut shadowed_lights: Vec<usize> =
            self.lights.iter().filter(|l| l.shadow_layer.is_some()).map(|l| l.source).collect();
        shadowed_lights.dedup();
        SceneNeeds {
            shadow_layers: self.shadow_layers,
            translucent_objects: self.objects.iter().filter(|o| !o.samples.is_empty()).count(),
            shadowed_lights,
            environment: self.lights.iter().find(|l| l.environment).map(|l| l.source),
            pixel_gather: self.scene.file.render.gather == super::GatherMode::Pixel,
            host_target: false,
            transport: self.scene.file.render.transport,
            splat_visibility: self.scene.file.render.splat_visibility,
            gather: self.scene.file.render.gather,
            receivers: self.scene.file.render.receivers,
            objects: self.objects.iter().map(ObjectFacts::of).collect(),
            shadow_texel: self.shadow_texel(),
            caster_center: self.caster_bounds.0.to_array(),
        }
    }

    /// The colour behind everything: `render.background`, else the environment's radiance at
    /// the horizon (scaled as the light is), else black.
    pub fn background(&self) -> [f32; 3] {
        if let Some(colour) = self.scene.file.render.background {
            return colour;
        }
        let Some(env) = &self.environment else {
            return [0.0; 3];
        };
        let scale = self
            .scene
            .file
            .lights
            .iter()
            .find_map(|l| match l {
                Light::Environment { scale, .. } => Some(*scale),
                _ => None,
            })
            .unwrap_or(1.0);
        let row = env.height / 2 - 1;
        let sum: Vec3 = env.radiance[row * env.width..(row + 1) * env.width].iter().sum();
        (sum / env.width as f32 * scale).to_array()
    }

    /// The shadow-map layers of scene light `source` (several for an environment).
    pub fn shadow_layers_of(&self, source: usize) -> Vec<u32> {
        self.lights.iter().filter(|l| l.source == source).filter_map(|l| l.shadow_layer).collect()
    }
}
