//! What one level of the truth holds in memory, estimated before it starts, and the limit it
//! is checked against.

use super::caster::{TrianglePlan, plans};
use super::clusters::Cluster;
use super::quadrature::BATCH;
use super::source::{Source, grid_points};
use super::store::PER_TRIANGLE;
use super::{Level, TruthError, TruthOptions};
use crate::reference::{occluders, ray_offset};
use crate::scene::build::PreparedScene;
use glam::DVec3;

/// What one level of the truth needs in memory, known before it starts (issue 47: memory by
/// construction). The triangles' full `E_t` grids and pyramids are held only as far as the
/// limit allows and made again when needed ([`Sources`](super::store::Sources)), so a level's
/// floor is what grows with the mesh and the receivers, not with the level's refinement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelMemory {
    /// The least the level runs in: per object its triangles' summaries and cluster tree, its
    /// receivers, one batch of their notes and the largest grid once per thread and once more;
    /// and every object's exitance at this level and the one before. Exact for the allocations
    /// that grow with the mesh; the rest (the BVH, the meshes) was already resident when the
    /// limit was read.
    pub bytes: u64,
    /// Every triangle's grid and pyramid at once, for the largest object: above the limit, the
    /// level streams (ray casts grids again) instead of holding them.
    pub whole: u64,
    /// `E_t` grid points over every object (what [`Level::irradiance_points`] will read).
    pub points: usize,
}

/// [`LevelMemory`] of `scene`'s truth at `level`: what [`compute`](super::compute) checks against the limit
/// before it starts that level (the triangles' base grids are ray cast to know their depths).
pub fn memory_estimate(scene: &PreparedScene, level: u32) -> LevelMemory {
    let occluders = occluders(scene);
    level_memory(scene, &plans(scene, &occluders, ray_offset(scene)), level)
}

/// [`LevelMemory`] of `level`, from the triangles' plans (no ray is cast).
pub(super) fn level_memory(scene: &PreparedScene, plans: &[Option<Vec<TrianglePlan>>], level: u32) -> LevelMemory {
    let (mut floor, mut whole, mut points, mut exitance) = (0u64, 0u64, 0usize, 0u64);
    let threads = rayon::current_num_threads() as u64;
    for (o, plan) in scene.objects.iter().zip(plans) {
        let vertices = o.mesh.positions().len() as u64;
        exitance += 2 * vertices * size_of::<[f64; 3]>() as u64;
        let Some(plan) = plan else { continue };
        let (mut all, mut largest) = (0u64, 0u64);
        for p in plan {
            let depth = p.depth(level);
            points += grid_points(depth);
            all += Source::bytes(depth);
            largest = largest.max(Source::bytes(depth));
        }
        let triangles = plan.len() as u64;
        let per_triangle = (PER_TRIANGLE + 2 * size_of::<Cluster>()) as u64;
        let per_receiver = (3 * size_of::<[f64; 3]>() + size_of::<DVec3>() + 64) as u64;
        let notes = BATCH as u64 * triangles * size_of::<u32>() as u64;
        floor = floor.max(triangles * per_triangle + vertices * per_receiver + notes + (threads + 1) * largest);
        whole = whole.max(all);
    }
    LevelMemory { bytes: floor + exitance, whole, points }
}

/// How a level shares its memory limit out, past its floor ([`LevelMemory::bytes`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct Budget {
    /// Bytes of full sources held at once (kept from the first pass and made again).
    pub(super) sources: u64,
    /// Bytes of a block of receivers' notes of the triangles they need whole.
    pub(super) notes: u64,
}

impl Budget {
    /// An eighth of what is left past the floor for the notes, the rest for the sources.
    fn of(limit: u64, floor: u64) -> Budget {
        let left = limit.saturating_sub(floor);
        Budget { sources: left - left / 8, notes: left / 8 }
    }
}

/// The limit of `level`'s memory ([`TruthOptions::memory`], else [`default_memory_limit`])
/// shared out as a [`Budget`], or the level refused when its floor ([`level_memory`]) is over
/// the limit.
pub(super) fn check_memory(
    scene: &PreparedScene,
    plans: &[Option<Vec<TrianglePlan>>],
    level: u32,
    options: &TruthOptions,
    done: &[Level],
) -> Result<Budget, TruthError> {
    let (limit, kind) = match options.memory {
        Some(bytes) => (bytes, MemoryLimitKind::Given),
        None => (default_memory_limit(available_memory()), MemoryLimitKind::Default),
    };
    let need = level_memory(scene, plans, level);
    if need.bytes <= limit {
        return Ok(Budget::of(limit, need.bytes));
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

/// The most a truth level may use unless told (`--truth-memory`): 1 GiB. A level whose grids
/// would take more streams them: ray casts them again when receivers need them.
pub const DEFAULT_MEMORY_CAP: u64 = 1 << 30;

/// The limit a truth level is held to when none is given: a quarter of the memory available
/// when it starts ([`available_memory`]), and at most [`DEFAULT_MEMORY_CAP`]; the cap alone
/// where the available memory is not known. A modest share, so that the study leaves the
/// machine usable and a level that would take it all is refused before it starts.
pub fn default_memory_limit(available: Option<u64>) -> u64 {
    available.map_or(DEFAULT_MEMORY_CAP, |bytes| (bytes / 4).min(DEFAULT_MEMORY_CAP))
}

/// Where a truth's memory limit came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryLimitKind {
    /// [`TruthOptions::memory`].
    Given,
    /// None was given: [`default_memory_limit`].
    Default,
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_truth_memory_limit_is_a_quarter_of_what_is_available_and_at_most_1_gib() {
        assert_eq!(default_memory_limit(Some(2 << 30)), 512 << 20);
        assert_eq!(default_memory_limit(Some(23 << 30)), DEFAULT_MEMORY_CAP);
        assert_eq!(default_memory_limit(Some(1000)), 250);
        assert_eq!(default_memory_limit(None), DEFAULT_MEMORY_CAP);
    }
}
