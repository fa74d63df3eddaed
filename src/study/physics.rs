//! The study's error split against the physics (`study --physics`).
//!
//! The study measures the renderer against the exact integral of the dipole model
//! (`reference::truth`): the discretisation error. With `--physics` it also walks the radiative
//! transfer equation inside each translucent mesh (`reference::rte_mesh`, cached by content as
//! `reference::rte_cache`) and measures, per channel and as a relative RMS over the vertices
//! lit in the reference:
//!
//! - the model error, the dipole's exact integral against the RTE (the same for every row);
//! - the total error, the renderer against the RTE.
//!
//! Beside the dipole it measures other models' exact exitance against the same reference
//! ([`Physics::alternatives`]: single scattering added or alone, and the directional dipole of
//! Frisvad et al. 2014 in three variants), and every model's error per band of incidence at the
//! vertex ([`Physics::bands`], [`BANDS`]).
//!
//! The reference has its own noise: a relative standard error per vertex. Against a noisy
//! reference an RMS error reads `sqrt(e^2 + s^2)` on average, with `s` the RMS relative
//! standard error ([`Physics::noise`]); the report prints `s` beside every figure and the
//! model error with it taken out in quadrature (`sqrt(max(e^2 - s^2, 0))`).
//!
//! Past the sample count where the discretisation error falls below the model's error, more
//! samples stop paying: the picture is then as far from the physics whatever the count.
//! [`crossovers`] finds that count per curve and channel.

use super::report::{Row, curve_gather, md_cell, percent, sampler_label};
use super::{Event, StudyError, VertexError, vertex_error_f64};
use crate::reference::rte_cache;
use crate::reference::rte_mesh::{MeshOptions, ModelEntry};
use crate::reference::truth::{LIT_FLOOR, Truth};
use crate::scene::build::PreparedScene;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

/// The radiative-transfer reference of a study's scene and the dipole's error against it.
#[derive(Clone, Debug)]
pub struct Physics {
    /// Per object, per vertex, RGB exitance by Monte Carlo (zero for an opaque object).
    pub exitance: Vec<Vec<[f64; 3]>>,
    /// Its standard error, alike.
    pub stderr: Vec<Vec<[f64; 3]>>,
    /// The model error: the dipole truth against the reference, per channel.
    pub model: VertexError,
    /// Per channel, the reference's noise: the RMS over lit vertices (at least `LIT_FLOOR` of
    /// the object's brightest) of its relative standard error.
    pub noise: [f64; 3],
    /// Photons walked, over every object.
    pub photons: u64,
    /// Wall time of the walk (when it was walked, not read), seconds, over every object.
    pub seconds: f64,
    /// The worst object's precision (`rte_mesh::ObjectExitance::relative_stderr`).
    pub relative_stderr: f64,
    /// Walks dropped because they met the surface from outside, per channel.
    pub lost: [u64; 3],
    /// Whether it came from the cache.
    pub cached: bool,
    /// The scene's own model, which the truth is the exact integral of: "dipole", or "dipole
    /// scaled by its transport kernel" where a material takes the kernel (the study then scales
    /// the dipole's integral by the kernel in f64, `transport_cache::model_exitance`), or single
    /// scattering between points in its low-albedo channels alone (`own_model_name`).
    pub model_name: &'static str,
    /// The budget and seed it was walked with.
    pub options: MeshOptions,
    /// Other models against the same reference, per channel: the dipole with the
    /// single-scattering exitance added (`reference::single`, Jensen et al. 2001's sum of the
    /// two terms), single scattering alone (what leaves a dark medium: nearly all of it), and
    /// the directional dipole of Frisvad et al. 2014 (`reference::directional`) in three
    /// variants: the diffusion coefficient `1/(3 sigma_t')`, Grosjean's, and the source scaled by
    /// `alpha'` (`optics::directional_dipole::Strength`).
    pub alternatives: Vec<(String, VertexError)>,
    /// Per model (the dipole first, then the alternatives, in order) and band of incidence
    /// ([`BANDS`]): the error over the lit vertices whose normal has a cosine to the first light
    /// in that band.
    pub bands: Vec<(String, Vec<VertexError>)>,
    /// Per band of [`BANDS`], the reference's own noise there ([`band_noise`]): the dim bands'
    /// errors are read against it.
    pub band_noise: Vec<[f64; 3]>,
}

/// The bands of `cos(normal, first light)` the models' errors are split by: the facing side,
/// towards the terminator, at it, and the far side (lit through the object only).
pub const BANDS: [(f64, f64, &str); 4] =
    [(0.5, 1.01, "cos > 0.5"), (0.2, 0.5, "0.2 to 0.5"), (0.0, 0.2, "0 to 0.2"), (-1.01, 0.0, "cos < 0 (unlit side)")];

impl Physics {
    /// The reference of `base` (from the cache folder `dir` if walked before, else walked and
    /// stored there) and the model error of `truth`, the exact exitance of the model `base`
    /// takes, against it; `dipole` is the dipole's exact integral, which the alternative models
    /// start from. `progress` hears of the walk.
    pub fn measure(
        base: &PreparedScene,
        (truth, dipole, single): (&Truth, &[Exitance], &super::models::BetweenPoints<'_>),
        options: &MeshOptions,
        models: &[Model],
        dir: &Path,
        progress: &(dyn Fn(Event) + Sync),
    ) -> Result<Physics, StudyError> {
        let options = &options.resolved(base);
        let (reference, cached) = rte_cache::cached(base, options, dir, &|p| progress(Event::Rte(p)))?;
        if cached {
            progress(Event::RteCached);
        }
        let (mut exitance, mut stderr) = (Vec::new(), Vec::new());
        let (mut photons, mut seconds, mut relative_stderr, mut lost) = (0, 0.0, 0.0f64, [0; 3]);
        for (o, object) in reference.objects.iter().zip(&base.objects) {
            let zero = vec![[0.0; 3]; object.mesh.positions().len()];
            match o {
                Some(o) => {
                    let (m, s) = o.per_vertex(object.mesh.positions().len());
                    exitance.push(m);
                    stderr.push(s);
                    photons += o.photons;
                    seconds += o.seconds;
                    relative_stderr = relative_stderr.max(o.relative_stderr);
                    (0..3).for_each(|c| lost[c] += o.lost[c]);
                }
                None => {
                    exitance.push(zero.clone());
                    stderr.push(zero);
                }
            }
        }
        let model = vertex_error_f64(&exitance, &truth.exitance);
        let noise = noise(&exitance, &stderr);
        let walks = reference.objects.iter().flatten().map(|o| o.photons).max().unwrap_or(1);
        let model_name = own_model_name(base, &truth.exitance, dipole);
        let own = (model_name, truth.exitance.as_slice(), dipole, single);
        let models = alternative_models(base, own, models, (options, walks), dir, progress)?;
        let alternatives =
            models.iter().skip(1).map(|(name, m)| (name.clone(), vertex_error_f64(&exitance, m))).collect();
        let cosines = light_cosines(base);
        let bands = models.iter().map(|(name, m)| (name.clone(), band_errors(&exitance, m, &cosines))).collect();
        let band_noise = band_noise(&exitance, &stderr, &cosines);
        Ok(Physics {
            model_name,
            exitance,
            stderr,
            model,
            noise,
            photons,
            seconds,
            relative_stderr,
            lost,
            cached,
            options: *options,
            alternatives,
            bands,
            band_noise,
        })
    }
}

/// A model measured beside the dipole against the same reference (`study --physics --models`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Model {
    /// Single scattering between points (`reference::single::between_points`).
    Between,
    /// Per channel: single scattering between points under `beam_single::ALBEDO_BELOW`, else
    /// the dipole.
    PerChannel,
    /// The dipole with the single-scattering exitance added (Jensen et al. 2001's sum).
    DipoleSingle,
    /// Single scattering alone (what leaves a dark medium: nearly all of it).
    Single,
    /// The directional dipole of Frisvad et al. 2014, `D = 1/(3 sigma_t')`.
    Directional,
    /// The directional dipole with Grosjean's `D`.
    DirectionalGrosjean,
    /// The directional dipole with Grosjean's `D` and the source scaled by `alpha'`.
    DirectionalAlpha,
    /// The radiative transfer in the mesh with the light entering along the normal
    /// (`rte_mesh::model_exitance`, `ModelEntry::Normal`): what a transport kernel precomputed without the
    /// lights converges to. Walked by the reference's own walks, so its gap to the reference
    /// is measured through their shared noise.
    Transport,
    /// As [`Model::Transport`], the light attenuated with depth as the refracted beam is: the
    /// limit of kernels precomputed at a few entry cosines (`rte_mesh::ModelEntry::Slanted`).
    TransportSlanted,
    /// What `material.model = "transport"` renders: per channel, single scattering between
    /// points under `beam_single::ALBEDO_BELOW`, else the dipole scaled per patch by a
    /// transport kernel between patches walked without the lights (`rte_mesh::kernel`).
    Kernel,
}

impl Model {
    /// Every model, in the report's order.
    pub const ALL: [Model; 10] = [
        Model::Between,
        Model::PerChannel,
        Model::DipoleSingle,
        Model::Single,
        Model::Directional,
        Model::DirectionalGrosjean,
        Model::DirectionalAlpha,
        Model::Transport,
        Model::TransportSlanted,
        Model::Kernel,
    ];

    /// Its name on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Model::Between => "between",
            Model::PerChannel => "per-channel",
            Model::DipoleSingle => "dipole+single",
            Model::Single => "single",
            Model::Directional => "directional",
            Model::DirectionalGrosjean => "directional-grosjean",
            Model::DirectionalAlpha => "directional-alpha",
            Model::Transport => "transport",
            Model::TransportSlanted => "transport-slanted",
            Model::Kernel => "kernel",
        }
    }

    /// Its name in the report.
    fn label(self) -> String {
        use crate::optics::beam_single::ALBEDO_BELOW;
        match self {
            Model::Between => "single scattering between points".into(),
            Model::PerChannel => format!("per channel: between points under albedo {ALBEDO_BELOW}, else dipole"),
            Model::DipoleSingle => "dipole + single scattering".into(),
            Model::Single => "single scattering alone".into(),
            Model::Directional => "directional dipole, D = 1/(3 sigma_t')".into(),
            Model::DirectionalGrosjean => "directional dipole, Grosjean's D".into(),
            Model::DirectionalAlpha => "directional dipole, Grosjean's D, source alpha'".into(),
            Model::Transport => "transport in the mesh, light entering along the normal".into(),
            Model::TransportSlanted => "transport in the mesh, along the normal at the refracted depth".into(),
            Model::Kernel => {
                format!("transport kernel (dipole scaled per patch; between points under albedo {ALBEDO_BELOW})")
            }
        }
    }
}

impl std::str::FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Model, String> {
        Model::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<&str> = Model::ALL.iter().map(|m| m.name()).collect();
            format!("unknown model {s:?}: one of {}", names.join(", "))
        })
    }
}

/// Every model's exitance per object and vertex, named: the scene's own model first (`own`,
/// named `own_name`), then the dipole's exact integral where the scene's model is another, then
/// those of `models` (see [`Model`]), each computed only if asked for (the directional dipole's
/// integral over a large mesh takes many minutes). Every alternative starts from the dipole's
/// integral, never from the scene's model: a kernel is applied once.
fn alternative_models(
    base: &PreparedScene,
    (own_name, own, truth, between): (&str, &[Exitance], &[Exitance], &super::models::BetweenPoints<'_>),
    models: &[Model],
    reference: (&MeshOptions, u64),
    dir: &Path,
    progress: &(dyn Fn(Event) + Sync),
) -> Result<Vec<(String, Vec<Exitance>)>, StudyError> {
    use crate::optics::directional_dipole::{Diffusion, Strength};
    use crate::reference::directional;
    let fineness = directional::FINENESS;
    let single = || crate::reference::single::exitance(base);
    let variant = |d, s| directional::exitance_with(base, d, s, fineness, None);
    let mut out = vec![(own_name.to_string(), own.to_vec())];
    if !same_exitance(own, truth) {
        out.push(("dipole".to_string(), truth.to_vec()));
    }
    for &m in models {
        progress(Event::Step(super::Step::Model(m)));
        let exitance = match m {
            Model::Between => between.get().to_vec(),
            Model::PerChannel => per_channel_choice(base, truth, between.get()),
            Model::DipoleSingle => truth
                .iter()
                .zip(&single())
                .map(|(t, s)| t.iter().zip(s).map(|(t, s)| [0, 1, 2].map(|c| t[c] + s[c])).collect())
                .collect(),
            Model::Single => single(),
            Model::Directional => variant(Diffusion::Classical, Strength::Paper),
            Model::DirectionalGrosjean => variant(Diffusion::Grosjean, Strength::Paper),
            Model::DirectionalAlpha => variant(Diffusion::Grosjean, Strength::ReducedAlbedo),
            Model::Transport => transport(base, reference, ModelEntry::Normal)?,
            Model::TransportSlanted => transport(base, reference, ModelEntry::Slanted)?,
            Model::Kernel => {
                let walk = |o: usize, done, of| progress(Event::Kernel(base.objects[o].name.clone(), done, of));
                let scaled = crate::reference::transport_cache::model_exitance(base, truth, dir, &walk)?;
                with_single_between_points(base, scaled, between)
            }
        };
        out.push((m.label(), exitance));
    }
    Ok(out)
}

/// What the scene's own model is called in the report, from its exact exitance `own` and the
/// dipole's integral.
fn own_model_name(base: &PreparedScene, own: &[Exitance], dipole: &[Exitance]) -> &'static str {
    if same_exitance(own, dipole) {
        "dipole"
    } else if base.objects.iter().any(|o| o.wants_transport()) {
        "dipole scaled by its transport kernel"
    } else {
        "the scene's model per channel (between points under albedo 0.3, else the dipole)"
    }
}

/// Whether two exitances are the same to the bit (NaN off a truth's receivers included).
fn same_exitance(a: &[Exitance], b: &[Exitance]) -> bool {
    let bits = |e: &[Exitance]| e.iter().flatten().flatten().map(|m| m.to_bits()).collect::<Vec<_>>();
    a.len() == b.len() && a.iter().zip(b).all(|(a, b)| a.len() == b.len()) && bits(a) == bits(b)
}

/// [`Model::Transport`]'s exitance per vertex (NaN off the receivers). Behind an adjoint
/// reference it is walked with the reference's options and walk count, so by the same walks
/// even where the reference was stopped by time or precision; behind a photon reference, by
/// the adjoint walk at every vertex under the reference's budget, with noise of its own.
fn transport(
    base: &PreparedScene,
    (options, walks): (&MeshOptions, u64),
    entry: ModelEntry,
) -> Result<Vec<Exitance>, StudyError> {
    use crate::reference::rte::Budget;
    use crate::reference::rte_mesh::Walk;
    let options = match options.walk {
        Walk::Adjoint { .. } => MeshOptions { budget: Budget::photons(walks.max(1)), ..*options },
        _ => *options,
    };
    let objects = crate::reference::rte_mesh::model_exitance(base, &options, entry, &|_| {})
        .map_err(|e| StudyError::Rte(crate::reference::rte_cache::RteCacheError::Rte(e)))?;
    Ok(objects
        .iter()
        .zip(&base.objects)
        .map(|(o, object)| {
            let count = object.mesh.positions().len();
            o.as_ref().map_or_else(|| vec![[0.0; 3]; count], |o| o.per_vertex(count).0)
        })
        .collect())
}

/// `exitance` with single scattering between points in the channels whose reduced albedo is
/// under `optics::beam_single::ALBEDO_BELOW`, as `material.model = "transport"` renders them
/// (`between` read only where a channel takes it).
pub fn with_single_between_points(
    base: &PreparedScene,
    exitance: Vec<Exitance>,
    between: &super::models::BetweenPoints<'_>,
) -> Vec<Exitance> {
    if !base.objects.iter().any(|o| low_albedo(&o.material).contains(&true)) {
        return exitance;
    }
    per_channel_choice(base, &exitance, between.get())
}

/// Per object, vertex and channel: `single` where the channel's reduced albedo is under
/// `optics::beam_single::ALBEDO_BELOW`, else the dipole's `truth`.
fn per_channel_choice(base: &PreparedScene, truth: &[Exitance], single: &[Exitance]) -> Vec<Exitance> {
    let rows = base.objects.iter().zip(truth.iter().zip(single));
    rows.map(|(o, (t, s))| {
        let once = low_albedo(&o.material);
        t.iter().zip(s).map(|(t, s)| [0, 1, 2].map(|c| if once[c] { s[c] } else { t[c] })).collect()
    })
    .collect()
}

/// Per channel, whether its reduced albedo is under `optics::beam_single::ALBEDO_BELOW`.
fn low_albedo(material: &crate::scene::build::ResolvedMaterial) -> [bool; 3] {
    use crate::scene::build::ResolvedMaterial;
    match material {
        ResolvedMaterial::Translucent { dipoles, .. } => {
            dipoles.map(|d| d.alpha_prime < crate::optics::beam_single::ALBEDO_BELOW)
        }
        ResolvedMaterial::Opaque { .. } => [false; 3],
    }
}

/// Per object and vertex, the cosine between the vertex normal and the direction to the first
/// light (NaN without lights).
pub fn light_cosines(base: &PreparedScene) -> Vec<Vec<f64>> {
    base.objects
        .iter()
        .map(|o| {
            o.mesh
                .positions()
                .iter()
                .zip(o.mesh.vertex_normals())
                .map(|(p, n)| match base.lights.first() {
                    Some(l) => {
                        let (wi, ..) = crate::reference::light_incidence(l, p.as_dvec3());
                        n.as_dvec3().normalize().dot(wi)
                    }
                    None => f64::NAN,
                })
                .collect()
        })
        .collect()
}

/// One object's exitance per vertex.
type Exitance = Vec<[f64; 3]>;

/// [`vertex_error_f64`] of `estimate` against `reference` per band of [`BANDS`]: the lit floor
/// is the object's, as over all vertices; each band keeps the vertices whose cosine is in it.
pub fn band_errors(reference: &[Vec<[f64; 3]>], estimate: &[Vec<[f64; 3]>], cosines: &[Vec<f64>]) -> Vec<VertexError> {
    BANDS
        .iter()
        .map(|&(lo, hi, _)| {
            // Outside the band the reference reads 0 (unlit, so left out); the floor is kept
            // by a copy of the brightest vertex placed where no estimate is compared.
            let (r, e): (Vec<Exitance>, Vec<Exitance>) = reference
                .iter()
                .zip(estimate)
                .zip(cosines)
                .map(|((r, e), cos)| {
                    let brightest = [0, 1, 2].map(|c| r.iter().map(|v| v[c]).fold(0.0, f64::max));
                    let mut rr: Vec<[f64; 3]> =
                        r.iter().zip(cos).map(|(v, k)| if *k >= lo && *k < hi { *v } else { [0.0; 3] }).collect();
                    let mut ee = e.clone();
                    rr.push(brightest);
                    ee.push([f64::NAN; 3]);
                    (rr, ee)
                })
                .unzip();
            vertex_error_f64(&r, &e)
        })
        .collect()
}

/// Per channel, the RMS over the lit vertices of every object (at least [`LIT_FLOOR`] of the
/// object's brightest in that channel) of the relative standard error `stderr / exitance`.
pub fn noise(exitance: &[Vec<[f64; 3]>], stderr: &[Vec<[f64; 3]>]) -> [f64; 3] {
    noise_where(exitance, stderr, &|_, _| true)
}

/// Per band of [`BANDS`], [`noise`] over the lit vertices whose cosine to the first light is in
/// it (the lit floor stays the object's, as in [`band_errors`]).
pub fn band_noise(exitance: &[Vec<[f64; 3]>], stderr: &[Vec<[f64; 3]>], cosines: &[Vec<f64>]) -> Vec<[f64; 3]> {
    BANDS.iter().map(|&(lo, hi, _)| noise_where(exitance, stderr, &|o, v| (lo..hi).contains(&cosines[o][v]))).collect()
}

/// [`noise`] over the vertices `keep(object, vertex)` selects.
fn noise_where(exitance: &[Vec<[f64; 3]>], stderr: &[Vec<[f64; 3]>], keep: &dyn Fn(usize, usize) -> bool) -> [f64; 3] {
    [0, 1, 2].map(|c| {
        let (mut sum, mut n) = (0.0, 0usize);
        for (o, (m, s)) in exitance.iter().zip(stderr).enumerate() {
            let floor = LIT_FLOOR * m.iter().map(|v| v[c]).fold(0.0, f64::max);
            for (v, (mv, sv)) in m.iter().zip(s).enumerate() {
                if mv[c] > 0.0 && mv[c] >= floor && keep(o, v) {
                    sum += (sv[c] / mv[c]).powi(2);
                    n += 1;
                }
            }
        }
        if n == 0 { f64::NAN } else { (sum / n as f64).sqrt() }
    })
}

/// An RMS error measured against a reference of RMS relative noise `noise`, with the noise
/// taken out in quadrature: `sqrt(max(error^2 - noise^2, 0))`.
pub fn without_noise(error: f64, noise: f64) -> f64 {
    (error * error - noise * noise).max(0.0).sqrt()
}

/// Where one curve of the sweep (sampler and gather, every count) stops paying.
#[derive(Clone, Debug, PartialEq)]
pub struct Crossover {
    /// The curve: sampler and gather.
    pub curve: String,
    /// The curve's sample counts, in order.
    pub counts: Vec<usize>,
    /// Per channel: the smallest count of the curve from which on (at it and every larger count
    /// swept) the discretisation error, mean over seeds, is below the model error; `None` when
    /// even the largest count's is not.
    pub from: [Option<usize>; 3],
}

/// [`Crossover`] of every curve of the sweep's rows (the scene's own row is no curve) against
/// the per-channel `model` error.
pub fn crossovers(rows: &[Row], model: [f64; 3]) -> Vec<Crossover> {
    // curve -> count -> per-channel (sum, seeds)
    let mut curves: BTreeMap<String, BTreeMap<usize, ([f64; 3], usize)>> = BTreeMap::new();
    for r in rows.iter().filter(|r| !r.default && r.rel_rms.iter().all(|e| e.is_finite())) {
        let curve = format!("{} + {}", sampler_label(r), curve_gather(&r.gather, r.epsilon));
        let point = curves.entry(curve).or_default().entry(r.samples).or_insert(([0.0; 3], 0));
        (0..3).for_each(|c| point.0[c] += r.rel_rms[c]);
        point.1 += 1;
    }
    curves
        .into_iter()
        .map(|(curve, points)| {
            let counts: Vec<usize> = points.keys().copied().collect();
            let from = [0, 1, 2].map(|c| {
                let mut from = None;
                // From the largest count down, while the error stays below the model's.
                for (&n, (sum, seeds)) in points.iter().rev() {
                    if sum[c] / *seeds as f64 >= model[c] {
                        break;
                    }
                    from = Some(n);
                }
                from
            });
            Crossover { curve, counts, from }
        })
        .collect()
}

/// study.md's section on the split: the reference, the model error per channel, the split per
/// configuration and where more samples stop paying.
pub fn markdown(physics: &Physics, rows: &[Row]) -> String {
    let mut out = String::new();
    reference_paragraph(&mut out, physics);
    let _ = writeln!(out, "| channel | model error (RMS) | without the noise | model bias | reference noise |");
    let _ = writeln!(out, "|---|---:|---:|---:|---:|");
    for (c, name) in ["r", "g", "b"].iter().enumerate() {
        let m = &physics.model;
        let _ = writeln!(
            out,
            "| {name} | {} % | {} % | {:+.2} % | {} % |",
            percent(m.rel_rms[c]),
            percent(without_noise(m.rel_rms[c], physics.noise[c])),
            100.0 * m.bias[c],
            percent(physics.noise[c])
        );
    }
    alternatives_table(&mut out, physics);
    bands_table(&mut out, physics);
    // Per model rendered (`study --render-models`), each against its own exact exitance.
    for (name, rows) in super::models::by_model(rows) {
        if !name.is_empty() {
            let _ = writeln!(out, "\n### `material.model = \"{name}\"`");
        }
        split_table(&mut out, &rows);
        crossover_table(&mut out, &rows, rows.first().map_or(physics.model.rel_rms, |r| r.model_rel_rms));
    }
    out
}

/// Each model's exact exitance against the reference, per channel: RMS (bias).
fn alternatives_table(out: &mut String, p: &Physics) {
    let _ = writeln!(
        out,
        "\nThe models' exact exitance against the reference (relative RMS per vertex, mean bias in brackets; \
         single scattering: `reference::single`, the half-space term of Jensen et al. 2001 Eq. 3 at each \
         vertex; between points: `reference::single::between_points`, the same term resolved in space \
         along each refracted beam):\n"
    );
    let _ = writeln!(out, "| model | r | g | b |");
    let _ = writeln!(out, "|---|---:|---:|---:|");
    let models = std::iter::once((p.model_name, &p.model)).chain(p.alternatives.iter().map(|(n, e)| (n.as_str(), e)));
    for (name, e) in models {
        let cell = |c: usize| format!("{} % ({:+.1} %)", percent(e.rel_rms[c]), 100.0 * e.bias[c]);
        let _ = writeln!(out, "| {name} | {} | {} | {} |", cell(0), cell(1), cell(2));
    }
}

/// Each model's error per band of incidence at the vertex.
fn bands_table(out: &mut String, p: &Physics) {
    let _ = writeln!(
        out,
        "\nBy the cosine between the vertex normal and the first light (relative RMS per vertex, mean bias in \
         brackets, lit vertices counted in the band; `reference::directional` for the directional dipole):\n"
    );
    let _ = writeln!(out, "| model | band | vertices (r, g, b) | r | g | b |");
    let _ = writeln!(out, "|---|---|---|---:|---:|---:|");
    // The reference's own noise per band first: what no model's error there can go below.
    let lit = p.bands.first().map(|(_, bands)| bands.iter().map(|e| e.lit).collect::<Vec<_>>());
    for (i, (noise, (.., band))) in p.band_noise.iter().zip(BANDS).enumerate() {
        let lit = lit.as_ref().map_or(String::new(), |l| l[i].map(|n| n.to_string()).join(", "));
        let cells = noise.map(|n| format!("{} %", percent(n)));
        let _ = writeln!(out, "| reference noise | {band} | {lit} | {} |", cells.join(" | "));
    }
    for (name, bands) in &p.bands {
        for (e, (.., band)) in bands.iter().zip(BANDS) {
            let cells = [0, 1, 2].map(|c| format!("{} % ({:+.1} %)", percent(e.rel_rms[c]), 100.0 * e.bias[c]));
            let lit = e.lit.map(|n| n.to_string()).join(", ");
            let _ = writeln!(out, "| {name} | {band} | {lit} | {} |", cells.join(" | "));
        }
    }
}

/// What the reference is, how far it got and what it cost.
fn reference_paragraph(out: &mut String, p: &Physics) {
    use crate::reference::rte_mesh::Walk;
    let b = &p.options.budget;
    let (unit, walk, precision) = match p.options.walk {
        Walk::Photons | Walk::Auto { .. } => (
            "photons",
            "photons from the lights tallied in each vertex's cell, refracting at the flat faces \
             (`reference::rte_mesh`)"
                .to_string(),
            "RMS standard error over lit vertices / their mean",
        ),
        Walk::Adjoint { receivers } => (
            "walks per receiver",
            format!(
                "walks backwards from {} per object to the lights' beams, refracting with the shading \
                 normals (`rte_mesh::adjoint`)",
                receivers.map_or("every vertex".to_string(), |r| format!("at most {r} receivers"))
            ),
            "RMS over lit receivers of the relative standard error",
        ),
    };
    let model = p.model_name;
    let budget = [
        Some(format!("at most {} {unit}", b.max_photons)),
        b.relative_stderr.map(|s| format!("to {s} precision")),
        b.max_seconds.map(|s| format!("at most {s} s")),
    ]
    .into_iter()
    .flatten()
    .collect::<Vec<_>>()
    .join(", ");
    let _ = writeln!(
        out,
        "\n## Against the physics: model, discretisation and total error\n\n\
         Reference: the radiative transfer equation by Monte Carlo inside each translucent mesh, {walk} \
         (Fresnel transmittance in and out, isotropic scattering with `sigma_s = sigma_s'`; budget {budget} per object, seed {}): {} {unit}, {:.1} s when walked{}; \
         precision reached ({precision}, worst channel) {}, walks lost \
         {:?}. Model error: the {model}'s exact integral against it; discretisation error: the renderer \
         against that integral (the study's `rel_rms`); total error: the renderer against it. \
         Relative RMS over the vertices lit in the reference. The reference noise is the RMS of its relative \
         standard error per vertex, which every error against it contains in quadrature: an error \
         not well above it is noise.\n",
        p.options.seed,
        p.photons,
        p.seconds,
        if p.cached { ", read from the cache" } else { "" },
        crate::study::report::sig3(p.relative_stderr),
        p.lost
    );
}

/// Per configuration (seeds averaged), the three errors per channel.
fn split_table(out: &mut String, rows: &[Row]) {
    let _ = writeln!(out, "\nPer configuration (mean over seeds; r, g, b in %):\n");
    let _ = writeln!(out, "| configuration | discretisation | total |");
    let _ = writeln!(out, "|---|---|---|");
    let mut groups: BTreeMap<(String, usize), Vec<&Row>> = BTreeMap::new();
    for r in rows {
        let label = format!("{} + {}", sampler_label(r), curve_gather(&r.gather, r.epsilon));
        groups.entry((label, r.samples)).or_default().push(r);
    }
    for ((label, samples), group) in groups {
        let mean = |f: &dyn Fn(&Row) -> [f64; 3]| {
            [0, 1, 2].map(|c| group.iter().map(|r| f(r)[c]).sum::<f64>() / group.len() as f64)
        };
        let fmt = |v: [f64; 3]| v.map(percent).join(", ");
        let _ = writeln!(
            out,
            "| {} {samples} | {} | {} |",
            md_cell(&label),
            fmt(mean(&|r| r.rel_rms)),
            fmt(mean(&|r| r.total_rel_rms))
        );
    }
}

/// Per curve, the sample count from which the discretisation error is below the model's.
fn crossover_table(out: &mut String, rows: &[Row], model: [f64; 3]) {
    let _ = writeln!(
        out,
        "\nWhere more samples stop paying: per curve and channel, the sample count from which on (at it and at \
         every larger count swept) the discretisation error is below the model error ({} %, {} %, {} %). \
         \"<= N\": already at the smallest count swept; \"none\": not within the sweep.\n",
        percent(model[0]),
        percent(model[1]),
        percent(model[2])
    );
    let _ = writeln!(out, "| curve | counts swept | r | g | b |");
    let _ = writeln!(out, "|---|---|---:|---:|---:|");
    for x in crossovers(rows, model) {
        let smallest = x.counts.first().copied();
        let cell = |f: Option<usize>| match f {
            None => "none".to_string(),
            Some(n) if Some(n) == smallest => format!("<= {n}"),
            Some(n) => n.to_string(),
        };
        let counts = x.counts.iter().map(usize::to_string).collect::<Vec<_>>().join(", ");
        let from = x.from.map(cell).join(" | ");
        let _ = writeln!(out, "| {} | {counts} | {from} |", md_cell(&x.curve));
    }
}

#[cfg(test)]
mod tests;
