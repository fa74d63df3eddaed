//! From a parsed scene to what the renderer uploads: meshes loaded, transformed to world space
//! and validated; materials resolved; sample points placed on each translucent mesh; lights
//! prepared with shadow layers. Everything here is CPU work done once per scene.

use super::lights::{self, Environment, PreparedLight};
use super::{AssetSource, GatherMode, Light, MaterialSpec, Scene, SceneError, Shape};
use crate::mesh::bvh::Bvh;
use crate::mesh::{LoadOptions, Mesh};
use crate::optics::Material;
use crate::sampling::{self, Method, SampleOptions};
use glam::{EulerRot, Mat4, Quat, Vec3};
use std::sync::Arc;

/// The prepared object and its material (`scene::object`).
pub use super::object::{KernelDropped, PreparedObject, ResolvedMaterial};
/// The warnings preparing a scene gives per object (`scene::warnings`).
pub use super::warnings::{near_plane_warning, precision_warning};
/// The built-in shapes, built by the mesh floor (`mesh::shapes`).
pub use crate::mesh::shapes::{plane, sphere};

/// `.with_context(|| where)`: wrap an error in [`SceneError::Context`].
trait WithContext<T> {
    fn with_context(self, context: impl FnOnce() -> String) -> Result<T, SceneError>;
}

impl<T, E: Into<SceneError>> WithContext<T> for Result<T, E> {
    fn with_context(self, context: impl FnOnce() -> String) -> Result<T, SceneError> {
        self.map_err(|e| SceneError::Context { context: context(), source: Box::new(e.into()) })
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
    /// `--receivers`: replaces `render.receivers`.
    pub receivers: Option<crate::scene::ReceiverPolicy>,
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
            location: super::Location::key(format!("light[{}].{key}", light.source)),
            problem: super::BadValue::LightNotFinite(light.kind).into(),
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
        // The mesh as loaded and the material as it is now (a material edit is kept; the file
        // is not read again).
        let old = &self.objects[object];
        let loaded = old.frame.as_deref().unwrap_or(&old.mesh).clone();
        let (mesh, frame) = place_mesh(&scene, object, &old.name, loaded)?;
        let placed = (old.name.clone(), mesh, frame);
        objects[object] = placed_object(&scene, object, placed, old.material.clone(), environment_lit);
        keep_kernel(old, &mut objects[object]);
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
    if let Some(r) = overrides.receivers {
        scene.file.render.receivers = r;
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
    .map_err(SceneError::Flag)?;
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
    let (mesh, frame) = place_mesh(scene, i, &name, mesh)?;
    let material = resolve_material(&o.material, &format!("{}: object[{i}].material", scene.name))?;
    Ok(placed_object(scene, i, (name, mesh, frame), material, environment_lit))
}

/// Object `i`'s mesh as loaded, `mesh`, placed by its transform and checked against
/// [`super::MAX_SCENE_COORDINATE`]; with the mesh as loaded where the transform moved it.
fn place_mesh(scene: &Scene, i: usize, name: &str, mesh: Mesh) -> Result<(Mesh, Option<Arc<Mesh>>), SceneError> {
    let (mesh, frame) = transform_mesh(mesh, &scene.file.objects[i].transform)
        .with_context(|| format!("{}: object[{i}] ({name}): transform", scene.name))?;
    check_reach(scene, i, name, &mesh)?;
    Ok((mesh, frame))
}

/// Object `i` from its name and placed meshes and its material: its levels of detail built,
/// no samples yet.
fn placed_object(
    scene: &Scene,
    i: usize,
    (name, mesh, frame): (String, Mesh, Option<Arc<Mesh>>),
    material: ResolvedMaterial,
    environment_lit: bool,
) -> PreparedObject {
    let levels = if scene.file.render.level_of_detail && lod_allowed(&material, environment_lit) {
        mesh.levels_of_detail()
    } else {
        vec![mesh.full_level()]
    };
    PreparedObject {
        name,
        mesh,
        frame,
        material,
        casts_shadow: scene.file.objects[i].casts_shadow,
        samples: Vec::new(),
        density: None,
        levels,
        atlas: None,
        transport: None,
        kernel_dropped: None,
        model: None,
    }
}

/// Carries `old`'s transport kernel over to `moved`, the same object placed anew: a rigid move
/// (its area unchanged within 1e-6) keeps it, the patches following the vertices
/// (`TransportKernel::placed`); a scale drops it (`KernelDropped::Scaled`).
fn keep_kernel(old: &PreparedObject, moved: &mut PreparedObject) {
    moved.kernel_dropped = old.kernel_dropped;
    if old.transport.is_some() {
        let (a, b) = (old.mesh.total_area(), moved.mesh.total_area());
        if (a - b).abs() <= 1e-6 * a {
            moved.transport.clone_from(&old.transport);
        } else {
            moved.kernel_dropped = Some(super::object::KernelDropped::Scaled);
        }
    }
}

/// Place the samples of every translucent object of `objects` (only object `only`, when given),
/// object `i` with seed `sampling.seed + i`: `sampling.count` of them when the scene sets it,
/// else as many as `render.max_error` needs (`super::accuracy`), judged with every shadow
/// caster of `objects` in place.
fn sample_objects(scene: &Scene, objects: &mut [PreparedObject], only: Option<usize>) -> Result<(), SceneError> {
    let occluders = occluders_of(objects);
    let eps = ray_offset_within(bounding_sphere(objects.iter().map(|o| &o.mesh)).1);
    let file = &scene.file;
    for (i, o) in objects.iter_mut().enumerate().filter(|(i, _)| only.is_none_or(|j| j == *i)) {
        let facts = super::accuracy::surface_facts(&o.mesh, &o.levels, &occluders, eps);
        // An opaque object takes no samples.
        let ResolvedMaterial::Translucent { dipoles, .. } = &o.material else { continue };
        let dipoles = *dipoles;
        if file.render.gather == GatherMode::Texture {
            o.place_texels(file.render.texture_resolution).map_err(|e| {
                SceneError::from(e).in_context(format!("{}: object[{i}] ({}): texture atlas", scene.name, o.name))
            })?;
            let count = Some(o.samples.len());
            o.density = Some(super::accuracy::choose_count(&dipoles, facts, count, file.render.max_error).1);
            o.choose_model(file.render.max_error);
            continue;
        }
        let (count, density) =
            super::accuracy::choose_count(&dipoles, facts, file.sampling.count, file.render.max_error);
        let options =
            SampleOptions::new(file.sampling.method, count).with_seed(file.sampling.seed.wrapping_add(i as u64));
        // The transform keeps the triangles; where cleaning a degenerate one changed them,
        // the samples are placed in world space.
        let frame = o.frame.as_deref().filter(|f| f.triangles() == o.mesh.triangles()).unwrap_or(&o.mesh);
        o.samples = sampling::sample_in_frame(frame, &o.mesh, &options)
            .with_context(|| format!("{}: object[{i}] ({}): sampling", scene.name, o.name))?
            .points;
        o.density = Some(density);
        o.choose_model(file.render.max_error);
    }
    Ok(())
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
            location: super::Location::key(format!("object[{i}]")),
            problem: super::BadValue::BeyondReach { object: name.to_string(), reach }.into(),
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
        Shape::Mesh { path, node, part } => {
            let mesh = match scene.resolve(path)? {
                AssetSource::File(p) => load_mesh_file(&p, node.as_deref(), *part)?,
                AssetSource::Embedded(bytes) => {
                    let text = std::str::from_utf8(bytes).map_err(SceneError::EmbeddedMeshNotUtf8)?;
                    Mesh::from_obj_text(text, path, &LoadOptions::default())?
                }
            };
            let name = match (node, part) {
                (Some(n), _) => format!("{path}#{n}"),
                (None, Some(part)) => format!("{path}#node{}", part.node),
                (None, None) => path.clone(),
            };
            Ok((name, mesh))
        }
        Shape::Plane { size, divisions } => Ok(("plane".into(), plane(*size, *divisions)?)),
        Shape::Sphere { radius, divisions } => Ok(("sphere".into(), sphere(*radius, *divisions)?)),
    }
}

/// A mesh file: an OBJ, or a glTF file's scene, its node named `node` or one node's `part`.
fn load_mesh_file(
    path: &std::path::Path,
    node: Option<&str>,
    part: Option<crate::mesh::GltfNodePart>,
) -> Result<Mesh, SceneError> {
    let options = LoadOptions::default();
    #[cfg(feature = "gltf")]
    match (node, part) {
        (Some(node), _) => return Ok(Mesh::load_gltf_node(path, node, &options)?),
        (None, Some(part)) => return Ok(Mesh::load_gltf_part(path, part, &options)?),
        (None, None) => {}
    }
    #[cfg(not(feature = "gltf"))]
    if node.is_some() || part.is_some() {
        return Err(crate::mesh::MeshError::GltfDisabled { path: path.to_path_buf() }.into());
    }
    Ok(Mesh::load(path, &options)?)
}

/// Apply fit, scale, rotation (degrees, x then y then z) and translation, in that order; also
/// the mesh as it was, where the transform is not the identity (`PreparedObject::frame`).
fn transform_mesh(mesh: Mesh, t: &super::Transform) -> Result<(Mesh, Option<Arc<Mesh>>), SceneError> {
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
        return Ok((mesh, None));
    }
    let placed = mesh.transformed(m)?;
    Ok((placed, Some(Arc::new(mesh))))
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
    // Any positive radius is a scale (the scene may be in micrometres); none, a unit one.
    let radius = ((hi - lo) * 0.5).length();
    ((lo + hi) * 0.5, if radius > 0.0 && radius.is_finite() { radius } else { 1.0 })
}
