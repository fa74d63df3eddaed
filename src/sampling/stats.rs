//! Statistics of a sample set: spacing (nearest-neighbour distances) and the spread of weights.

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::SamplePoint;
use super::hash::SpatialHash;

/// Distance from each point to its nearest other point (Euclidean, through a spatial hash).
/// Empty for fewer than two points.
pub fn nearest_neighbour_distances(positions: &[Vec3]) -> Vec<f64> {
    if positions.len() < 2 {
        return Vec::new();
    }
    let pts: Vec<DVec3> = positions.iter().map(|p| p.as_dvec3()).collect();
    let (lo, hi) = pts.iter().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(*p), hi.max(*p)));
    // A cell near the expected spacing of points spread over the box's surface area.
    let ext = (hi - lo).max(DVec3::splat(1e-12));
    let box_area = 2.0 * (ext.x * ext.y + ext.y * ext.z + ext.z * ext.x);
    let cell = (box_area / pts.len() as f64).sqrt().max(1e-12);
    let hash = SpatialHash::new(&pts, cell);
    pts.par_iter().enumerate().map(|(i, p)| hash.nearest(*p, Some(i as u32)).map_or(0.0, |(_, d)| d)).collect()
}

/// Summary printed by `translucent sample`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SampleStats {
    /// Number of points.
    pub count: usize,
    /// Sum of the area weights.
    pub total_weight: f64,
    /// Area of the mesh, for comparison with `total_weight`.
    pub mesh_area: f64,
    /// Nearest-neighbour distances; `None` with fewer than two points.
    pub nn_min: Option<f64>,
    /// Mean nearest-neighbour distance; `None` with fewer than two points.
    pub nn_mean: Option<f64>,
    /// Largest nearest-neighbour distance; `None` with fewer than two points.
    pub nn_max: Option<f64>,
    /// Coefficient of variation (standard deviation over mean) of the area weights.
    pub weight_cv: f64,
    /// Smallest area weight (infinite with no points).
    pub weight_min: f64,
    /// Largest area weight (0 with no points).
    pub weight_max: f64,
}

impl SampleStats {
    /// The statistics of `points`; `mesh_area` is kept for comparison with their total weight.
    pub fn compute(points: &[SamplePoint], mesh_area: f64) -> SampleStats {
        let positions: Vec<Vec3> = points.iter().map(|p| p.position).collect();
        let nn = nearest_neighbour_distances(&positions);
        let (nn_min, nn_mean, nn_max) = if nn.is_empty() {
            (None, None, None)
        } else {
            (
                Some(nn.iter().copied().fold(f64::INFINITY, f64::min)),
                Some(nn.iter().sum::<f64>() / nn.len() as f64),
                Some(nn.iter().copied().fold(0.0, f64::max)),
            )
        };
        let n = points.len().max(1) as f64;
        let total: f64 = points.iter().map(|p| p.area).sum();
        let mean = total / n;
        let var = points.iter().map(|p| (p.area - mean).powi(2)).sum::<f64>() / n;
        SampleStats {
            count: points.len(),
            total_weight: total,
            mesh_area,
            nn_min,
            nn_mean,
            nn_max,
            weight_cv: if mean > 0.0 { var.sqrt() / mean } else { 0.0 },
            weight_min: points.iter().map(|p| p.area).fold(f64::INFINITY, f64::min),
            weight_max: points.iter().map(|p| p.area).fold(0.0, f64::max),
        }
    }
}
