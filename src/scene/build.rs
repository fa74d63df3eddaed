//! From a parsed scene to what the renderer uploads: meshes loaded, transformed to world space
//! and validated; materials resolved; sample points placed on each translucent mesh; lights
//! prepared with shadow layers. Everything here is CPU work done once per scene.

use super::lights::{self, Environment, PreparedLight};
use super::{AssetSource, Camera, GatherMode, Light, MaterialSpec, Scene, SceneError, Shape};
use crate::mesh::bvh::Bvh;
use crate::mesh::{LoadOptions, Mesh, MeshError};
use crate::optics::{Dipole, Material};
use crate::sampling::{self, Method, SampleOptions, SamplePoint};
use glam::{DVec3, EulerRot, Mat4, Quat, Vec3};

/// `.with_context(|| where)`: wrap an error in [`SceneError::Context`].
trait WithContext<T> {
    fn with_context(self, context: impl FnOnce() -> String) -> Result<T, SceneError>;
}

impl<T, E: Into<SceneError>> WithContext<T> for Result<T, E> {
    fn with_context(self, context: impl FnOnce() -> String) -> Result<T, SceneError> {
        self.map_err(|e| SceneError::Context { context: context(), source: Box::new(e.into()) })
    }
}

/// An object's material, resolved.
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)] // one per object, never in a hot loop
pub enum ResolvedMaterial {
    /// A dipole-diffusion material with its three channels' dipoles in scene units.
    Translucent {
        /// Coefficients in 1/mm (preset or custom, `eta` overridden where the scene gives one).
        material: Material,
        /// The R, G, B dipoles, in scene units (`material` scaled by `mm_per_unit`).
        dipoles: [Dipole; 3],
        /// Millimetres per scene unit.
        mm_per_unit: f64,
        /// GGX roughness of the dielectric specular lobe (0 to 1).
        roughness: f32,
        /// Which model each channel takes (`material.model`).
        model: super::ScatteringModel,
    },
    /// Lambertian with a GGX specular lobe.
    Opaque {
        /// Diffuse albedo per channel (0 to 1).
        albedo: [f32; 3],
        /// GGX roughness of the specular lobe (0 to 1).
        roughness: f32,
    },
}

/// One scene object ready to upload: world-space mesh, resolved material and sample points.
#[derive(Clone, Debug)]
pub struct PreparedObject {
    /// For messages: the mesh path or the built-in shape.
    pub name: String,
    /// World-space mesh.
    pub mesh: Mesh,
    /// What it is made of.
    pub material: ResolvedMaterial,
    /// Whether it is drawn into the shadow maps (`casts_shadow` in the scene).
    pub casts_shadow: bool,
    /// World-space sample points with area weights (translucent objects only).
    pub samples: Vec<SamplePoint>,
    /// How many samples it got and the error predicted for them (translucent objects only).
    pub density: Option<super::accuracy::Density>,
    /// Its levels of detail, finest (the mesh itself) first; only the mesh itself when
    /// `render.level_of_detail` is off or the object's shading rests on per-vertex data the
    /// simplifier cannot see (`lod_allowed`).
    pub levels: Vec<crate::mesh::LodLevel>,
    /// The texture gather's atlas of its mesh, whose texels are then its samples (translucent
    /// objects of a scene with `render.gather = "texture"` only).
    pub atlas: Option<std::sync::Arc<crate::mesh::atlas::Atlas>>,
}

impl PreparedObject {
    /// Per channel, whether it takes single scattering between points (`material.model`);
    /// none for an opaque object.
    pub fn single_channels(&self) -> [bool; 3] {
        match &self.material {
            ResolvedMaterial::Translucent { dipoles, model, .. } => {
                model.single_channels(dipoles.map(|d| d.alpha_prime))
            }
            ResolvedMaterial::Opaque { .. } => [false; 3],
        }
    }

    /// The hierarchy over its samples for the hierarchical gather (built on each call; the
    /// renderer and the f64 reference each build it once, identically). Its reach is the widest
    /// channel's near-blend radius.
    pub fn sample_tree(&self) -> sampling::SampleTree {
        let positions: Vec<glam::DVec3> = self.samples.iter().map(|s| s.position.as_dvec3()).collect();
        let areas: Vec<f64> = self.samples.iter().map(|s| s.area).collect();
        let widest = self.near_blend_radii().into_iter().fold(crate::optics::kernel::NEAR_BLEND_RADIUS, f64::max);
        sampling::SampleTree::new(&positions, &areas, widest)
    }

    /// Per channel, the near-field blend's radius in units of `sqrt(dA)` for its samples
    /// (`optics::kernel::near_blend_radii` at their mean area); the least radius for an opaque
    /// object or one without samples.
    pub fn near_blend_radii(&self) -> [f64; 3] {
        use crate::optics::kernel;
        match &self.material {
            ResolvedMaterial::Translucent { dipoles, .. } if !self.samples.is_empty() => {
                let mean_area = self.samples.iter().map(|s| s.area).sum::<f64>() / self.samples.len() as f64;
                kernel::near_blend_radii(dipoles, mean_area)
            }
            _ => [kernel::NEAR_BLEND_RADIUS; 3],
        }
    }

    /// The hierarchical gather's items for each receiver, in `groups.order` (receivers at
    /// `positions`), at accuracy `epsilon`: each receiver's own cut (`sampling::SampleTree::cut`
    /// about its point, nodes dropped by `optics::kernel::negligible_cluster`); empty lists for
    /// an opaque object. Its own, not its group's: a group's cut lists one by one every sample
    /// within reach of any of its receivers, which on a coarse level of detail is three times
    /// what one receiver needs (docs/STUDY.md, "What a group's list costs").
    pub fn gather_cuts(
        &self,
        tree: &sampling::SampleTree,
        groups: &sampling::ReceiverGroups,
        positions: &[glam::DVec3],
        epsilon: f64,
    ) -> sampling::Cuts {
        let ResolvedMaterial::Translucent { dipoles, .. } = &self.material else {
            return sampling::Cuts::build(groups.order.len(), |_, _| {});
        };
        let negligible =
            |n: &sampling::TreeNode, dist: f64| crate::optics::kernel::negligible_cluster(dipoles, n.area as f64, dist);
        sampling::Cuts::build(groups.order.len(), |k, items| {
            let at = positions[groups.order[k] as usize].as_vec3().to_array();
            tree.cut_into((at, 0.0), epsilon, negligible, items)
        })
    }

    /// Make the texels of an atlas of its mesh at `resolution` its samples (the texture
    /// gather's; `mesh::atlas`), its density judged for their count.
    pub fn place_texels(&mut self, resolution: u32) -> Result<(), crate::mesh::atlas::AtlasError> {
        let atlas = crate::mesh::atlas::Atlas::new(&self.mesh, resolution)?;
        self.samples = atlas.texels.iter().map(texel_sample).collect();
        if let ResolvedMaterial::Translucent { dipoles, .. } = &self.material {
            self.density = self.density.as_ref().map(|d| d.given(dipoles, self.samples.len()));
        }
        self.atlas = Some(std::sync::Arc::new(atlas));
        Ok(())
    }

    /// The texture gather's local window half-width in texels (`mesh::atlas::window_radius`
    /// for its atlas and its widest channel's profile); `None` without an atlas.
    pub fn window_radius(&self) -> Option<u32> {
        let (Some(atlas), ResolvedMaterial::Translucent { dipoles, .. }) = (&self.atlas, &self.material) else {
            return None;
        };
        let widest = dipoles.iter().map(|d| d.profile_radius()).fold(0.0, f64::max);
        Some(crate::mesh::atlas::window_radius(atlas.scale, widest))
    }

    /// Its vertices as the hierarchical gather groups them (`sampling::ReceiverGroups`).
    pub fn receiver_groups(&self) -> sampling::ReceiverGroups {
        let positions: Vec<glam::DVec3> = self.mesh.positions().iter().map(|p| p.as_dvec3()).collect();
        sampling::ReceiverGroups::new(&positions)
    }
}

/// A scene with all its CPU work done: objects loaded, placed and sampled, lights prepared.
/// The renderer uploads it as it is.
#[derive(Clone, Debug)]
pub struct PreparedScene {
    /// The scene it was prepared from, with the command-line overrides applied.
    pub scene: Scene,
    /// The objects, in scene order.
    pub objects: Vec<PreparedObject>,
    /// The lights, key lights first, then the environment's directions (see [`lights::prepare`]).
    pub lights: Vec<PreparedLight>,
    /// Layers of the shadow-map array: one per light that casts shadows onto something.
    pub shadow_layers: u32,
    /// The environment light's map or procedural sky, loaded once.
    pub environment: Option<Environment>,
    /// Bounding sphere of everything (centre, radius).
    pub bounds: (Vec3, f32),
    /// Bounding sphere of the shadow casters, which every shadow frustum covers.
    pub caster_bounds: (Vec3, f32),
    /// Whether any object casts shadows; without one no light gets a shadow layer.
    pub any_caster: bool,
}

/// Whether an object may be drawn simplified. An opaque object under an environment light
/// carries its sky light (soft shadows included) in per-vertex values that a simplifier
/// measuring only positions cannot see: a flat floor would collapse to its outline and lose the
/// shadow under what stands on it. Translucent objects carry gathered exitance, which varies
/// over the width of the diffusion profile, and every level keeps its vertices' values exactly.
fn lod_allowed(material: &ResolvedMaterial, environment_lit: bool) -> bool {
    matches!(material, ResolvedMaterial::Translucent { .. }) || !environment_lit
}

/// Overrides from the command line, applied on top of the scene file.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// `--samples`: replaces `sampling.count` (1 to [`crate::scene::MAX_SAMPLE_COUNT`]).
    pub samples: Option<usize>,
    /// `--sampler`: replaces `sampling.method`.
    pub sampler: Option<Method>,
    /// `--gather`: replaces `render.gather`.
    pub gather: Option<GatherMode>,
    /// `--gather-epsilon`: replaces `render.gather_epsilon` (0 to
    /// [`crate::scene::MAX_GATHER_EPSILON`]).
    pub gather_epsilon: Option<f32>,
    /// `--resolution`: replaces `camera.resolution` (width, height in pixels).
    pub resolution: Option<[u32; 2]>,
    /// `--transport`: replaces `render.transport`.
    pub transport: Option<crate::scene::TransportMode>,
    /// `--splat-visibility`: replaces `render.splat_visibility`.
    pub splat_visibility: Option<crate::scene::SplatVisibility>,
    /// `--full-detail` (false): replaces `render.level_of_detail`.
    pub level_of_detail: Option<bool>,
    /// `--max-error`: replaces `render.max_error` ([`crate::scene::MIN_MAX_ERROR`] to
    /// [`crate::scene::MAX_MAX_ERROR`]).
    pub max_error: Option<f64>,
    /// `--texture-samples`: replaces `render.texture_samples`.
    pub texture_samples: Option<u32>,
    /// `--texture-resolution`: replaces `render.texture_resolution`.
    pub texture_resolution: Option<u32>,
}

/// Every triangle of every shadow-casting object of `objects`, in a hierarchy for rays.
pub fn occluders_of(objects: &[PreparedObject]) -> Bvh {
    let mut triangles = Vec::new();
    for o in objects.iter().filter(|o| o.casts_shadow) {
        for t in 0..o.mesh.triangles().len() {
            triangles.push(o.mesh.corners(t));
        }
    }
    Bvh::new(triangles)
}

/// [`PreparedScene::ray_offset`] for a scene whose bounding sphere has radius `radius`.
pub fn ray_offset_within(radius: f32) -> f64 {
    1e-5 * f64::from(radius)
}

impl PreparedScene {
    /// The shadow casters' triangles in a hierarchy: what the truth's and the splat's shadow
    /// rays are cast into.
    pub fn occluders(&self) -> Bvh {
        occluders_of(&self.objects)
    }

    /// How far a visibility ray starts off the surface, and the least distance at which it
    /// counts a hit: the scale of f32 positions in the scene.
    pub fn ray_offset(&self) -> f64 {
        ray_offset_within(self.bounds.1)
    }

    /// Scene units a shadow-map texel spans: the casters' bounding sphere's diameter over
    /// `render.shadow_map_size` (exact for directional lights, whose maps span that sphere).
    pub fn shadow_texel(&self) -> f64 {
        2.0 * self.caster_bounds.1 as f64 / self.scene.file.render.shadow_map_size as f64
    }

    /// Apply `overrides`, then load, transform and check every object's mesh, resolve its
    /// material, place its sample points (translucent objects only, seed `sampling.seed + i`
    /// for object `i`), load the environment and prepare the lights. Errors say which object
    /// or light and which step.
    pub fn new(scene: &Scene, overrides: &Overrides) -> Result<PreparedScene, SceneError> {
        let mut scene = scene.clone();
        apply_overrides(&mut scene, overrides)?;
        let environment_lit = scene.file.lights.iter().any(|l| matches!(l, Light::Environment { .. }));
        let mut objects = (0..scene.file.objects.len())
            .map(|i| prepare_object(&scene, i, environment_lit))
            .collect::<Result<Vec<_>, _>>()?;
        sample_objects(&scene, &mut objects, None)?;
        choose_gather(&mut scene, &objects, overrides);
        for (i, o) in objects.iter().enumerate() {
            if let Some(warning) = precision_warning(&o.mesh) {
                log::warn!("{}: object[{i}] ({}): {warning}", scene.name, o.name);
            }
        }
        let bounds = bounding_sphere(objects.iter().map(|o| &o.mesh));
        for (i, o) in objects.iter().enumerate() {
            if let Some(warning) = near_plane_warning(&scene.file.camera, &o.mesh, bounds) {
                log::warn!("{}: object[{i}] ({}): {warning}", scene.name, o.name);
            }
        }
        let casters: Vec<&Mesh> = objects.iter().filter(|o| o.casts_shadow).map(|o| &o.mesh).collect();
        let caster_bounds = if casters.is_empty() { bounds } else { bounding_sphere(casters.iter().copied()) };
        let any_caster = !casters.is_empty();
        let environment = load_environment(&scene)?;
        let mut prepared = PreparedScene {
            scene,
            objects,
            lights: Vec::new(),
            shadow_layers: 0,
            environment,
            bounds,
            caster_bounds,
            any_caster,
        };
        prepared.reprepare_lights();
        prepared.check_lights_finite()?;
        Ok(prepared)
    }

    /// Each light's values were checked finite when parsed, but products can overflow (an
    /// environment's `scale` times the irradiance of one of its directions): the first light
    /// that is not finite once prepared, as an error naming the key to lower.
    fn check_lights_finite(&self) -> Result<(), SceneError> {
        let Some(light) = self.lights.iter().find(|l| !light_is_finite(l)) else {
            return Ok(());
        };
        let key = match &self.scene.file.lights[light.source] {
            Light::Environment { .. } => "scale",
            Light::Directional { .. } => "irradiance",
            _ => "intensity",
        };
        Err(SceneError::Invalid {
            file: self.scene.name.clone(),
            message: format!(
                "`light[{}].{key}`: the light is not finite once prepared ({:?}); lower it",
                light.source, light.kind
            ),
        })
    }

    /// Move object `object` to `transform`: that object alone is placed, sampled and given its
    /// levels anew (as `new` would: same method, count and seed), then the scene's bounds and
    /// the lights' shadow frames follow it. Errors as `new` does for that object, leaving the
    /// scene as it was.
    pub fn set_transform(&mut self, object: usize, transform: super::Transform) -> Result<(), SceneError> {
        let mut scene = self.scene.clone();
        scene.file.objects[object].transform = transform;
        let environment_lit = scene.file.lights.iter().any(|l| matches!(l, Light::Environment { .. }));
        let mut objects = self.objects.clone();
        objects[object] = prepare_object(&scene, object, environment_lit)?;
        sample_objects(&scene, &mut objects, Some(object))?;
        self.scene = scene;
        self.objects = objects;
        self.bounds = bounding_sphere(self.objects.iter().map(|o| &o.mesh));
        let casters: Vec<&Mesh> = self.objects.iter().filter(|o| o.casts_shadow).map(|o| &o.mesh).collect();
        self.caster_bounds = if casters.is_empty() { self.bounds } else { bounding_sphere(casters.iter().copied()) };
        self.reprepare_lights();
        self.check_lights_finite()
    }

    /// Recompute the GPU light records from `scene.file.lights` (after a light moved). The
    /// environment's directions and every light's shadow layer stay as they were.
    pub fn reprepare_lights(&mut self) {
        let file = &self.scene.file;
        let mut lights =
            lights::prepare(&file.lights, self.environment.as_ref(), self.caster_bounds, file.render.shadow_map_size);
        self.shadow_layers = lights::assign_shadow_layers(&mut lights, self.any_caster);
        self.lights = lights;
    }

    /// Sample points over all objects.
    pub fn sample_count(&self) -> usize {
        self.objects.iter().map(|o| o.samples.len()).sum()
    }
    /// Mesh vertices over all objects.
    pub fn vertex_count(&self) -> usize {
        self.objects.iter().map(|o| o.mesh.positions().len()).sum()
    }
    /// Whether any object has a translucent material.
    pub fn has_translucent(&self) -> bool {
        self.objects.iter().any(|o| matches!(o.material, ResolvedMaterial::Translucent { .. }))
    }
}

/// Apply the command-line `overrides` to `scene`, checking the two whose ranges the scene
/// file's parser would otherwise have checked (sample count, gather epsilon).
fn apply_overrides(scene: &mut Scene, overrides: &Overrides) -> Result<(), SceneError> {
    if let Some(n) = overrides.samples {
        if n > crate::scene::MAX_SAMPLE_COUNT {
            return Err(SceneError::TooManySamples(n));
        }
        if n == 0 {
            return Err(SceneError::ZeroSamples);
        }
        scene.file.sampling.count = Some(n);
    }
    if let Some(e) = overrides.max_error {
        if crate::scene::check_max_error("--max-error", e).is_err() {
            return Err(SceneError::MaxError(e));
        }
        scene.file.render.max_error = e;
    }
    if let Some(m) = overrides.sampler {
        scene.file.sampling.method = m;
    }
    if let Some(g) = overrides.gather {
        scene.file.render.gather = g;
    }
    if let Some(e) = overrides.gather_epsilon {
        if !(0.0..=crate::scene::MAX_GATHER_EPSILON).contains(&e) {
            return Err(SceneError::GatherEpsilon(e));
        }
        scene.file.render.gather_epsilon = e;
    }
    if let Some(t) = overrides.transport {
        scene.file.render.transport = t;
    }
    if let Some(v) = overrides.splat_visibility {
        scene.file.render.splat_visibility = v;
    }
    let render = &mut scene.file.render;
    render.texture_samples = overrides.texture_samples.unwrap_or(render.texture_samples);
    render.texture_resolution = overrides.texture_resolution.unwrap_or(render.texture_resolution);
    crate::scene::check_texture(
        "--texture-samples",
        "--texture-resolution",
        render.texture_samples,
        render.texture_resolution,
    )
    .map_err(|(flag, message)| SceneError::Flag(format!("{flag} {message}")))?;
    if let Some(l) = overrides.level_of_detail {
        scene.file.render.level_of_detail = l;
    }
    if let Some(r) = overrides.resolution {
        scene.file.camera.resolution = r;
    }
    Ok(())
}

/// Object `i` of `scene` loaded, placed, checked against [`super::MAX_SCENE_COORDINATE`], its
/// material resolved and its levels of detail built (where [`lod_allowed`]); [`sample_objects`]
/// places its samples once every object is placed.
fn prepare_object(scene: &Scene, i: usize, environment_lit: bool) -> Result<PreparedObject, SceneError> {
    let o = &scene.file.objects[i];
    let (name, mesh) = load_shape(scene, &o.shape).with_context(|| format!("{}: object[{i}]", scene.name))?;
    let mesh = transform_mesh(mesh, &o.transform)
        .with_context(|| format!("{}: object[{i}] ({name}): transform", scene.name))?;
    check_reach(scene, i, &name, &mesh)?;
    let material = resolve_material(&o.material, &format!("{}: object[{i}].material", scene.name))?;
    let levels = if scene.file.render.level_of_detail && lod_allowed(&material, environment_lit) {
        mesh.levels_of_detail()
    } else {
        vec![mesh.full_level()]
    };
    Ok(PreparedObject {
        name,
        mesh,
        material,
        casts_shadow: o.casts_shadow,
        samples: Vec::new(),
        density: None,
        levels,
        atlas: None,
    })
}

/// Place the samples of every translucent object of `objects` (only object `only`, when given),
/// object `i` with seed `sampling.seed + i`: `sampling.count` of them when the scene sets it,
/// else as many as `render.max_error` needs (`super::accuracy`), judged with every shadow
/// caster of `objects` in place.
fn sample_objects(scene: &Scene, objects: &mut [PreparedObject], only: Option<usize>) -> Result<(), SceneError> {
    let occluders = crate::reference::occluders_of(objects);
    let eps = crate::reference::ray_offset_within(bounding_sphere(objects.iter().map(|o| &o.mesh)).1);
    let file = &scene.file;
    for (i, o) in objects.iter_mut().enumerate().filter(|(i, _)| only.is_none_or(|j| j == *i)) {
        let facts = super::accuracy::surface_facts(o, &occluders, eps);
        if file.render.gather == GatherMode::Texture && matches!(o.material, ResolvedMaterial::Translucent { .. }) {
            o.place_texels(file.render.texture_resolution).map_err(|e| {
                SceneError::Flag(format!("{}: object[{i}] ({}): texture atlas: {e}", scene.name, o.name))
            })?;
            let count = Some(o.samples.len());
            o.density = super::accuracy::choose_count(o, facts, count, file.render.max_error).map(|(_, d)| d);
            continue;
        }
        let Some((count, density)) =
            super::accuracy::choose_count(o, facts, file.sampling.count, file.render.max_error)
        else {
            continue;
        };
        let options =
            SampleOptions::new(file.sampling.method, count).with_seed(file.sampling.seed.wrapping_add(i as u64));
        o.samples = sampling::sample(&o.mesh, &options)
            .with_context(|| format!("{}: object[{i}] ({}): sampling", scene.name, o.name))?
            .points;
        o.density = Some(density);
    }
    Ok(())
}

/// A texel of the texture gather's atlas as a sample point (`mesh::atlas`: it carries the area
/// of the surface it stands for).
fn texel_sample(t: &crate::mesh::atlas::Texel) -> SamplePoint {
    SamplePoint {
        position: t.position,
        normal: t.normal,
        triangle: t.triangle,
        barycentric: t.barycentric.map(|b| b as f32),
        area: t.area,
    }
}

/// The gather a scene leaves to the sample count: the hierarchical one, at
/// [`super::accurate_gather_epsilon`] of its error target unless the scene or the command line gives an epsilon,
/// when an object has more than [`super::AUTO_HIERARCHICAL_COUNT`] samples.
fn choose_gather(scene: &mut Scene, objects: &[PreparedObject], overrides: &Overrides) {
    let render = &mut scene.file.render;
    if overrides.gather.is_some() {
        return;
    }
    let (gather, epsilon) = own_gather(render, objects);
    render.gather = gather;
    if overrides.gather_epsilon.is_none() {
        render.gather_epsilon = epsilon;
    }
}

/// The gather and epsilon a scene's own `render` settings give `objects` as sampled: what it
/// names, else by [`choose_gather`]'s rule (the study's `default` row).
pub fn own_gather(render: &super::RenderSettings, objects: &[PreparedObject]) -> (GatherMode, f32) {
    let many = objects.iter().any(|o| o.samples.len() > super::AUTO_HIERARCHICAL_COUNT);
    let gather = render.gather_given.unwrap_or(if many { GatherMode::Hierarchical } else { GatherMode::Vertex });
    let chosen = render.gather_given.is_none() && gather == GatherMode::Hierarchical;
    let fallback =
        if chosen { super::accurate_gather_epsilon(render.max_error) } else { super::DEFAULT_GATHER_EPSILON };
    (gather, render.gather_epsilon_given.unwrap_or(fallback))
}

/// Object `i` (`name`), as placed, must stay within [`super::MAX_SCENE_COORDINATE`] of the
/// origin on every axis.
fn check_reach(scene: &Scene, i: usize, name: &str, mesh: &Mesh) -> Result<(), SceneError> {
    let (lo, hi) = mesh.bounds();
    let reach = lo.abs().max(hi.abs()).max_element();
    if reach > super::MAX_SCENE_COORDINATE {
        return Err(SceneError::Invalid {
            file: scene.name.clone(),
            message: format!(
                "`object[{i}]` ({name}): placed by its shape and transform it reaches {reach:e} scene units \
                 from the origin, beyond the limit of {:e}",
                super::MAX_SCENE_COORDINATE
            ),
        });
    }
    Ok(())
}

/// A material as the scene gives it, resolved: a preset or custom coefficients (`eta` 1.3 unless
/// given, a preset's own overridden where given) and its dipoles in scene units. Errors carry
/// `key`, the material's place in the scene.
fn resolve_material(spec: &MaterialSpec, key: &str) -> Result<ResolvedMaterial, SceneError> {
    let (preset, sigma_a, sigma_s_prime, eta, mm_per_unit, roughness, model) = match spec {
        MaterialSpec::Translucent { preset, sigma_a, sigma_s_prime, eta, mm_per_unit, roughness, model } => {
            (preset, sigma_a, sigma_s_prime, eta, mm_per_unit, roughness, model)
        }
        MaterialSpec::Opaque { albedo, roughness } => {
            return Ok(ResolvedMaterial::Opaque { albedo: *albedo, roughness: *roughness });
        }
    };
    let key = || key.to_owned();
    let mut material = match preset {
        Some(p) => Material::preset(p).with_context(key)?,
        None => Material::new(
            "custom",
            sigma_a.expect("checked when parsed"),
            sigma_s_prime.expect("checked when parsed"),
            eta.unwrap_or(1.3),
        )
        .with_context(key)?,
    };
    if let (Some(e), Some(_)) = (eta, preset) {
        material = material.with_eta(*e).with_context(key)?;
    }
    let dipoles = material.dipoles(*mm_per_unit).with_context(key)?;
    Ok(ResolvedMaterial::Translucent {
        material,
        dipoles,
        mm_per_unit: *mm_per_unit,
        roughness: *roughness,
        model: *model,
    })
}

/// The environment light's map loaded (or the procedural sky where it names none), if the scene
/// has an environment light. A map embedded in the scene file is refused.
fn load_environment(scene: &Scene) -> Result<Option<Environment>, SceneError> {
    scene
        .file
        .lights
        .iter()
        .find_map(|l| match l {
            Light::Environment { map, .. } => Some(map.clone()),
            _ => None,
        })
        .map(|map| match map {
            None => Ok(Environment::procedural_sky(128, 64)),
            Some(path) => match scene.resolve(&path)? {
                AssetSource::File(p) => Ok(Environment::load(&p)?),
                AssetSource::Embedded(_) => Err(SceneError::EmbeddedEnvironment),
            },
        })
        .transpose()
        .with_context(|| format!("{}: environment light", scene.name))
}

fn light_is_finite(l: &PreparedLight) -> bool {
    let kind = match l.kind {
        lights::LightKind::Directional { direction, irradiance } => direction.is_finite() && irradiance.is_finite(),
        lights::LightKind::Point { position, intensity } => position.is_finite() && intensity.is_finite(),
        lights::LightKind::Spot { position, axis, intensity, cos_outer, cos_inner } => {
            position.is_finite()
                && axis.is_finite()
                && intensity.is_finite()
                && cos_outer.is_finite()
                && cos_inner.is_finite()
        }
    };
    kind && l.shadow_matrix.is_finite() && l.normal_offset.is_finite()
}

fn load_shape(scene: &Scene, shape: &Shape) -> Result<(String, Mesh), SceneError> {
    match shape {
        Shape::Mesh { path } => {
            let mesh = match scene.resolve(path)? {
                AssetSource::File(p) => Mesh::load(&p, &LoadOptions::default())?,
                AssetSource::Embedded(bytes) => {
                    let text = std::str::from_utf8(bytes).map_err(SceneError::EmbeddedMeshNotUtf8)?;
                    Mesh::from_obj_text(text, path, &LoadOptions::default())?
                }
            };
            Ok((path.clone(), mesh))
        }
        Shape::Plane { size, divisions } => Ok(("plane".into(), plane(*size, *divisions)?)),
        Shape::Sphere { radius, divisions } => Ok(("sphere".into(), sphere(*radius, *divisions)?)),
    }
}

/// Apply fit, scale, rotation (degrees, x then y then z) and translation, in that order.
fn transform_mesh(mesh: Mesh, t: &super::Transform) -> Result<Mesh, SceneError> {
    let mut m = Mat4::IDENTITY;
    if let Some(fit) = t.fit {
        let (lo, hi) = mesh.bounds();
        let extent = (hi - lo).max_element();
        if extent.is_nan() || extent <= 0.0 {
            return Err(SceneError::EmptyBounds);
        }
        let centre = Vec3::new(0.5 * (lo.x + hi.x), lo.y, 0.5 * (lo.z + hi.z));
        m = Mat4::from_scale(Vec3::splat(fit / extent)) * Mat4::from_translation(-centre);
    }
    if let Some(s) = t.scale {
        m = Mat4::from_scale(Vec3::splat(s)) * m;
    }
    if let Some([x, y, z]) = t.rotate {
        let q = Quat::from_euler(EulerRot::ZYX, z.to_radians(), y.to_radians(), x.to_radians());
        m = Mat4::from_quat(q) * m;
    }
    if let Some(tr) = t.translate {
        m = Mat4::from_translation(Vec3::from(tr)) * m;
    }
    if m == Mat4::IDENTITY {
        return Ok(mesh);
    }
    let positions = mesh.positions().iter().map(|p| m.transform_point3(*p)).collect();
    Ok(Mesh::from_triangles(positions, mesh.triangles().to_vec())?)
}

/// A square in the xz plane at y = 0, facing +y.
pub fn plane(size: f32, divisions: u32) -> Result<Mesh, MeshError> {
    let n = divisions as usize;
    let mut positions = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let u = i as f32 / n as f32 - 0.5;
            let v = j as f32 / n as f32 - 0.5;
            positions.push(Vec3::new(u * size, 0.0, v * size));
        }
    }
    let mut triangles = Vec::with_capacity(2 * n * n);
    let at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    for j in 0..n {
        for i in 0..n {
            // Counter-clockwise seen from +y.
            triangles.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            triangles.push([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    Mesh::from_triangles(positions, triangles)
}

/// A UV sphere centred at the origin (outward-facing).
pub fn sphere(radius: f32, divisions: u32) -> Result<Mesh, MeshError> {
    let rings = divisions.max(3) as usize;
    let segments = 2 * rings;
    let mut positions = vec![Vec3::new(0.0, radius, 0.0)];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = 2.0 * std::f32::consts::PI * s as f32 / segments as f32;
            positions.push(radius * Vec3::new(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin()));
        }
    }
    positions.push(Vec3::new(0.0, -radius, 0.0));
    let bottom = (positions.len() - 1) as u32;
    let ring = |r: usize, s: usize| (1 + (r - 1) * segments + s % segments) as u32;
    let mut triangles = Vec::new();
    for s in 0..segments {
        triangles.push([0, ring(1, s + 1), ring(1, s)]);
        triangles.push([bottom, ring(rings - 1, s), ring(rings - 1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            triangles.push([ring(r, s), ring(r, s + 1), ring(r + 1, s)]);
            triangles.push([ring(r, s + 1), ring(r + 1, s + 1), ring(r + 1, s)]);
        }
    }
    Mesh::from_triangles(positions, triangles)
}

/// A warning when the camera's near plane clips `mesh` where the camera looks at it: its
/// nearest point to the eye lies inside the field of view (the cone through the image's
/// corners) and nearer than the near plane, which the scene's depth sets (a camera 1e-5 units
/// from a thin mesh in a large scene sees nothing of it). A grazing part of the mesh that is
/// not its nearest point is not looked for.
pub fn near_plane_warning(camera: &Camera, mesh: &Mesh, bounds: (Vec3, f32)) -> Option<String> {
    let (near, _) = camera.depth_range(bounds.0, bounds.1);
    let eye = Vec3::from(camera.eye).as_dvec3();
    let forward = (Vec3::from(camera.target) - Vec3::from(camera.eye)).as_dvec3().normalize_or_zero();
    let aspect = f64::from(camera.resolution[0]) / f64::from(camera.resolution[1].max(1));
    let tan_corner = (f64::from(camera.fov_y).to_radians() / 2.0).tan() * (1.0 + aspect * aspect).sqrt();
    let nearest = (0..mesh.triangles().len())
        .map(|t| closest_on_triangle(eye, mesh.corners(t)))
        .min_by(|a, b| a.distance_squared(eye).total_cmp(&b.distance_squared(eye)))?;
    let (offset, depth) = (nearest - eye, (nearest - eye).dot(forward));
    let lateral = (offset - forward * depth).length();
    (depth >= 0.0 && lateral <= depth * tan_corner && offset.length() < f64::from(near)).then(|| {
        format!(
            "the camera is {:.3e} units from it, nearer than the near plane ({near:.3e} units, set by the \
             scene's depth), which clips it from the image: move the camera back",
            offset.length()
        )
    })
}

/// The point of the triangle `corners` nearest to `p` (Ericson, Real-Time Collision Detection
/// 5.1.5: by the Voronoi region of `p`).
fn closest_on_triangle(p: DVec3, corners: [DVec3; 3]) -> DVec3 {
    let [a, b, c] = corners;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Positions are f32 in world space: an object far from the origin compared with its size has
/// its vertices quantised to the f32 spacing there. A warning with the figures when that spacing
/// is above 1e-4 of the object's size (the sample spacing of a few hundred samples is about
/// 5e-2 of it, the dipole kernels' blend widths a fraction of that).
pub fn precision_warning(mesh: &Mesh) -> Option<String> {
    let (lo, hi) = mesh.bounds();
    let size = (hi - lo).max_element();
    let distance = lo.abs().max(hi.abs()).max_element();
    let spacing = distance * f32::EPSILON;
    (size > 0.0 && spacing > 1e-4 * size).then(|| {
        format!(
            "it is {distance:.3e} units from the origin and {size:.3e} across: f32 positions there are \
             quantised to {spacing:.2e} units ({:.2}% of its size); move the scene near the origin",
            100.0 * spacing / size
        )
    })
}

fn bounding_sphere<'a>(meshes: impl Iterator<Item = &'a Mesh>) -> (Vec3, f32) {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    for m in meshes {
        let (a, b) = m.bounds();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if !lo.is_finite() {
        return (Vec3::ZERO, 1.0);
    }
    ((lo + hi) * 0.5, ((hi - lo) * 0.5).length().max(1e-6))
}
