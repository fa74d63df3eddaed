//! The accuracy study (`translucent study`): what accuracy costs in time.
//!
//! Every configuration (sampler x sample count x gather x seed) is rendered and compared with
//! the exact dipole integral of `reference::truth`, per vertex and as an image; its passes are
//! timed. `report` turns the rows into CSV and Markdown, `plot` into error against time, `flip`
//! measures the tone-mapped images' FLIP error, `raster` draws per-vertex error on the model.

pub mod flip;
pub mod models;
pub mod physics;
pub mod plot;
pub mod raster;
pub mod report;

use crate::gpu::Gpu;
use crate::reference::rte::RteProgress;
use crate::reference::rte_cache::RteCacheError;
use crate::reference::rte_mesh::MeshOptions;
use crate::reference::truth::{self, LIT_FLOOR, Truth, TruthOptions};
use crate::render::error::RenderError;
use crate::render::plan::{Change, Pass};
use crate::render::renderer::Renderer;
use crate::sampling::{self, Method, SampleOptions};
use crate::scene::build::{Overrides, PreparedScene, ResolvedMaterial};
use crate::scene::{GatherMode, Scene, SceneError, TransportMode};
use report::Row;
use std::path::Path;
use std::sync::Arc;

/// What a study sweeps.
#[derive(Clone, Debug)]
pub struct StudyConfig {
    /// Samplers, in order.
    pub samplers: Vec<Method>,
    /// Sample counts per object.
    pub counts: Vec<usize>,
    /// Gathers, with the hierarchical gather's epsilon or the texture gather's atlas
    /// resolution (texels per side) where they apply. The texture gather takes each count as
    /// its draws per receiver (`render.texture_samples`, counts above its limit skipped), with
    /// the first sampler and seed only: its samples are the atlas's texels and its random
    /// numbers are fixed.
    pub gathers: Vec<(GatherMode, Option<f32>)>,
    /// Seeds (each replaces `sampling.seed`).
    pub seeds: Vec<u64>,
    /// Timed frames per configuration (median taken), after one warm-up frame.
    pub frames: usize,
    /// How far the truth is refined (its tolerance and deepest level).
    pub truth: TruthOptions,
    /// Measure the scene's own configuration (its error target's counts and gather) as a row
    /// labelled `default`.
    pub own: bool,
    /// Measure the sweep (samplers x counts x gathers x seeds).
    pub sweep: bool,
    /// Split the error against the physics (`--physics`): the radiative-transfer reference's
    /// budget and seed (`reference::rte_mesh`); `None` measures against the dipole alone.
    pub physics: Option<MeshOptions>,
    /// With `physics`: the models measured beside the dipole.
    pub models: Vec<physics::Model>,
    /// The models the renderer is swept with, each forced on every translucent material
    /// (`models`); empty: the scene's own.
    pub render_models: Vec<crate::scene::ScatteringModel>,
}

impl StudyConfig {
    /// The sweep: every sampler, 100 to 6,400 samples doubling, every gather (the
    /// hierarchical at three epsilons), three seeds, five timed frames.
    pub fn full() -> StudyConfig {
        StudyConfig {
            samplers: Method::ALL.to_vec(),
            counts: vec![100, 200, 400, 800, 1600, 3200, 6400],
            gathers: vec![
                (GatherMode::Vertex, None),
                (GatherMode::Sparse, None),
                (GatherMode::Pixel, None),
                (GatherMode::Hierarchical, Some(0.3)),
                (GatherMode::Hierarchical, Some(0.1)),
                (GatherMode::Hierarchical, Some(0.03)),
                (GatherMode::Texture, Some(128.0)),
                (GatherMode::Texture, Some(256.0)),
                (GatherMode::Texture, Some(512.0)),
            ],
            seeds: vec![1, 2, 3],
            frames: 5,
            truth: TruthOptions::default(),
            own: true,
            sweep: true,
            physics: None,
            models: Vec::new(),
            render_models: Vec::new(),
        }
    }

    /// A few seconds' worth, for CI: Turk at three doubling counts and random at one, the
    /// vertex gather, one seed, three frames.
    pub fn quick() -> StudyConfig {
        StudyConfig {
            samplers: vec![Method::Turk, Method::Random],
            counts: vec![100, 200, 400],
            gathers: vec![(GatherMode::Vertex, None)],
            seeds: vec![1],
            frames: 3,
            truth: TruthOptions::default(),
            own: true,
            sweep: true,
            physics: None,
            models: Vec::new(),
            render_models: Vec::new(),
        }
    }

    /// Configurations times seeds, and the scene's own row, per model rendered.
    pub fn runs(&self) -> usize {
        (self.configurations().len() + usize::from(self.own)) * self.render_models.len().max(1)
    }

    /// The sweep's configurations, in order.
    fn configurations(&self) -> Vec<Configuration> {
        let mut out = Vec::new();
        if !self.sweep {
            return out;
        }
        for &method in &self.samplers {
            for &count in &self.counts {
                for &seed in &self.seeds {
                    for &gather in &self.gathers {
                        let texture = gather.0 == GatherMode::Texture;
                        let first = Some(&method) == self.samplers.first() && Some(&seed) == self.seeds.first();
                        if texture && !(first && count <= crate::scene::MAX_TEXTURE_SAMPLES as usize) {
                            continue;
                        }
                        out.push(Configuration { method, count, seed, gather, own: false });
                    }
                }
            }
        }
        out
    }
}

/// Why a study stopped.
#[derive(Debug, thiserror::Error)]
#[allow(missing_docs)] // each variant carries the underlying error, which names what failed
pub enum StudyError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Truth(#[from] truth::TruthError),
    #[error(transparent)]
    Rte(#[from] RteCacheError),
    // The cause is the source, shown after it by `{:#}` and error reporters.
    /// Sample points for object `object` could not be placed.
    #[error("sampling {object}")]
    Sampling { object: String, source: sampling::SamplingError },
    /// Texels for object `object` (the texture gather's samples) could not be placed.
    #[error("sampling {object}")]
    Atlas { object: String, source: crate::mesh::atlas::AtlasError },
    /// A picture or comparison of the report (a FLIP score) could not be made.
    #[error(transparent)]
    Plot(#[from] plot::PlotError),
    #[error("the scene has no translucent object: there is nothing to study")]
    NothingTranslucent,
    #[error(
        "no light reaches a translucent object: the exact exitance is zero at every receiver, so every \
         configuration would read 0% error and none can be ranked; light the scene"
    )]
    NothingLit,
}

/// What a running study reports, for a progress bar.
#[derive(Clone, Debug)]
pub enum Event {
    /// The truth: `(level, receivers done, receivers)`.
    Truth(u32, usize, usize),
    /// The truth was read from the cache.
    TruthCached,
    /// The radiative-transfer reference (`--physics`) after a round of photons.
    Rte(RteProgress),
    /// The radiative-transfer reference was read from the cache.
    RteCached,
    /// A configuration starts: `(index, of, label)`.
    Run(usize, usize, String),
    /// An object's transport kernel is walked: `(object's name, patches done, patches)`.
    Kernel(String, usize, usize),
    /// A long step that counts nothing of its own starts.
    Step(Step),
}

/// The long steps of a study that report no count, named so a progress bar can say which one
/// the study is in.
#[derive(Clone, Copy, Debug)]
pub enum Step {
    /// Single scattering between points over the scene (`reference::single::between_points`).
    BetweenPoints,
    /// One of `--models`, beside the scene's own model against the radiative transfer.
    Model(physics::Model),
    /// The truth's image (the exact exitance rendered through the camera).
    TruthImage,
}

/// Per-vertex error against the truth, per channel, over the receivers lit in the truth
/// (exitance at least [`LIT_FLOOR`] of the object's brightest in that channel).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct VertexError {
    /// Relative RMS error.
    pub rel_rms: [f64; 3],
    /// 99th percentile of the absolute relative error.
    pub p99: [f64; 3],
    /// Largest absolute relative error.
    pub max: [f64; 3],
    /// Mean relative error (signed: positive reads too bright).
    pub bias: [f64; 3],
    /// Lit receivers per channel.
    pub lit: [usize; 3],
}

/// Per-vertex error of `estimate` against `truth`, over every object (scene order; opaque
/// objects have all-zero truth and count for nothing). The floor is per object and channel.
pub fn vertex_error(truth: &[Vec<[f64; 3]>], estimate: &[Vec<[f32; 3]>]) -> VertexError {
    let estimate: Vec<Vec<[f64; 3]>> = estimate.iter().map(|o| o.iter().map(|m| m.map(f64::from)).collect()).collect();
    vertex_error_f64(truth, &estimate)
}

/// [`vertex_error`] of an f64 estimate (the dipole truth against the radiative-transfer
/// reference); receivers where the estimate is NaN (outside a truth's receiver subset) are
/// left out.
pub fn vertex_error_f64(truth: &[Vec<[f64; 3]>], estimate: &[Vec<[f64; 3]>]) -> VertexError {
    let mut out = VertexError::default();
    for c in 0..3 {
        let mut rel = Vec::new();
        for (t, e) in truth.iter().zip(estimate) {
            let floor = LIT_FLOOR * t.iter().map(|m| m[c]).fold(0.0, f64::max);
            for (tv, ev) in t.iter().zip(e) {
                if tv[c] > 0.0 && tv[c] >= floor && !ev[c].is_nan() {
                    rel.push((ev[c] - tv[c]) / tv[c]);
                }
            }
        }
        if rel.is_empty() {
            continue;
        }
        let n = rel.len() as f64;
        out.lit[c] = rel.len();
        out.rel_rms[c] = (rel.iter().map(|r| r * r).sum::<f64>() / n).sqrt();
        out.bias[c] = rel.iter().sum::<f64>() / n;
        let mut abs: Vec<f64> = rel.iter().map(|r| r.abs()).collect();
        abs.sort_by(f64::total_cmp);
        out.max[c] = abs[abs.len() - 1];
        out.p99[c] = abs[((0.99 * (abs.len() - 1) as f64).round() as usize).min(abs.len() - 1)];
    }
    out
}

/// Relative RMSE of the RGB of two linear RGBA images: `sqrt(sum (a - b)^2 / sum b^2)`.
pub fn image_rel_rmse(truth: &[f32], image: &[f32]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (t, i) in truth.chunks_exact(4).zip(image.chunks_exact(4)) {
        for c in 0..3 {
            let (t, i) = (f64::from(t[c]), f64::from(i[c]));
            num += (i - t) * (i - t);
            den += t * t;
        }
    }
    if den > 0.0 { (num / den).sqrt() } else { 0.0 }
}

/// The images of one frame: tone-mapped RGBA8 and linear RGBA f32.
#[derive(Clone, Debug)]
pub struct Images {
    /// Width and height in pixels.
    pub size: [u32; 2],
    /// Tone-mapped, 8-bit RGBA, rows top to bottom.
    pub ldr: Vec<u8>,
    /// Linear HDR RGBA.
    pub hdr: Vec<f32>,
}

/// A finished study.
#[derive(Clone, Debug)]
pub struct Study {
    /// One row per configuration and seed.
    pub rows: Vec<Row>,
    /// The truth it was measured against.
    pub truth: Truth,
    /// Whether the truth came from the cache.
    pub truth_cached: bool,
    /// The scene shaded with the true exitance (vertex interpolation, like the vertex gather);
    /// none when the truth covers a subset of the vertices.
    pub truth_image: Option<Images>,
    /// The scene prepared as the truth saw it (the study's first configuration's geometry).
    pub prepared: PreparedScene,
    /// Each configuration's per-vertex exitance, for `--error-image` (same order as `rows`).
    pub exitance: Vec<Option<Vec<Vec<[f32; 3]>>>>,
    /// The f64 CPU reference timed on one swept configuration, beside the GPU's time for it.
    pub reference: Option<ReferenceTiming>,
    /// With `--physics`: the radiative-transfer reference and the dipole's error against it.
    pub physics: Option<physics::Physics>,
}

/// The GPU against the f64 CPU reference (`reference::splat` then `reference::gather`, the same
/// discrete sum in f64 with rayon) on one configuration, timed in the same run.
#[derive(Clone, Debug)]
pub struct ReferenceTiming {
    /// Which configuration (index into `Study::rows`, its first seed).
    pub row: usize,
    /// Median wall time of the reference's splat and gather, ms (three runs).
    pub cpu_ms: f64,
    /// CPU threads the reference ran on.
    pub threads: usize,
}

/// Time the f64 reference on the swept configuration closest to the scene's own (its sampler
/// and count if swept, with the vertex gather), so the GPU's speed-up is measured in one run.
fn time_reference(base: &PreparedScene, rows: &[Row]) -> Result<Option<ReferenceTiming>, StudyError> {
    let own = &base.scene.file.sampling;
    let own_count = base.objects.iter().find(|o| !o.samples.is_empty()).map(|o| o.samples.len());
    let vertex_rows = || rows.iter().enumerate().filter(|(_, r)| r.gather == GatherMode::Vertex.name());
    let pick = vertex_rows()
        .find(|(_, r)| r.sampler == own.method.name() && Some(r.samples) == own_count)
        .or_else(|| vertex_rows().next());
    let Some((row, r)) = pick else { return Ok(None) };
    // The scene's own row stays when `--samplers` leaves its sampler out, so look among all.
    let Some(&method) = Method::ALL.iter().find(|m| m.name() == r.sampler) else { return Ok(None) };
    let run =
        Configuration { method, count: r.samples, seed: r.seed, gather: (GatherMode::Vertex, None), own: r.default };
    let (scene, _) = configure(base, run)?;
    let occluders = crate::reference::occluders(&scene);
    let mut times = Vec::new();
    for _ in 0..3 {
        let start = std::time::Instant::now();
        let irradiance = crate::reference::splat(&scene, &occluders);
        std::hint::black_box(crate::reference::gather(&scene, &irradiance));
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    Ok(Some(ReferenceTiming { row, cpu_ms: median(times), threads: rayon::current_num_threads() }))
}

/// The scene for one configuration: `base` (prepared once, geometry and lights) with new
/// samples, the gather set, every channel gathered. Returns it and the sampling time (ms).
fn configure(base: &PreparedScene, run: Configuration) -> Result<(PreparedScene, f64), StudyError> {
    let Configuration { method, count, seed, gather, own } = run;
    let mut scene = base.clone();
    let file = &mut scene.scene.file;
    file.render.gather = gather.0;
    if let Some(e) = gather.1 {
        file.render.gather_epsilon = e;
    }
    file.render.transport = TransportMode::Gather;
    if gather.0 == GatherMode::Texture && !own {
        return configure_texture(scene, count, gather.1);
    }
    if own {
        // The samples as the scene's error target placed them (their time is the scene's).
        return Ok((scene, f64::NAN));
    }
    file.sampling.method = method;
    file.sampling.count = Some(count);
    file.sampling.seed = seed;
    let start = std::time::Instant::now();
    for (i, o) in scene.objects.iter_mut().enumerate() {
        if let ResolvedMaterial::Translucent { dipoles, .. } = &o.material {
            o.density = o.density.as_ref().map(|d| d.given(dipoles, count));
            // The seed of object i is sampling.seed + i, as `PreparedScene::new` places them.
            let options = SampleOptions::new(method, count).with_seed(seed.wrapping_add(i as u64));
            o.samples = sampling::sample(&o.mesh, &options)
                .map_err(|source| StudyError::Sampling { object: o.name.clone(), source })?
                .points;
        }
    }
    Ok((scene, start.elapsed().as_secs_f64() * 1e3))
}

/// `scene` with the texture gather: `count` draws per receiver, every translucent object's
/// samples the texels of its atlas at `resolution` (default `render.texture_resolution`), and
/// the time the atlases took.
fn configure_texture(
    mut scene: PreparedScene,
    count: usize,
    resolution: Option<f32>,
) -> Result<(PreparedScene, f64), StudyError> {
    let render = &mut scene.scene.file.render;
    render.texture_samples = count as u32;
    render.texture_resolution = resolution.map_or(render.texture_resolution, |r| r as u32);
    let resolution = render.texture_resolution;
    let start = std::time::Instant::now();
    for o in &mut scene.objects {
        if matches!(o.material, ResolvedMaterial::Translucent { .. }) {
            o.place_texels(resolution).map_err(|source| StudyError::Atlas { object: o.name.clone(), source })?;
        }
    }
    Ok((scene, start.elapsed().as_secs_f64() * 1e3))
}

/// The error model's prediction for `scene` as configured, per channel (of the object whose
/// worst channel is predicted worst): NaN where it makes none (it was fitted to Turk's samples
/// at the vertices).
fn predicted(scene: &PreparedScene, method: Method, gather: GatherMode) -> [f64; 3] {
    let none = [f64::NAN; 3];
    if method != Method::Turk || matches!(gather, GatherMode::Pixel | GatherMode::Texture) {
        return none;
    }
    scene
        .objects
        .iter()
        .filter_map(|o| o.density.as_ref())
        .map(|d| d.predicted.map(|c| c.error))
        .max_by(|a, b| report::worst(a).total_cmp(&report::worst(b)))
        .unwrap_or(none)
}

fn images(renderer: &Renderer) -> Result<Images, StudyError> {
    let scene = renderer.scene();
    let [w, h] = scene.scene.file.camera.resolution;
    Ok(Images { size: [w, h], ldr: renderer.image()?.0, hdr: renderer.hdr_image()? })
}

fn median(mut v: Vec<f64>) -> f64 {
    crate::gpu::median(&mut v)
}

/// Run the study of `scene` on `gpu`: the truth (from `truth_dir` if cached there), its image,
/// then every configuration of `config`. `progress` hears of each step.
pub fn run(
    gpu: &Arc<Gpu>,
    scene: &Scene,
    config: &StudyConfig,
    truth_dir: &Path,
    progress: &(dyn Fn(Event) + Sync),
) -> Result<Study, StudyError> {
    // Every vertex is measured: whole meshes.
    let overrides = Overrides {
        transport: Some(TransportMode::Gather),
        gather: Some(GatherMode::Vertex),
        level_of_detail: Some(false),
        ..Overrides::default()
    };
    let base = PreparedScene::new(scene, &overrides)?;
    if !base.has_translucent() {
        return Err(StudyError::NothingTranslucent);
    }
    let (dipole, truth_cached) =
        truth::cached(&base, &config.truth, truth_dir, &|l, d, n| progress(Event::Truth(l, d, n)))?;
    if truth_cached {
        progress(Event::TruthCached);
    }
    if !dipole.exitance.iter().flatten().flatten().any(|&m| m > 0.0) {
        return Err(StudyError::NothingLit);
    }
    // Each model renders against its own exact exitance: a kernel scales the dipole's, and
    // single scattering between points replaces it in the channels that take it.
    let forced: Vec<Option<crate::scene::ScatteringModel>> = match config.render_models.as_slice() {
        [] => vec![None],
        list => list.iter().copied().map(Some).collect(),
    };
    let single = models::BetweenPoints::new(&base, progress);
    let models = models::prepare(&base, &forced, (&dipole, &single), truth_dir, progress)?;
    let first = (models[0].base.clone(), models[0].truth.clone());
    let physics = match &config.physics {
        Some(options) => {
            let (base, truth) = (&first.0, &first.1);
            let own = (truth, dipole.exitance.as_slice(), &single);
            Some(physics::Physics::measure(base, own, options, &config.models, truth_dir, progress)?)
        }
        None => None,
    };
    let (base, truth) = first;
    progress(Event::Step(Step::TruthImage));
    let images = models.iter().map(|m| truth_image(gpu, &m.base, &m.truth)).collect::<Result<Vec<_>, _>>()?;
    let (mut rows, mut exitances) = (Vec::new(), Vec::new());
    let total = config.runs();
    for (model, image) in models.iter().zip(&images) {
        let bench = Bench {
            gpu,
            model,
            frames: config.frames,
            truth_image: image.as_ref(),
            scene: &scene.name,
            physics: physics.as_ref(),
            model_error: physics.as_ref().map(|p| vertex_error_f64(&p.exitance, &model.truth.exitance).rel_rms),
        };
        let own = config.own.then(|| own_configuration(&model.base));
        for run in own.into_iter().chain(config.configurations()) {
            let prefix = if model.name().is_empty() { String::new() } else { format!("{}: ", model.name()) };
            progress(Event::Run(rows.len(), total, prefix + &run.label()));
            let (row, exitance) = bench.measure(run)?;
            rows.push(row);
            exitances.push(exitance);
        }
    }
    let reference = time_reference(&base, &rows)?;
    let truth_image = images.into_iter().next().flatten();
    Ok(Study { rows, truth, truth_cached, truth_image, prepared: base, exitance: exitances, reference, physics })
}

/// The truth's image: a full frame for shadows and sky, then the exact exitance shaded. A
/// truth at a subset of the vertices has no image (the others are unknown), so no image error.
fn truth_image(gpu: &Arc<Gpu>, base: &PreparedScene, truth: &Truth) -> Result<Option<Images>, StudyError> {
    if truth.subset.is_some() {
        return Ok(None);
    }
    let mut renderer = Renderer::new(gpu, base.clone())?;
    renderer.frame(&renderer.plan(Change::Everything))?;
    for (i, m) in truth.exitance.iter().enumerate() {
        if matches!(base.objects[i].material, ResolvedMaterial::Translucent { .. }) {
            let values: Vec<[f32; 3]> = m.iter().map(|v| v.map(|x| x as f32)).collect();
            renderer.set_exitance(i, &values)?;
        }
    }
    renderer.frame(&renderer.plan(Change::Camera))?;
    Ok(Some(images(&renderer)?))
}

/// Per-vertex exitance of every object, in scene order.
type Exitance = Vec<Vec<[f32; 3]>>;

/// One configuration of the sweep, or the scene's own.
#[derive(Clone, Copy, Debug)]
struct Configuration {
    method: Method,
    /// Samples per object (the scene's own row keeps each object's own count).
    count: usize,
    seed: u64,
    /// The gather, with the hierarchical gather's epsilon.
    gather: (GatherMode, Option<f32>),
    /// The scene's own configuration: its samples as placed, its own gather.
    own: bool,
}

/// The scene's own configuration: `base`'s samples as its error target placed them, and the
/// gather its own settings give them (`scene::build::own_gather`).
fn own_configuration(base: &PreparedScene) -> Configuration {
    let file = &base.scene.file;
    let (gather, epsilon) = crate::scene::build::own_gather(&file.render, &base.objects);
    let count = base.objects.iter().map(|o| o.samples.len()).max().unwrap_or(0);
    Configuration {
        method: file.sampling.method,
        count,
        seed: file.sampling.seed,
        gather: (gather, (gather == GatherMode::Hierarchical).then_some(epsilon)),
        own: true,
    }
}

impl Configuration {
    /// For the progress bar: `turk 400 hierarchical eps 0.1 seed 1`.
    fn label(&self) -> String {
        format!(
            "{}{} {} {}{} seed {}",
            if self.own { "default: " } else { "" },
            self.method,
            self.count,
            self.gather.0.name(),
            self.gather.1.map_or(String::new(), |e| match self.gather.0 {
                GatherMode::Texture => format!(" atlas {e}"),
                _ => format!(" eps {e}"),
            }),
            self.seed
        )
    }
}

/// What every configuration of a study is measured with and against.
struct Bench<'a> {
    gpu: &'a Arc<Gpu>,
    /// The model rendered: the scene prepared once under it (geometry, lights and kernels; each
    /// configuration resamples it) and its exact exitance.
    model: &'a models::RenderModel,
    /// Timed frames per configuration (`StudyConfig::frames`).
    frames: usize,
    /// The truth's image, for the model whose truth it shades.
    truth_image: Option<&'a Images>,
    /// The scene's name, for the rows.
    scene: &'a str,
    /// With `--physics`: the radiative-transfer reference, for the model and total errors.
    physics: Option<&'a physics::Physics>,
    /// With `--physics`: the model's exact exitance against the reference, per channel.
    model_error: Option<[f64; 3]>,
}

impl Bench<'_> {
    /// Render configuration `run`, compare it with the truth (per vertex unless it is the pixel
    /// gather, and as an image where the truth has one) and time a moving light's frame: its
    /// row, and its per-vertex exitance for `--error-image`.
    fn measure(&self, run: Configuration) -> Result<(Row, Option<Exitance>), StudyError> {
        let Configuration { method, count, seed, gather, own } = run;
        let (base, truth) = (&self.model.base, &self.model.truth);
        let (prepared, sampling_ms) = configure(base, run)?;
        let predicted = predicted(&prepared, method, gather.0);
        let mut renderer = Renderer::new(self.gpu, prepared)?;
        renderer.frame(&renderer.plan(Change::Everything))?;
        let exitance = if gather.0 == GatherMode::Pixel {
            None
        } else {
            Some((0..base.objects.len()).map(|i| renderer.exitance(i)).collect::<Result<Vec<_>, _>>()?)
        };
        let image = images(&renderer)?;
        // A moving light's frame: splat, gather and shade (the study's subject), each pass in a
        // submission of its own (`frame_isolated`).
        let plan = renderer.plan(Change::Lights);
        renderer.frame_isolated(&plan)?;
        let mut timings = Vec::new();
        for _ in 0..self.frames.max(1) {
            timings.push(renderer.frame_isolated(&plan)?);
        }
        let pass = |p: Pass| median(timings.iter().map(|t| t.get(p).unwrap_or(0.0)).collect());
        let error = exitance.as_ref().map(|e| vertex_error(&truth.exitance, e));
        let nan = [f64::NAN; 3];
        let total = self.physics.zip(exitance.as_ref()).map(|(p, e)| vertex_error(&p.exitance, e));
        let row = Row {
            scene: self.scene.to_string(),
            model: self.model.name().to_string(),
            precompute_s: self.model.precompute_s,
            default: own,
            predicted,
            sampler: if gather.0 == GatherMode::Texture { "atlas" } else { method.name() }.to_string(),
            samples: count,
            gather: gather.0.name().to_string(),
            epsilon: gather.1.map(f64::from),
            seed,
            sampling_ms,
            splat_ms: pass(Pass::Splat),
            gather_ms: pass(Pass::Gather),
            shade_ms: pass(Pass::Shade),
            frame_ms: median(timings.iter().map(|t| t.total()).collect()),
            device_mib: renderer.device_memory() as f64 / (1024.0 * 1024.0),
            rel_rms: error.map_or(nan, |e| e.rel_rms),
            p99: error.map_or(nan, |e| e.p99),
            max: error.map_or(nan, |e| e.max),
            bias: error.map_or(nan, |e| e.bias),
            model_rel_rms: self.model_error.unwrap_or(nan),
            total_rel_rms: total.map_or(nan, |e| e.rel_rms),
            rte_noise: self.physics.map_or(nan, |p| p.noise),
            image_rel_rmse: self.truth_image.map_or(f64::NAN, |t| image_rel_rmse(&t.hdr, &image.hdr)),
            flip_mean: match self.truth_image {
                Some(t) => flip::flip_mean(&t.ldr, &image.ldr, image.size[0], image.size[1])?,
                None => f64::NAN,
            },
        };
        Ok((row, exitance))
    }
}

/// Width of the strip beside the model that holds the error image's legend, pixels.
pub const LEGEND_STRIP: u32 = 120;

/// A false-colour picture of per-vertex relative error `|M - M_true| / M_true` drawn on the
/// model from the scene's camera, `0` to `scale` mapped through `raster::colormap`; dark
/// receivers (under [`LIT_FLOOR`]) are grey. RGBA8 of the camera's resolution with a white
/// strip of [`LEGEND_STRIP`] pixels on the right for the legend (so the legend never covers
/// the model); returns the pixels and the image's width.
pub fn error_image(
    scene: &PreparedScene,
    truth: &[Vec<[f64; 3]>],
    estimate: &[Vec<[f32; 3]>],
    scale: f64,
) -> Result<(Vec<u8>, u32), plot::PlotError> {
    let [w, h] = scene.scene.file.camera.resolution;
    let camera = crate::render::camera::CameraView::of_scene(scene);
    let view_proj = camera.projection * camera.view;
    let (mut positions, mut triangles, mut colours) = (Vec::new(), Vec::new(), Vec::new());
    for (i, o) in scene.objects.iter().enumerate() {
        let first = positions.len() as u32;
        positions.extend(o.mesh.positions().iter().map(|p| p.to_array()));
        triangles.extend(o.mesh.triangles().iter().map(|t| t.map(|v| v + first)));
        let translucent = matches!(o.material, ResolvedMaterial::Translucent { .. });
        let floor = [0, 1, 2].map(|c| LIT_FLOOR * truth[i].iter().map(|m| m[c]).fold(0.0, f64::max));
        for (v, t) in truth[i].iter().enumerate() {
            let lit: Vec<usize> = (0..3).filter(|&c| t[c] > 0.0 && t[c] >= floor[c]).collect();
            colours.push(if !translucent {
                [0.15, 0.15, 0.15]
            } else if lit.is_empty() {
                [0.45, 0.45, 0.45]
            } else {
                // The worst lit channel: where any colour is wrong shows.
                let e = lit.iter().map(|&c| ((f64::from(estimate[i][v][c]) - t[c]) / t[c]).abs()).fold(0.0, f64::max);
                raster::colormap((e / scale) as f32)
            });
        }
    }
    let model = raster::rasterise(&positions, &triangles, &colours, view_proj, w, h, [255, 255, 255]);
    let labels = ["0".to_string(), format!("{:.2}%", 50.0 * scale), format!(">= {:.2}%", 100.0 * scale)];
    // The legend needs some height (80 pixels); a flatter image goes without.
    if h < 80 {
        return Ok((model, w));
    }
    let width = w + LEGEND_STRIP;
    let mut rgba = vec![255u8; width as usize * h as usize * 4];
    for (dst, src) in rgba.chunks_exact_mut(width as usize * 4).zip(model.chunks_exact(w as usize * 4)) {
        dst[..src.len()].copy_from_slice(src);
    }
    raster::legend_bar(&mut rgba, width, h, [&labels[0], &labels[1], &labels[2]])?;
    Ok((rgba, width))
}
