//! The ground truth of the accuracy study: the dipole model's exact answer, independent of the
//! renderer's sample points.
//!
//! At every vertex `x` of a translucent object, the radiant exitance of seed Eq. 10,
//!
//! ```text
//! M(x) = integral over the object's surface S of R_d(|x - y|) E_t(y) dA(y)
//! E_t(y) = sum over lights l of E_l cos_i F_t(cos_i, eta) V_l(y)
//! ```
//!
//! with `R_d` seed Eq. 8 (`Dipole::r_d`), the renderer's lights (the environment as its
//! median-cut directions), its shading normals (interpolated vertex normals) and exact
//! visibility by ray casting through a BVH of the shadow casters.
//!
//! # Quadrature
//!
//! Two approximations, both refined level by level until the answer stops changing:
//! - `E_t` is evaluated on a grid over each mesh triangle (the triangle split in `4^depth`
//!   cells) and taken as linear inside each cell. Every light is ray cast on the triangle's
//!   base grid; on finer grids only the lights whose shadow edge crosses it (reaching some base
//!   points, blocked at others) and those facing none of its base points. Where a strong light's edge crosses ([`STRONG_LIGHT`]) the grid
//!   is [`EDGE_EXTRA_DEPTH`] levels finer. (So a shadow narrower than the base grid that touches
//!   none of its points is missed at every level: the one assumption the levels cannot check.)
//!   This is the only place rays are cast, and it does not depend on the receiver. Each triangle keeps the exact flux and centroid of
//!   every coarser piece of its grid (a pyramid of moments).
//! - The kernel integral is adaptive per receiver: a piece of surface of radius `R` at distance
//!   `d` from `x` is fine enough when `2 R kappa <= eta_l` with
//!   `kappa = sigma_tr,max + 3 / sqrt(d^2 + z_r,min^2)`, the inverse length over which `R_d`
//!   changes there (its `1/d^3` flank near, its exponential far, its peak of width `z_r` at
//!   `d = 0`, so no singularity needs special treatment: `R_d` is finite at `r = 0`). The lit
//!   triangles sit in a binary tree of clusters: a cluster fine at `eta_l / 2` is one point at
//!   its `E_t`-weighted centroid plus its quadrupole (exact to third order), so far surface
//!   costs a receiver the log of the triangle count. A triangle that is not fine is split in
//!   four, recursively; a piece four times finer than `eta_l` is a monopole with its exact
//!   moments (from the pyramid while it spans several cells), one inside a grid cell that is
//!   merely fine takes Radon's 7-point degree-5 rule over the linear `E_t`.
//!
//! Level `l` uses grid depth `l` more than a triangle's base depth (set by how far its shading
//! normal turns, [`NORMAL_SPREAD`]) and `eta_l = 0.4 / 2^(l/2)`. The change between two levels,
//! relative, over lit receivers, estimates the coarser level's error; levels are added until
//! its RMS is under the tolerance (1e-4), and the finer level is kept. `Truth::levels` reports
//! every step, so a reader can see it converge.
//!
//! # Memory
//!
//! A level's grids grow four times a level, so they are not all held ([`store`]): a first pass
//! ray casts them all and keeps each triangle's summary (its moments as a whole), and within
//! three quarters of the memory limit its rays' verdicts or its whole grid; receivers then take
//! their far field from the summaries and integrate the triangles they need piece by piece,
//! those grids made again a chunk at a time. The result does not depend on the limit, bit for
//! bit; only a level whose floor (what grows with the mesh and the receivers, [`LevelMemory`])
//! is over the limit is refused.
//!
//! # Receivers
//!
//! On a large mesh the truth may be asked for at a subset of the vertices
//! ([`TruthOptions::receivers`]): the quadrature at each receiver does not depend on the
//! others (but for the threshold of what is negligible, set from the brightest receiver of the
//! subset), so a subset costs in proportion and its values are those of the full truth.
//! Vertices left out hold NaN ("not computed"), which every statistic over lit receivers skips.

mod cache;
mod caster;
mod clusters;
mod memory;
mod quadrature;
mod source;
mod store;

/// The vertices the truth is computed at (`scene::accuracy`, where occlusion picks them too).
pub use crate::scene::accuracy::receiver_subset;
pub use cache::FolderProblem;
pub(crate) use cache::{Fnv, folder_problem, read_cached, write_replacing};
pub use cache::{cached, content_key, default_cache_dir};
pub use memory::{
    DEFAULT_MEMORY_CAP, LevelMemory, MemoryLimitKind, available_memory, default_memory_limit, human_bytes,
    memory_estimate,
};

use super::{occluders, ray_offset};
use crate::mesh::bvh::Bvh;
use crate::scene::build::{PreparedScene, ResolvedMaterial};
use caster::{Caster, TrianglePlan, plans};
use memory::{Budget, check_memory};
use quadrature::exitance_at_vertices;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use store::Sources;

/// Relative RMS change between two levels, over lit receivers, under which the truth counts
/// as converged.
pub const TOLERANCE: f64 = 1e-4;
/// The finest level tried: past it the truth reports that it did not converge rather than run
/// for hours (each level costs about four times the one before).
pub const MAX_LEVEL: u32 = 5;
/// A receiver is lit in a channel when its exitance is at least this fraction of the object's
/// brightest in that channel; relative errors are taken over lit receivers only (a dark
/// receiver's relative error is noise over nothing).
pub const LIT_FLOOR: f64 = 0.01;
/// The most the shading normal may turn across one grid cell at level 0 (radians).
pub const NORMAL_SPREAD: f64 = 0.05;
/// Extra grid depth on triangles the shadow edge of a strong light crosses.
pub const EDGE_EXTRA_DEPTH: u32 = 2;
/// A light is strong, and its shadow edges refined [`EDGE_EXTRA_DEPTH`] levels more, when it
/// brings at least this fraction of all the lights' irradiance to the object. The weak ones (an
/// environment's many directions) are left to the levels' uniform refinement: refining every
/// triangle that any of 16 sky directions half-shadows would refine nearly all of them.
pub const STRONG_LIGHT: f64 = 0.1;
/// Bumped whenever the quadrature changes, so an old cache is not read as the truth.
pub const VERSION: u32 = 5;

/// One refinement level of the truth.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Level {
    /// 0, 1, 2, ...
    pub level: u32,
    /// The kernel quadrature's fineness (`2 R kappa <= eta`).
    pub eta: f64,
    /// Points at which `E_t` was ray cast, over every object.
    pub irradiance_points: usize,
    /// Relative change from the previous level, RMS over lit receivers (none on level 0,
    /// which has nothing to compare with).
    pub change_rms: Option<f64>,
    /// The largest relative change over lit receivers (none on level 0).
    pub change_max: Option<f64>,
    /// Wall time of this level, seconds.
    pub seconds: f64,
}

/// The exact exitance at every vertex, with the evidence that it converged.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct Truth {
    /// [`VERSION`] of the quadrature that made it.
    pub version: u32,
    /// The scene content it belongs to ([`content_key`]).
    pub key: String,
    /// Per object (scene order), per vertex, RGB exitance; all zero for an opaque object, NaN
    /// at a vertex outside the receiver subset (`subset`).
    #[serde(with = "crate::reference::json_null::nan_as_null")]
    pub exitance: Vec<Vec<[f64; 3]>>,
    /// At most this many receivers per object when the truth covers a subset of the vertices
    /// ([`TruthOptions::receivers`]); `None` when it covers them all.
    #[serde(default)]
    pub subset: Option<usize>,
    /// Every level computed, in order.
    pub levels: Vec<Level>,
    /// The tolerance it was asked for.
    pub tolerance: f64,
    /// Whether the last level changed by less than `tolerance`.
    pub converged: bool,
    /// [`Truth::digest`] of what it holds, written with the cache file and checked when it is
    /// read back, so that an edited or damaged file is recomputed, never trusted.
    #[serde(default)]
    pub checksum: Option<String>,
}

impl Truth {
    /// The last level's RMS relative change: the truth's own error estimate (an upper bound of
    /// the kept level's error when each level at least halves the error).
    pub fn change(&self) -> f64 {
        self.levels.last().and_then(|l| l.change_rms).unwrap_or(f64::NAN)
    }
}

/// How far and how hard to refine.
#[derive(Clone, Copy, Debug)]
pub struct TruthOptions {
    /// Stop when the RMS relative change between two levels is below this.
    pub tolerance: f64,
    /// Give up (reporting `converged: false`) after this level.
    pub max_level: u32,
    /// At most this many receivers per translucent object, spread evenly over its vertex order
    /// ([`receiver_subset`]); `None`: every vertex. The others hold NaN.
    pub receivers: Option<usize>,
    /// The most memory (bytes) one level may take ([`LevelMemory`]); `None`:
    /// [`default_memory_limit`] of the memory available when the level starts. A level over it
    /// is refused.
    /// Not part of the content key: it changes whether a truth is computed, not its values.
    pub memory: Option<u64>,
}

impl Default for TruthOptions {
    fn default() -> Self {
        TruthOptions { tolerance: TOLERANCE, max_level: MAX_LEVEL, receivers: None, memory: None }
    }
}

/// Progress of a truth computation, for a progress bar: `(level, receivers done, receivers in
/// the level)`, once with none done as a level starts (its sources are then placed and ray
/// cast, which on a large mesh takes a while) and after every receiver.
pub type Progress<'a> = &'a (dyn Fn(u32, usize, usize) + Sync);

/// Compute the truth for every translucent object of `scene`, level after level until it
/// converges (or `options.max_level`). Before each level its memory is estimated
/// ([`level_memory`](memory::level_memory)) and checked against `options.memory` (or [`default_memory_limit`]): a level
/// that would not fit is refused with [`TruthError::Memory`] rather than run out of memory.
pub fn compute(scene: &PreparedScene, options: &TruthOptions, progress: Progress) -> Result<Truth, TruthError> {
    let occluders = occluders(scene);
    let eps = ray_offset(scene);
    let plans = plans(scene, &occluders, eps);
    let mut levels: Vec<Level> = Vec::new();
    let mut previous: Option<Vec<Vec<[f64; 3]>>> = None;
    let mut converged = false;
    for level in 0..=options.max_level {
        let budget = check_memory(scene, &plans, level, options, &levels)?;
        let start = std::time::Instant::now();
        let eta = 0.4 * 0.5f64.powf(f64::from(level) / 2.0);
        let cast = Cast { occluders: &occluders, eps, plans: &plans };
        let (exitance, points) = level_exitance(scene, &cast, level, options.receivers, budget, progress);
        let (change_rms, change_max) = match &previous {
            Some(p) => {
                let (rms, max) = relative_change(p, &exitance);
                (Some(rms), Some(max))
            }
            None => (None, None),
        };
        levels.push(Level {
            level,
            eta,
            irradiance_points: points,
            change_rms,
            change_max,
            seconds: start.elapsed().as_secs_f64(),
        });
        previous = Some(exitance);
        if change_rms.is_some_and(|c| c < options.tolerance) {
            converged = true;
            break;
        }
    }
    let mut truth = Truth {
        version: VERSION,
        key: content_key(scene, options),
        exitance: previous.unwrap_or_default(),
        subset: options.receivers.filter(|&m| scene.objects.iter().any(|o| m < o.mesh.positions().len())),
        levels,
        tolerance: options.tolerance,
        converged,
        checksum: None,
    };
    truth.checksum = Some(truth.digest());
    Ok(truth)
}

/// Every object's exitance at `level` (all zero for an opaque one), and the `E_t` points ray
/// cast for it, at `receivers` per object at most. One object's sources at a time, held within
/// `budget`: they are dropped before the next object's.
fn level_exitance(
    scene: &PreparedScene,
    cast: &Cast,
    level: u32,
    receivers: Option<usize>,
    budget: Budget,
    progress: Progress,
) -> (Vec<Vec<[f64; 3]>>, usize) {
    let eta = 0.4 * 0.5f64.powf(f64::from(level) / 2.0);
    let mut points = 0;
    let total: usize = scene.objects.iter().map(|o| receiver_subset(o.mesh.positions().len(), receivers).len()).sum();
    let done = AtomicUsize::new(0);
    let tick = |n| {
        let d = done.fetch_add(n, Ordering::Relaxed) + n;
        progress(level, d, total);
    };
    progress(level, 0, total);
    let exitance = scene
        .objects
        .iter()
        .zip(cast.plans)
        .map(|(o, plan)| {
            let subset = receiver_subset(o.mesh.positions().len(), receivers);
            match (&o.material, plan) {
                (ResolvedMaterial::Translucent { material, dipoles, .. }, Some(plan)) => {
                    let caster = Caster::new(scene, cast.occluders, o, material.eta, cast.eps);
                    let sources = Sources::build(&caster, &o.mesh, plan, level, budget.sources);
                    points += sources.points;
                    exitance_at_vertices(o, &subset, dipoles, &sources, eta, budget.notes, &tick)
                }
                _ => {
                    tick(subset.len());
                    vec![[0.0; 3]; o.mesh.positions().len()]
                }
            }
        })
        .collect();
    (exitance, points)
}

/// What ray casting needs of the scene, made once for every level: the shadow casters, the
/// rays' offset and each object's triangle plans.
struct Cast<'a> {
    occluders: &'a Bvh,
    eps: f64,
    plans: &'a [Option<Vec<TrianglePlan>>],
}

/// Relative change from `a` to `b` over the receivers lit in `b` ([`LIT_FLOOR`]): RMS and
/// maximum over every lit (object, vertex, channel).
pub fn relative_change(a: &[Vec<[f64; 3]>], b: &[Vec<[f64; 3]>]) -> (f64, f64) {
    let (mut sum, mut n, mut max) = (0.0, 0usize, 0.0f64);
    for (oa, ob) in a.iter().zip(b) {
        for c in 0..3 {
            let floor = LIT_FLOOR * ob.iter().map(|m| m[c]).fold(0.0, f64::max);
            for (ma, mb) in oa.iter().zip(ob) {
                if mb[c] > 0.0 && mb[c] >= floor {
                    let rel = (ma[c] - mb[c]).abs() / mb[c];
                    sum += rel * rel;
                    n += 1;
                    max = max.max(rel);
                }
            }
        }
    }
    if n == 0 { (0.0, 0.0) } else { ((sum / n as f64).sqrt(), max) }
}

/// Why the truth could not be computed, read or written.
#[derive(Debug, thiserror::Error)]
#[allow(missing_docs)] // each variant names the cache file, or the level and its figures
pub enum TruthError {
    #[error("truth cache {}: {error}", path.display())]
    Io { path: PathBuf, error: std::io::Error },
    #[error("truth cache {}: {why}", path.display())]
    Folder { path: PathBuf, why: FolderProblem },
    #[error("truth cache {}: {error}", path.display())]
    Json { path: PathBuf, error: serde_json::Error },
    #[error(
        "the exact integral's level {level} would need about {} of memory ({points} E_t points), more than \
         the {} {}{}",
        human_bytes(*bytes),
        human_bytes(*limit),
        match kind {
            MemoryLimitKind::Given => "limit given",
            MemoryLimitKind::Default =>
                "default limit (a quarter of the memory available, at most 1 GiB; --truth-memory sets another)",
        },
        last_change.map_or(String::new(), |c| format!(
            "; level {} changed by {c:.2e} RMS from the one before, not yet converged",
            level - 1
        ))
    )]
    Memory { level: u32, bytes: u64, points: usize, limit: u64, kind: MemoryLimitKind, last_change: Option<f64> },
}
