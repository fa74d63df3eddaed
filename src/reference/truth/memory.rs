//! What one level of the truth holds in memory, estimated before it starts, and the limit it
//! is checked against.

use super::caster::{TrianglePlan, plans};
use super::clusters::Cluster;
use super::source::{Source, grid_points};
use super::{Level, TruthError, TruthOptions};
use crate::reference::{occluders, ray_offset};
use crate::scene::build::PreparedScene;

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

/// [`LevelMemory`] of `scene`'s truth at `level`: what [`compute`](super::compute) checks against the limit
/// before it starts that level (the triangles' base grids are ray cast to know their depths).
pub fn memory_estimate(scene: &PreparedScene, level: u32) -> LevelMemory {
    let occluders = occluders(scene);
    level_memory(scene, &plans(scene, &occluders, ray_offset(scene)), level)
}

/// [`LevelMemory`] of `level`, from the triangles' plans (no ray is cast).
pub(super) fn level_memory(scene: &PreparedScene, plans: &[Option<Vec<TrianglePlan>>], level: u32) -> LevelMemory {
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

/// Refuse `level` when [`level_memory`] exceeds the limit ([`TruthOptions::memory`], else
/// [`default_memory_limit`]).
pub(super) fn check_memory(
    scene: &PreparedScene,
    plans: &[Option<Vec<TrianglePlan>>],
    level: u32,
    options: &TruthOptions,
    done: &[Level],
) -> Result<(), TruthError> {
    let (limit, kind) = match options.memory {
        Some(bytes) => (bytes, MemoryLimitKind::Given),
        None => (default_memory_limit(available_memory()), MemoryLimitKind::Default),
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

/// The most a truth level may use unless told (`--truth-memory`): 4 GiB.
pub const DEFAULT_MEMORY_CAP: u64 = 4 << 30;

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
    fn the_default_truth_memory_limit_is_a_quarter_of_what_is_available_and_at_most_4_gib() {
        assert_eq!(default_memory_limit(Some(8 << 30)), 2 << 30);
        assert_eq!(default_memory_limit(Some(23 << 30)), DEFAULT_MEMORY_CAP);
        assert_eq!(default_memory_limit(Some(1000)), 250);
        assert_eq!(default_memory_limit(None), DEFAULT_MEMORY_CAP);
    }
}
