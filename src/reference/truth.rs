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
//! # Receivers
//!
//! On a large mesh the truth may be asked for at a subset of the vertices
//! ([`TruthOptions::receivers`]): the quadrature at each receiver does not depend on the
//! others (but for the threshold of what is negligible, set from the brightest receiver of the
//! subset), so a subset costs in proportion and its values are those of the full truth.
//! Vertices left out hold NaN ("not computed"), which every statistic over lit receivers skips.

use super::bvh::Bvh;
use super::{Visibility, occluders, ray_offset, transmitted_irradiance_known};
use crate::mesh::Mesh;
use crate::optics::Dipole;
use crate::scene::build::{PreparedObject, PreparedScene, ResolvedMaterial};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

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
/// Deepest split of one piece of surface (a guard: `kappa` bounds the depth long before).
const MAX_DEPTH: u32 = 40;

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
    #[serde(with = "nan_as_null")]
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
    /// A hash (FNV-1a, hex) of its key, version, subset, convergence and every exitance value's
    /// bits.
    pub fn digest(&self) -> String {
        let mut h = Fnv(0xcbf2_9ce4_8422_2325);
        h.bytes(self.key.as_bytes());
        h.u64(u64::from(self.version));
        h.u64(self.subset.map_or(u64::MAX, |m| m as u64));
        h.u64(u64::from(self.converged));
        for o in &self.exitance {
            h.u64(o.len() as u64);
            o.iter().flatten().for_each(|&v| h.f64(v));
        }
        format!("{:016x}", h.0)
    }

    /// Why this truth, read from a cache file, cannot be the truth of `scene` under `options`
    /// (`None`: it can): a foreign key or version, a checksum that does not match its values, a
    /// vertex count other than the mesh's, or a value that is negative, infinite, or NaN at a
    /// vertex the receivers include.
    pub fn unusable_for(&self, scene: &PreparedScene, options: &TruthOptions, key: &str) -> Option<String> {
        if self.key != key || self.version != VERSION {
            return Some(format!("made for other content (key {}, version {})", self.key, self.version));
        }
        if self.checksum.as_deref() != Some(self.digest().as_str()) {
            return Some("its checksum does not match its values (edited or damaged)".into());
        }
        if self.exitance.len() != scene.objects.len() {
            return Some(format!("{} objects, the scene has {}", self.exitance.len(), scene.objects.len()));
        }
        for (i, (m, o)) in self.exitance.iter().zip(&scene.objects).enumerate() {
            let vertices = o.mesh.positions().len();
            if m.len() != vertices {
                return Some(format!("object {i} has {} values, its mesh {vertices} vertices", m.len()));
            }
            for v in receiver_subset(vertices, options.receivers) {
                if m[v].iter().any(|x| !x.is_finite() || *x < 0.0) {
                    return Some(format!("object {i}, vertex {v}: {:?} is not a finite non-negative exitance", m[v]));
                }
            }
        }
        None
    }

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
    /// The most memory (bytes) one level may take ([`LevelMemory`]); `None`: the memory
    /// available when the level starts ([`available_memory`]). A level over it is refused.
    /// Not part of the content key: it changes whether a truth is computed, not its values.
    pub memory: Option<u64>,
}

impl Default for TruthOptions {
    fn default() -> Self {
        TruthOptions { tolerance: TOLERANCE, max_level: MAX_LEVEL, receivers: None, memory: None }
    }
}

/// The vertices of a mesh of `count` vertices at which the truth is computed: all of them, or
/// `max` spread evenly over the vertex order (vertex `floor((i + 1/2) count / max)` for
/// `i < max`), so the subset is the same on every run.
pub fn receiver_subset(count: usize, max: Option<usize>) -> Vec<usize> {
    match max {
        Some(m) if m < count => (0..m).map(|i| ((2 * i + 1) * count) / (2 * m)).collect(),
        _ => (0..count).collect(),
    }
}

/// Serialises NaN ("not computed") as JSON null, which plain `f64` cannot read back.
mod nan_as_null {
    use serde::{Deserialize, Deserializer, Serialize, Serializer};

    type Values = Vec<Vec<[f64; 3]>>;

    pub fn serialize<S: Serializer>(v: &Values, s: S) -> Result<S::Ok, S::Error> {
        let opt: Vec<Vec<[Option<f64>; 3]>> =
            v.iter().map(|o| o.iter().map(|m| m.map(|x| (!x.is_nan()).then_some(x))).collect()).collect();
        opt.serialize(s)
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Values, D::Error> {
        let opt = Vec::<Vec<[Option<f64>; 3]>>::deserialize(d)?;
        Ok(opt.into_iter().map(|o| o.into_iter().map(|m| m.map(|x| x.unwrap_or(f64::NAN))).collect()).collect())
    }
}

/// Progress of a truth computation, for a progress bar: `(level, receivers done, receivers in
/// the level)`.
pub type Progress<'a> = &'a (dyn Fn(u32, usize, usize) + Sync);

/// Compute the truth for every translucent object of `scene`, level after level until it
/// converges (or `options.max_level`). Before each level its memory is estimated
/// ([`level_memory`]) and checked against `options.memory` (or the memory available): a level
/// that would not fit is refused with [`TruthError::Memory`] rather than run out of memory.
pub fn compute(scene: &PreparedScene, options: &TruthOptions, progress: Progress) -> Result<Truth, TruthError> {
    let occluders = occluders(scene);
    let eps = ray_offset(scene);
    let plans = plans(scene, &occluders, eps);
    let mut levels: Vec<Level> = Vec::new();
    let mut previous: Option<Vec<Vec<[f64; 3]>>> = None;
    let mut converged = false;
    for level in 0..=options.max_level {
        check_memory(scene, &plans, level, options, &levels)?;
        let start = std::time::Instant::now();
        let eta = 0.4 * 0.5f64.powf(f64::from(level) / 2.0);
        let (exitance, points) = level_exitance(scene, &occluders, eps, &plans, level, options, progress);
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
/// cast for it. One object's sources at a time: they are dropped before the next object's.
fn level_exitance(
    scene: &PreparedScene,
    occluders: &Bvh,
    eps: f64,
    plans: &[Option<Vec<TrianglePlan>>],
    level: u32,
    options: &TruthOptions,
    progress: Progress,
) -> (Vec<Vec<[f64; 3]>>, usize) {
    let eta = 0.4 * 0.5f64.powf(f64::from(level) / 2.0);
    let mut points = 0;
    let receivers: usize =
        scene.objects.iter().map(|o| receiver_subset(o.mesh.positions().len(), options.receivers).len()).sum();
    let done = AtomicUsize::new(0);
    let exitance = scene
        .objects
        .iter()
        .zip(plans)
        .map(|(o, plan)| match (&o.material, plan) {
            (ResolvedMaterial::Translucent { material, dipoles, .. }, Some(plan)) => {
                let caster = Caster::new(scene, occluders, o, material.eta, eps);
                let sources: Vec<Source> =
                    plan.par_iter().enumerate().map(|(t, p)| caster.source(&o.mesh, t, p, level)).collect();
                points += sources.iter().map(|s| s.grid.len()).sum::<usize>();
                let subset = receiver_subset(o.mesh.positions().len(), options.receivers);
                exitance_at_vertices(o, &subset, dipoles, &sources, eta, &|n| {
                    let d = done.fetch_add(n, Ordering::Relaxed) + n;
                    progress(level, d, receivers);
                })
            }
            _ => {
                done.fetch_add(receiver_subset(o.mesh.positions().len(), options.receivers).len(), Ordering::Relaxed);
                vec![[0.0; 3]; o.mesh.positions().len()]
            }
        })
        .collect();
    (exitance, points)
}

/// Each translucent object's [`TrianglePlan`]s (`None` for an opaque object): the base grids
/// ray cast once, for every level.
fn plans(scene: &PreparedScene, occluders: &Bvh, eps: f64) -> Vec<Option<Vec<TrianglePlan>>> {
    scene
        .objects
        .iter()
        .map(|o| match &o.material {
            ResolvedMaterial::Translucent { material, .. } => {
                let caster = Caster::new(scene, occluders, o, material.eta, eps);
                Some((0..o.mesh.triangles().len()).into_par_iter().map(|t| caster.plan(&o.mesh, t)).collect())
            }
            ResolvedMaterial::Opaque { .. } => None,
        })
        .collect()
}

/// What one level of the truth would hold in memory at its peak: one object's sources (their
/// `E_t` grids and moment pyramids), its cluster tree and receivers, and every object's
/// exitance at this level and the one before. Exact for the allocations that grow with the
/// level; the rest (the BVH, the meshes) is the same at every level and was already resident
/// when the limit was read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelMemory {
    /// Bytes at the level's peak.
    pub bytes: u64,
    /// `E_t` grid points over every object (what [`Level::irradiance_points`] will read).
    pub points: usize,
}

/// [`LevelMemory`] of `scene`'s truth at `level`: what [`compute`] checks against the limit
/// before it starts that level (the triangles' base grids are ray cast to know their depths).
pub fn memory_estimate(scene: &PreparedScene, level: u32) -> LevelMemory {
    let occluders = occluders(scene);
    level_memory(scene, &plans(scene, &occluders, ray_offset(scene)), level)
}

/// [`LevelMemory`] of `level`, from the triangles' plans (no ray is cast).
fn level_memory(scene: &PreparedScene, plans: &[Option<Vec<TrianglePlan>>], level: u32) -> LevelMemory {
    let (mut peak, mut points, mut exitance) = (0u64, 0usize, 0u64);
    for (o, plan) in scene.objects.iter().zip(plans) {
        let vertices = o.mesh.positions().len() as u64;
        exitance += 2 * vertices * std::mem::size_of::<[f64; 3]>() as u64;
        let Some(plan) = plan else { continue };
        let (mut bytes, mut grid) = (0u64, 0usize);
        for p in plan {
            let depth = p.depth(level);
            grid += grid_points(depth);
            bytes += Source::bytes(depth);
        }
        // The cluster tree (two nodes a triangle at most) and the receivers' coarse and fine
        // exitance and positions.
        bytes += plan.len() as u64 * 2 * std::mem::size_of::<Cluster>() as u64;
        bytes += vertices * 3 * std::mem::size_of::<[f64; 3]>() as u64;
        peak = peak.max(bytes);
        points += grid;
    }
    LevelMemory { bytes: peak + exitance, points }
}

/// Refuse `level` when [`level_memory`] exceeds the limit ([`TruthOptions::memory`], else the
/// memory available now, [`available_memory`]; no check where neither is known).
fn check_memory(
    scene: &PreparedScene,
    plans: &[Option<Vec<TrianglePlan>>],
    level: u32,
    options: &TruthOptions,
    done: &[Level],
) -> Result<(), TruthError> {
    let (limit, kind) = match options.memory {
        Some(bytes) => (bytes, MemoryLimitKind::Given),
        None => match available_memory() {
            Some(bytes) => (bytes, MemoryLimitKind::Available),
            None => return Ok(()),
        },
    };
    let need = level_memory(scene, plans, level);
    if need.bytes <= limit {
        return Ok(());
    }
    Err(TruthError::Memory {
        level,
        bytes: need.bytes,
        points: need.points,
        limit,
        kind,
        last_change: done.last().and_then(|l| l.change_rms),
    })
}

/// `MemAvailable` of `/proc/meminfo`, in bytes: what can be allocated without swapping or the
/// kernel killing something. `None` where that file is not there (not Linux) or says nothing.
pub fn available_memory() -> Option<u64> {
    let info = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// Where a truth's memory limit came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryLimitKind {
    /// [`TruthOptions::memory`].
    Given,
    /// The memory available when the level was to start ([`available_memory`]).
    Available,
}

/// `bytes` for a reader: `4.70 GiB`, `312.0 MiB`, `64.0 KiB`.
pub fn human_bytes(bytes: u64) -> String {
    let b = bytes as f64;
    match b {
        b if b >= 1024f64.powi(3) => format!("{:.2} GiB", b / 1024f64.powi(3)),
        b if b >= 1024f64.powi(2) => format!("{:.1} MiB", b / 1024f64.powi(2)),
        b => format!("{:.1} KiB", b / 1024.0),
    }
}

/// Why the truth could not be computed, read or written.
#[derive(Debug, thiserror::Error)]
#[allow(missing_docs)] // each variant names the cache file, or the level and its figures
pub enum TruthError {
    #[error("truth cache {}: {error}", path.display())]
    Io { path: PathBuf, error: std::io::Error },
    #[error("truth cache {}: {why}", path.display())]
    Folder { path: PathBuf, why: String },
    #[error("truth cache {}: {error}", path.display())]
    Json { path: PathBuf, error: serde_json::Error },
    #[error(
        "the exact integral's level {level} would need about {} of memory ({points} E_t points), more than \
         the {} {}{}",
        human_bytes(*bytes),
        human_bytes(*limit),
        match kind { MemoryLimitKind::Given => "limit given", MemoryLimitKind::Available => "available (MemAvailable, /proc/meminfo)" },
        last_change.map_or(String::new(), |c| format!(
            "; level {} changed by {c:.2e} RMS from the one before, not yet converged",
            level - 1
        ))
    )]
    Memory { level: u32, bytes: u64, points: usize, limit: u64, kind: MemoryLimitKind, last_change: Option<f64> },
}

/// The truth of `scene` from `dir` if an earlier run left it there (same content key and
/// quadrature version), else computed and stored there. Returns it and whether it was cached.
pub fn cached(
    scene: &PreparedScene,
    options: &TruthOptions,
    dir: &Path,
    progress: Progress,
) -> Result<(Truth, bool), TruthError> {
    let key = content_key(scene, options);
    let path = dir.join(format!("truth-{key}.json"));
    if let Ok(bytes) = std::fs::read(&path) {
        // An unreadable, foreign, edited or damaged file is recomputed and replaced, never
        // trusted.
        match serde_json::from_slice::<Truth>(&bytes) {
            Ok(truth) => match truth.unusable_for(scene, options, &key) {
                None => return Ok((truth, true)),
                Some(why) => log::warn!("truth cache {}: {why}; computing it anew", path.display()),
            },
            Err(e) => log::warn!("truth cache {}: unreadable ({e}); computing it anew", path.display()),
        }
    }
    // A folder the truth cannot be written to is found before the truth is computed.
    writable_folder(dir)?;
    let truth = compute(scene, options, progress)?;
    let io = |error| TruthError::Io { path: path.clone(), error };
    let json = serde_json::to_vec(&truth).map_err(|error| TruthError::Json { path: path.clone(), error })?;
    // Write then rename, so a run cut short never leaves half a truth behind.
    let tmp = dir.join(format!(".truth-{key}.json.tmp"));
    std::fs::write(&tmp, json).map_err(io)?;
    std::fs::rename(&tmp, &path).map_err(io)?;
    Ok((truth, false))
}

/// `dir`, made if missing, is a folder a file can be written in (a file of its own is made and
/// removed); otherwise what stands in the way.
fn writable_folder(dir: &Path) -> Result<(), TruthError> {
    match folder_problem(dir) {
        None => Ok(()),
        Some(why) => Err(TruthError::Folder { path: dir.to_path_buf(), why }),
    }
}

/// What keeps `dir` (made if missing) from being a folder a file can be written in, if
/// anything: a file of its own is made and removed to find out.
pub(crate) fn folder_problem(dir: &Path) -> Option<String> {
    if let Some(existing) = dir.ancestors().find(|a| a.exists())
        && !existing.is_dir()
    {
        return Some(format!("{} is a file, not a folder", existing.display()));
    }
    if let Err(e) = std::fs::create_dir_all(dir) {
        return Some(format!("cannot make the folder ({e})"));
    }
    let probe = dir.join(format!(".truth-probe-{}.tmp", std::process::id()));
    match std::fs::write(&probe, b"") {
        Ok(()) => {
            let _ = std::fs::remove_file(&probe);
            None
        }
        Err(e) => Some(format!("cannot write a file in the folder ({e})")),
    }
}

/// Where truths are cached unless told otherwise: `$XDG_CACHE_HOME/translucent/truth`, else
/// `$HOME/.cache/translucent/truth`, else the system's temporary folder.
pub fn default_cache_dir() -> PathBuf {
    let base = std::env::var_os("XDG_CACHE_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").filter(|v| !v.is_empty()).map(|h| PathBuf::from(h).join(".cache")))
        .unwrap_or_else(std::env::temp_dir);
    base.join("translucent").join("truth")
}

/// A hash (FNV-1a, 64 bits, hex) of everything the truth depends on: each object's placed mesh
/// and dipoles, which objects cast shadows, the prepared lights, the options and the quadrature
/// version. Sample points, the camera and the gather are left out: the truth does not depend
/// on them.
pub fn content_key(scene: &PreparedScene, options: &TruthOptions) -> String {
    let mut h = Fnv(0xcbf2_9ce4_8422_2325);
    h.u64(u64::from(VERSION));
    h.f64(options.tolerance);
    h.u64(u64::from(options.max_level));
    // Only a subset changes the key, so the caches of whole truths stay valid.
    if let Some(m) = options.receivers {
        h.u64(m as u64);
    }
    for o in &scene.objects {
        h.u64(o.mesh.positions().len() as u64);
        for p in o.mesh.positions() {
            p.to_array().iter().for_each(|c| h.u64(u64::from(c.to_bits())));
        }
        for t in o.mesh.triangles() {
            t.iter().for_each(|&i| h.u64(u64::from(i)));
        }
        h.u64(u64::from(o.casts_shadow));
        match &o.material {
            ResolvedMaterial::Translucent { material, dipoles, .. } => {
                h.f64(material.eta);
                for d in dipoles {
                    [d.sigma_a, d.sigma_s_prime, d.eta].iter().for_each(|&v| h.f64(v));
                }
            }
            ResolvedMaterial::Opaque { .. } => h.u64(0),
        }
    }
    for l in &scene.lights {
        h.bytes(format!("{:?} {}", l.kind, l.shadow_layer.is_some()).as_bytes());
    }
    format!("{:016x}", h.0)
}

/// FNV-1a, 64 bits: the content keys and checksums of the cached references.
pub(crate) struct Fnv(pub(crate) u64);

impl Fnv {
    /// The FNV-1a offset basis: an empty hash.
    pub(crate) fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    pub(crate) fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }
    pub(crate) fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
    pub(crate) fn f64(&mut self, v: f64) {
        self.u64(v.to_bits());
    }
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

/// One mesh triangle as a source: its transmitted irradiance on a grid of `4^depth` cells.
struct Source {
    corners: [DVec3; 3],
    depth: u32,
    /// `E_t` at grid point `(i, j)` (`u = i/n`, `v = j/n`, `n = 2^depth`), at [`grid_index`].
    grid: Vec<DVec3>,
    area: f64,
    /// Flux `integral E_t dA` per channel and its `E_t`-weighted centroid.
    flux: [f64; 3],
    centroid: [DVec3; 3],
    /// Second moment `integral (y - c)(y - c)^T E_t dA` about each channel's centroid `c`:
    /// xx, yy, zz, xy, xz, yz.
    quadrupole: [[f64; 6]; 3],
    /// Bounding sphere of the triangle (centre of its corners).
    centre: DVec3,
    radius: f64,
    /// Exact moments of every piece coarser than a grid cell by more than [`PYRAMID_SKIP`]
    /// splits, in the order [`Quadrature::piece`] splits (node `k`'s children are
    /// `4k + 1 ..= 4k + 4`, the root is the whole triangle), so a piece spanning many cells can
    /// stand as one monopole once the kernel is smooth over it. The finer pieces' moments are
    /// summed from their cells when asked ([`Source::moments`]).
    pyramid: Vec<Moments>,
}

/// The pyramid leaves out the pieces this many splits above a grid cell (4 cells each): its
/// last level held 3/4 of it, twice the grid's own memory, and a receiver asks for those
/// pieces only where the kernel is not smooth over them. (Leaving out two levels saved a third
/// more memory but made each level about 1.5 times slower.)
const PYRAMID_SKIP: u32 = 1;

/// Points of a triangle's grid at `depth`.
fn grid_points(depth: u32) -> usize {
    let n = 1usize << depth;
    (n + 1) * (n + 2) / 2
}

/// Nodes of a triangle's moment pyramid whose grid is at `depth`.
fn pyramid_nodes(depth: u32) -> usize {
    ((1usize << (2 * depth.saturating_sub(PYRAMID_SKIP))) - 1) / 3
}

/// Flux `integral E_t dA` and first moment `integral y E_t dA` of a piece of surface, per channel.
#[derive(Clone, Copy, Debug, Default)]
struct Moments {
    flux: [f64; 3],
    moment: [DVec3; 3],
}

impl Moments {
    fn add(&mut self, o: &Moments) {
        for c in 0..3 {
            self.flux[c] += o.flux[c];
            self.moment[c] += o.moment[c];
        }
    }

    /// Each channel's `E_t`-weighted centroid (`fallback` where the piece is dark).
    fn centroid(&self, fallback: DVec3) -> [DVec3; 3] {
        [0, 1, 2].map(|c| if self.flux[c] > 0.0 { self.moment[c] / self.flux[c] } else { fallback })
    }
}

/// The four children of the piece with corners `uv`, in the order of [`Source::pyramid`].
fn split(uv: [[f64; 2]; 3]) -> [[[f64; 2]; 3]; 4] {
    let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) * 0.5, (a[1] + b[1]) * 0.5];
    let (ab, bc, ca) = (mid(uv[0], uv[1]), mid(uv[1], uv[2]), mid(uv[2], uv[0]));
    [[uv[0], ab, ca], [ab, uv[1], bc], [ca, bc, uv[2]], [ab, bc, ca]]
}

/// The whole triangle in `(u, v)`.
const WHOLE: [[f64; 2]; 3] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];

/// Index of grid point `(i, j)`, `i + j <= n`, in a triangle's grid (rows of `i`).
fn grid_index(i: usize, j: usize, n: usize) -> usize {
    i * (n + 1) - i * i.saturating_sub(1) / 2 + j
}

/// The point at `(u, v)` of the triangle with `corners`.
fn triangle_point(corners: &[DVec3; 3], u: f64, v: f64) -> DVec3 {
    corners[0] + (corners[1] - corners[0]) * u + (corners[2] - corners[0]) * v
}

impl Source {
    fn point(&self, u: f64, v: f64) -> DVec3 {
        triangle_point(&self.corners, u, v)
    }

    /// Exact moments of the piece `uv` at split depth `depth <= self.depth`: a grid cell's from
    /// its linear `E_t`, a coarser piece's as the sum of its children's (stored in `pyramid`
    /// at `node` where the pyramid keeps it). Returns the piece's moments.
    fn build_pyramid(&mut self, uv: [[f64; 2]; 3], depth: u32, node: usize) -> Moments {
        if node >= self.pyramid.len() {
            return self.summed_moments(uv, depth);
        }
        let mut sum = Moments::default();
        for (k, child) in split(uv).into_iter().enumerate() {
            sum.add(&self.build_pyramid(child, depth + 1, 4 * node + 1 + k));
        }
        self.pyramid[node] = sum;
        sum
    }

    /// The moments of the piece `uv` at split depth `depth`, pyramid node `node`: stored, or
    /// summed from its cells in the order `build_pyramid` sums them (so the same bits).
    fn moments(&self, uv: [[f64; 2]; 3], depth: u32, node: usize) -> Moments {
        self.pyramid.get(node).copied().unwrap_or_else(|| self.summed_moments(uv, depth))
    }

    /// The moments of the piece `uv` at split depth `depth <= self.depth`, summed from its cells.
    fn summed_moments(&self, uv: [[f64; 2]; 3], depth: u32) -> Moments {
        if depth == self.depth {
            let y = uv.map(|[u, v]| self.point(u, v));
            let e = uv.map(|[u, v]| self.irradiance(u, v));
            let (flux, moment) = linear_moments(&y, &e, self.area * 0.25f64.powi(depth as i32));
            return Moments { flux, moment };
        }
        let mut sum = Moments::default();
        for child in split(uv) {
            sum.add(&self.summed_moments(child, depth + 1));
        }
        sum
    }

    /// Heap and inline bytes of a source whose grid is at `depth`.
    fn bytes(depth: u32) -> u64 {
        (grid_points(depth) * std::mem::size_of::<DVec3>()
            + pyramid_nodes(depth) * std::mem::size_of::<Moments>()
            + std::mem::size_of::<Source>()) as u64
    }

    /// `E_t` at `(u, v)`, linear in each grid cell.
    fn irradiance(&self, u: f64, v: f64) -> DVec3 {
        let n = 1usize << self.depth;
        let (s, t) = (u * n as f64, v * n as f64);
        let i = (s.floor().max(0.0) as usize).min(n - 1);
        let j = (t.floor().max(0.0) as usize).min(n - 1 - i);
        let (a, b) = (s - i as f64, t - j as f64);
        let e = |i, j| self.grid[grid_index(i, j, n)];
        if a + b <= 1.0 || i + j + 2 > n {
            e(i, j) * (1.0 - a - b) + e(i + 1, j) * a + e(i, j + 1) * b
        } else {
            e(i + 1, j + 1) * (a + b - 1.0) + e(i + 1, j) * (1.0 - b) + e(i, j + 1) * (1.0 - a)
        }
    }
}

/// Call `f` with the grid points of every cell of a triangle's grid of side `n`: the `n^2`
/// triangles of its uniform subdivision, pointing up and down.
fn for_each_cell(n: usize, mut f: impl FnMut([(usize, usize); 3])) {
    for i in 0..n {
        for j in 0..n - i {
            f([(i, j), (i + 1, j), (i, j + 1)]);
            if i + j + 2 <= n {
                f([(i + 1, j), (i + 1, j + 1), (i, j + 1)]);
            }
        }
    }
}

/// Flux and first moment of a linear `E` over a triangle of `area` with corners `y` and
/// values `e`: `integral E dA = A mean(E)`, `integral y E dA = (A/12)(sum y_i E_i + sum y_i sum E_i)`.
fn linear_moments(y: &[DVec3; 3], e: &[DVec3; 3], area: f64) -> ([f64; 3], [DVec3; 3]) {
    let ys = y[0] + y[1] + y[2];
    let mut flux = [0.0; 3];
    let mut moment = [DVec3::ZERO; 3];
    for c in 0..3 {
        let es = e[0][c] + e[1][c] + e[2][c];
        flux[c] = area * es / 3.0;
        moment[c] = (y[0] * e[0][c] + y[1] * e[1][c] + y[2] * e[2][c] + ys * es) * (area / 12.0);
    }
    (flux, moment)
}

/// The lights (by bit, modulo 64) giving at least [`STRONG_LIGHT`] of the total incidence at
/// the mesh's centre: their shadow edges get [`EDGE_EXTRA_DEPTH`] more levels.
fn strong_lights(scene: &PreparedScene, mesh: &Mesh) -> u64 {
    let centre = mesh.positions().iter().map(|p| p.as_dvec3()).sum::<DVec3>() / mesh.positions().len().max(1) as f64;
    let peak: Vec<f64> = scene.lights.iter().map(|l| super::light_incidence(l, centre).1.max_element()).collect();
    let total: f64 = peak.iter().sum();
    peak.iter().enumerate().filter(|&(_, &p)| p >= STRONG_LIGHT * total).fold(0u64, |m, (i, _)| m | 1u64 << (i % 64))
}

/// What ray casting `E_t` on one object's triangles needs: the scene, its occluders, the
/// object's refractive index and ray offset, its vertex normals and its strong lights.
struct Caster<'a> {
    scene: &'a PreparedScene,
    occluders: &'a Bvh,
    eta: f64,
    eps: f64,
    normals: &'a [Vec3],
    /// [`strong_lights`].
    strong: u64,
}

/// How one triangle is refined, from its base grid (ray cast once): its depth at level `l` is
/// `base + l + extra`, and which lights its finer grids ray cast.
#[derive(Clone, Copy, Debug)]
struct TrianglePlan {
    /// Grid depth at level 0 before shadow edges: set by how far the shading normal turns.
    base: u32,
    /// [`EDGE_EXTRA_DEPTH`] where a strong light's shadow edge crosses the triangle, else 0.
    extra: u32,
    /// The lights finer grids ray cast, and those known blocked everywhere.
    finer: Visibility,
}

impl TrianglePlan {
    fn depth(&self, level: u32) -> u32 {
        self.base + level + self.extra
    }
}

impl<'a> Caster<'a> {
    fn new(scene: &'a PreparedScene, occluders: &'a Bvh, o: &'a PreparedObject, eta: f64, eps: f64) -> Caster<'a> {
        let mesh = &o.mesh;
        Caster { scene, occluders, eta, eps, normals: mesh.vertex_normals(), strong: strong_lights(scene, mesh) }
    }

    /// How triangle `t` of `mesh` is refined at every level: its grid as deep as its normals
    /// and shadow edges ask.
    fn plan(&self, mesh: &Mesh, t: usize) -> TrianglePlan {
        let corners = mesh.corners(t);
        let normals = mesh.triangles()[t].map(|i| self.normals[i as usize].as_dvec3());
        let [a, b, c] = normals;
        // E_t follows the shading normal: linear interpolation over a cell whose normals
        // turn by `delta` radians misses about `delta^2 / 8` of it, so cells start small
        // enough that `delta` is at most NORMAL_SPREAD.
        let spread = [a.angle_between(b), b.angle_between(c), c.angle_between(a)].into_iter().fold(0.0, f64::max);
        let base = (spread / NORMAL_SPREAD).log2().ceil().clamp(0.0, 8.0) as u32;
        // Every light is ray cast on the base grid. A light that reaches some of its points
        // and is blocked at others casts a shadow edge across the triangle (the terminator
        // is no edge: E_t falls to zero there continuously, as cos^2); such lights are ray
        // cast on the finer grids, and so are those that face none of the base points (the
        // triangle straddles their terminator, so the base grid says nothing of their
        // shadows; back-facing points cost no ray). The others keep the base grid's
        // verdict, so a shadow narrower than the base grid that touches none of its points
        // is missed at every level.
        let (_, reached, blocked) = self.grid(&corners, normals, base, Visibility::TRACE_ALL);
        let edges = reached & blocked;
        let unknown = !(reached | blocked);
        TrianglePlan {
            base,
            extra: if edges & self.strong != 0 { EDGE_EXTRA_DEPTH } else { 0 },
            finer: Visibility { trace: edges | unknown, blocked: blocked & !reached },
        }
    }

    /// Triangle `t` of `mesh` as a source at `level`, refined as `plan` says.
    fn source(&self, mesh: &Mesh, t: usize, plan: &TrianglePlan, level: u32) -> Source {
        let corners = mesh.corners(t);
        let normals = mesh.triangles()[t].map(|i| self.normals[i as usize].as_dvec3());
        let depth = plan.depth(level);
        let known = if depth == plan.base { Visibility::TRACE_ALL } else { plan.finer };
        let grid = self.grid(&corners, normals, depth, known).0;
        Source::new(corners, depth, grid, mesh.triangle_areas()[t])
    }

    /// `E_t` at the grid points of a triangle's grid at `depth` (at [`grid_index`]), with the
    /// lights that reached and that were blocked at any of them or at the centroid. Normals are
    /// interpolated from the corners'; `known` says which lights need no ray.
    fn grid(&self, corners: &[DVec3; 3], normals: [DVec3; 3], depth: u32, known: Visibility) -> (Vec<DVec3>, u64, u64) {
        let [a, b, c] = normals;
        let n = 1usize << depth;
        let mut grid = vec![DVec3::ZERO; (n + 1) * (n + 2) / 2];
        let at = |u: f64, v: f64| {
            let p = triangle_point(corners, u, v);
            let normal = a * (1.0 - u - v) + b * u + c * v;
            transmitted_irradiance_known(self.scene, self.occluders, p, normal, self.eta, self.eps, known)
        };
        let (mut reached, mut blocked) = (0u64, 0u64);
        for i in 0..=n {
            for j in 0..=n - i {
                let (e, r, b) = at(i as f64 / n as f64, j as f64 / n as f64);
                grid[grid_index(i, j, n)] = e;
                (reached, blocked) = (reached | r, blocked | b);
            }
        }
        let (_, r, b) = at(1.0 / 3.0, 1.0 / 3.0);
        (grid, reached | r, blocked | b)
    }
}

impl Source {
    /// A triangle's source from its `E_t` grid at `depth`: its moment pyramid, flux, centroid
    /// and second moments, and its bounding sphere.
    fn new(corners: [DVec3; 3], depth: u32, grid: Vec<DVec3>, area: f64) -> Source {
        let centre = (corners[0] + corners[1] + corners[2]) / 3.0;
        let radius = corners.iter().map(|p| p.distance(centre)).fold(0.0, f64::max);
        let mut s = Source {
            corners,
            depth,
            grid,
            area,
            flux: [0.0; 3],
            centroid: [DVec3::ZERO; 3],
            quadrupole: [[0.0; 6]; 3],
            centre,
            radius,
            pyramid: vec![Moments::default(); pyramid_nodes(depth)],
        };
        let whole = s.build_pyramid(WHOLE, 0, 0);
        s.centroid = whole.centroid(centre);
        s.flux = whole.flux;
        s.quadrupole = s.second_moments();
        s
    }

    /// `integral (y - c)(y - c)^T E_t dA` about each channel's centroid, cell by cell: Radon's
    /// rule is exact for the cubic `(y - c)^2 E_t`.
    fn second_moments(&self) -> [[f64; 6]; 3] {
        let n = 1usize << self.depth;
        let cell_area = self.area / (n * n) as f64;
        let mut q = [[0.0; 6]; 3];
        for_each_cell(n, |cell| {
            let y = cell.map(|(i, j)| self.point(i as f64 / n as f64, j as f64 / n as f64));
            let e = cell.map(|(i, j)| self.grid[grid_index(i, j, n)]);
            for (b, w) in RADON {
                let p = y[0] * b[0] + y[1] * b[1] + y[2] * b[2];
                let ep = e[0] * b[0] + e[1] * b[1] + e[2] * b[2];
                for ch in 0..3 {
                    let r = p - self.centroid[ch];
                    let we = w * cell_area * ep[ch];
                    let terms = [r.x * r.x, r.y * r.y, r.z * r.z, r.x * r.y, r.x * r.z, r.y * r.z];
                    for (qk, t) in q[ch].iter_mut().zip(terms) {
                        *qk += we * t;
                    }
                }
            }
        });
        q
    }
}

/// Radon's 7-point degree-5 rule on a triangle: barycentric coordinates and weights (summing
/// to one). Published constants: `a = (6 -+ sqrt 15)/21`, `w = (155 -+ sqrt 15)/1200`.
const RADON: [([f64; 3], f64); 7] = {
    const A1: f64 = 0.101_286_507_323_456_3;
    const B1: f64 = 0.797_426_985_353_087_4;
    const W1: f64 = 0.125_939_180_544_827_1;
    const A2: f64 = 0.470_142_064_105_115_1;
    const B2: f64 = 0.059_715_871_789_769_8;
    const W2: f64 = 0.132_394_152_788_506_2;
    [
        ([1.0 / 3.0, 1.0 / 3.0, 1.0 / 3.0], 0.225),
        ([A1, A1, B1], W1),
        ([A1, B1, A1], W1),
        ([B1, A1, A1], W1),
        ([A2, A2, B2], W2),
        ([A2, B2, A2], W2),
        ([B2, A2, A2], W2),
    ]
};

/// The exact exitance at every vertex of `o`.
///
/// The lit triangles are gathered in a [`Clusters`] tree. A first pass sums it Barnes-Hut
/// style (a cluster as one point once it is small seen from `x`): a coarse `M_0(x)`, which
/// only sets what "negligible" means. The refinement then measures each piece's error against
/// `max(its own bound, TAU M_ref)`, with `M_ref = max(M_0(x), LIT_FLOOR max M_0)`: a piece
/// whose whole contribution is negligible next to the receiver's exitance needs no accuracy of
/// its own (far pieces, where `R_d` has decayed by `e^(-sigma_tr d)`, would otherwise be split
/// to the diffusion length).
fn exitance_at_vertices(
    o: &PreparedObject,
    subset: &[usize],
    dipoles: &[Dipole; 3],
    sources: &[Source],
    eta: f64,
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<[f64; 3]> {
    let lit: Vec<&Source> = sources.iter().filter(|s| s.flux.iter().any(|&f| f > 0.0)).collect();
    if lit.is_empty() {
        return vec![[0.0; 3]; o.mesh.positions().len()];
    }
    let tree = Clusters::new(&lit);
    let all = o.mesh.positions();
    let positions: Vec<glam::Vec3> = subset.iter().map(|&v| all[v]).collect();
    let coarse: Vec<[f64; 3]> = positions
        .par_iter()
        .map(|x| {
            let q = Quadrature { x: x.as_dvec3(), dipoles, eta, m_ref: [0.0; 3] };
            let mut m = [0.0; 3];
            tree.walk(
                |c| c.radius <= COARSE_OPENING * (x.as_dvec3().distance(c.centre) - c.radius),
                |c| q.monopole(&c.moments.flux, &c.centroid, &mut m),
            );
            m
        })
        .collect();
    let floor = [0, 1, 2].map(|c| LIT_FLOOR * coarse.iter().map(|m| m[c]).fold(0.0, f64::max));
    let chunk = 64;
    let at_subset: Vec<[f64; 3]> = positions
        .par_chunks(chunk)
        .zip(coarse.par_chunks(chunk))
        .flat_map_iter(|(xs, m0)| {
            let out: Vec<[f64; 3]> = xs
                .iter()
                .zip(m0)
                .map(|(x, m0)| {
                    let x = x.as_dvec3();
                    let m_ref = [0, 1, 2].map(|c| m0[c].max(floor[c]));
                    let q = Quadrature { x, dipoles, eta, m_ref };
                    let mut m = [0.0; 3];
                    // A cluster that is fine as a whole is one multipole; a triangle that is not
                    // is integrated piece by piece.
                    let fine = |c: &Cluster| {
                        let d = (x.distance(c.centre) - c.radius).max(0.0);
                        c.source.is_none() && q.fine(d, c.radius, &c.moments.flux, eta / 2.0)
                    };
                    tree.walk(fine, |c| match c.source {
                        Some(s) => q.piece(lit[s], WHOLE, 0, 0, &mut m),
                        None => q.multipole(&c.moments.flux, &c.centroid, &c.quadrupole, &mut m),
                    });
                    m
                })
                .collect();
            progress(xs.len());
            out
        })
        .collect();
    if subset.len() == all.len() {
        return at_subset;
    }
    let mut exitance = vec![[f64::NAN; 3]; all.len()];
    for (&v, m) in subset.iter().zip(at_subset) {
        exitance[v] = m;
    }
    exitance
}

/// The coarse pass takes a cluster whole once its radius is at most this fraction of its
/// distance (an error of a few percent in `M_0`, which only scales what "negligible" means).
const COARSE_OPENING: f64 = 0.3;

/// A node of the tree of lit triangles: their moments about each channel's centroid and a
/// bounding sphere.
struct Cluster {
    moments: Moments,
    centroid: [DVec3; 3],
    /// Second moments about `centroid`, as [`Source::quadrupole`].
    quadrupole: [[f64; 6]; 3],
    centre: DVec3,
    radius: f64,
    /// The triangle (index into the lit sources) of a leaf.
    source: Option<usize>,
    /// Children of an inner node.
    children: [usize; 2],
}

/// A binary tree over the lit triangles (median split on the longest axis of their centres),
/// so a receiver takes a far group of triangles as one multipole instead of visiting each: the
/// cost per receiver grows with the log of the triangle count, not with it.
struct Clusters {
    nodes: Vec<Cluster>,
}

impl Clusters {
    fn new(lit: &[&Source]) -> Clusters {
        let mut nodes = Vec::with_capacity(2 * lit.len());
        let mut members: Vec<usize> = (0..lit.len()).collect();
        Self::build(lit, &mut members, &mut nodes);
        Clusters { nodes }
    }

    /// Append the subtree over `members` (post-order) and return its root's index.
    fn build(lit: &[&Source], members: &mut [usize], nodes: &mut Vec<Cluster>) -> usize {
        if let [only] = members {
            let s = lit[*only];
            nodes.push(Cluster {
                moments: Moments { flux: s.flux, moment: [0, 1, 2].map(|c| s.centroid[c] * s.flux[c]) },
                centroid: s.centroid,
                quadrupole: s.quadrupole,
                centre: s.centre,
                radius: s.radius,
                source: Some(*only),
                children: [0; 2],
            });
            return nodes.len() - 1;
        }
        let (lo, hi) = members.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &i| {
            (lo.min(lit[i].centre), hi.max(lit[i].centre))
        });
        let axis = (hi - lo).max_position();
        let half = members.len() / 2;
        members.select_nth_unstable_by(half, |&a, &b| lit[a].centre[axis].total_cmp(&lit[b].centre[axis]));
        let (left, right) = members.split_at_mut(half);
        let children = [Self::build(lit, left, nodes), Self::build(lit, right, nodes)];
        let [a, b] = children.map(|k| &nodes[k]);
        let mut moments = a.moments;
        moments.add(&b.moments);
        let centre = (a.centre + b.centre) * 0.5;
        let centroid = moments.centroid(centre);
        // Parallel axes: each child's second moment moved from its centroid to the parent's.
        let mut quadrupole = [[0.0; 6]; 3];
        for child in [a, b] {
            for c in 0..3 {
                let (f, r) = (child.moments.flux[c], child.centroid[c] - centroid[c]);
                let shift = [r.x * r.x, r.y * r.y, r.z * r.z, r.x * r.y, r.x * r.z, r.y * r.z];
                for k in 0..6 {
                    quadrupole[c][k] += child.quadrupole[c][k] + f * shift[k];
                }
            }
        }
        let radius = [a, b].iter().map(|n| n.centre.distance(centre) + n.radius).fold(0.0, f64::max);
        nodes.push(Cluster { moments, centroid, quadrupole, centre, radius, source: None, children });
        nodes.len() - 1
    }

    /// Visit the tree from the root: `take` a node that is a leaf or `whole(node)`, else go
    /// down to its children.
    fn walk(&self, whole: impl Fn(&Cluster) -> bool, mut take: impl FnMut(&Cluster)) {
        let mut stack = vec![self.nodes.len() - 1];
        while let Some(k) = stack.pop() {
            let node = &self.nodes[k];
            if node.source.is_some() || whole(node) {
                take(node);
            } else {
                stack.extend(node.children);
            }
        }
    }
}

/// A piece's error may reach this fraction of the receiver's reference exitance (times the
/// rule's `(eta)^2`) when that is more than its own relative error would allow.
const TAU: f64 = 1e-3;

struct Quadrature<'a> {
    x: DVec3,
    dipoles: &'a [Dipole; 3],
    eta: f64,
    m_ref: [f64; 3],
}

impl Quadrature<'_> {
    /// Is a piece of radius `radius` at distance `d` (to its nearest point, at most), carrying
    /// `flux`, fine enough for a rule of fineness `limit`? Per channel, `t = 2 R kappa` with
    /// `kappa = sigma_tr + 3 / sqrt(d^2 + z_r^2)` the inverse length over which `R_d` changes
    /// there; the rule's error is about `t^2` of the piece's contribution, bounded by
    /// `flux R_d(d)`. Fine when that error is within `limit^2` of the contribution, or of
    /// `TAU M_ref`.
    fn fine(&self, d: f64, radius: f64, flux: &[f64; 3], limit: f64) -> bool {
        (0..3).all(|c| {
            if flux[c] <= 0.0 {
                return true;
            }
            let dp = &self.dipoles[c];
            let t = 2.0 * radius * (dp.sigma_tr + 3.0 / (d * d + dp.z_r * dp.z_r).sqrt());
            if t <= limit {
                return true;
            }
            let bound = flux[c] * dp.r_d_sq(d * d);
            t * t * bound <= limit * limit * TAU * self.m_ref[c]
        })
    }

    fn monopole(&self, flux: &[f64; 3], centroid: &[DVec3; 3], m: &mut [f64; 3]) {
        for c in 0..3 {
            if flux[c] > 0.0 {
                m[c] += flux[c] * self.dipoles[c].r_d_sq(self.x.distance_squared(centroid[c]));
            }
        }
    }

    /// A piece of surface as a point at each channel's centroid plus the quadrupole term
    /// `(1/2) Q : H`, `H = R_d'' r^ r^T + (R_d'/r)(I - r^ r^T)` the kernel's Hessian: the error
    /// is third order in the piece's size over the kernel's length.
    fn multipole(&self, flux: &[f64; 3], centroid: &[DVec3; 3], quadrupole: &[[f64; 6]; 3], m: &mut [f64; 3]) {
        for c in 0..3 {
            if flux[c] <= 0.0 {
                continue;
            }
            let r = self.x - centroid[c];
            let r2 = r.length_squared();
            let (g, g1, g2) = self.dipoles[c].r_d_derivatives(r2);
            let q = &quadrupole[c];
            let trace = q[0] + q[1] + q[2];
            let along = if r2 > 0.0 {
                (r.x * r.x * q[0]
                    + r.y * r.y * q[1]
                    + r.z * r.z * q[2]
                    + 2.0 * (r.x * r.y * q[3] + r.x * r.z * q[4] + r.y * r.z * q[5]))
                    / r2
            } else {
                0.0
            };
            m[c] += flux[c] * g + 0.5 * ((g2 - g1) * along + g1 * trace);
        }
    }

    /// Integrate over the piece of `s` with corners `uv` (in the triangle's `(u, v)`), at split
    /// depth `depth` below the triangle and, while coarser than a grid cell, `node` of its
    /// pyramid.
    fn piece(&self, s: &Source, uv: [[f64; 2]; 3], depth: u32, node: usize, m: &mut [f64; 3]) {
        if depth == 0 {
            let d = (self.x.distance(s.centre) - s.radius).max(0.0);
            if self.fine(d, s.radius, &s.flux, self.eta / 2.0) {
                return self.multipole(&s.flux, &s.centroid, &s.quadrupole, m);
            }
        }
        let y = uv.map(|[u, v]| s.point(u, v));
        let centre = (y[0] + y[1] + y[2]) / 3.0;
        let radius = y.iter().map(|p| p.distance(centre)).fold(0.0, f64::max);
        let d = (self.x.distance(centre) - radius).max(0.0);
        if depth < s.depth {
            // Coarser than a grid cell: its exact moments are in the pyramid.
            let moments = s.moments(uv, depth, node);
            if self.fine(d, radius, &moments.flux, self.eta / 4.0) {
                return self.monopole(&moments.flux, &moments.centroid(centre), m);
            }
        } else {
            // Inside one grid cell `E_t` is linear, so the piece's moments are known exactly.
            let e = uv.map(|[u, v]| s.irradiance(u, v));
            let area = s.area * 0.25f64.powi(depth as i32);
            let (flux, moment) = linear_moments(&y, &e, area);
            if self.fine(d, radius, &flux, self.eta / 4.0) {
                return self.monopole(&flux, &Moments { flux, moment }.centroid(centre), m);
            }
            if self.fine(d, radius, &flux, self.eta) || depth >= MAX_DEPTH {
                for (b, w) in RADON {
                    let p = y[0] * b[0] + y[1] * b[1] + y[2] * b[2];
                    let ep = e[0] * b[0] + e[1] * b[1] + e[2] * b[2];
                    let r2 = self.x.distance_squared(p);
                    for c in 0..3 {
                        if ep[c] > 0.0 {
                            m[c] += w * area * ep[c] * self.dipoles[c].r_d_sq(r2);
                        }
                    }
                }
                return;
            }
        }
        for (k, child) in split(uv).into_iter().enumerate() {
            // Pieces finer than a grid cell have no pyramid node.
            let child_node = if depth + 1 < s.depth { 4 * node + 1 + k } else { 0 };
            self.piece(s, child, depth + 1, child_node, m);
        }
    }
}
