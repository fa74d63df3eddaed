//! Distances from each vertex to the open boundary of its mesh, for the near field's edge
//! factor (`optics::kernel::near_kept_at_edge`): the near-field blend assumes the surface goes
//! on all around a receiver, which an open boundary breaks.

use super::Mesh;
use glam::DVec3;
use rayon::prelude::*;

/// The distance stored where a mesh has no boundary in that direction: larger than any reach of
/// the near field, finite so that nothing infinite travels to the GPU.
pub const NO_BOUNDARY: f32 = f32::MAX;

/// Two boundary edges count as one direction when their lines are within this angle's cosine
/// (45 degrees) of parallel.
const SAME_DIRECTION: f64 = std::f64::consts::FRAC_1_SQRT_2;

impl Mesh {
    /// The edges used by exactly one triangle (an open boundary; edges shared by three or more
    /// go on into the surface and are not boundaries), as vertex pairs, found with the rest of
    /// the edge adjacency when the mesh was built.
    pub fn boundary_edges(&self) -> &[[u32; 2]] {
        &self.boundary_edges
    }

    /// Per vertex, the distance to the nearest boundary edge and the distance to the nearest
    /// boundary edge running in another direction (more than 45 degrees from the first), so a
    /// receiver near a corner sees both sides of it; [`NO_BOUNDARY`] where there is none. All
    /// [`NO_BOUNDARY`] on a closed mesh. Brute force over the boundary edges, in parallel over
    /// vertices: `O(vertices x boundary edges)`.
    pub fn boundary_distances(&self) -> Vec<[f32; 2]> {
        let points: Vec<DVec3> = self.positions().iter().map(|p| p.as_dvec3()).collect();
        self.boundary_distances_at(&points)
    }

    /// [`Self::boundary_distances`] at any points (on or near the surface).
    pub fn boundary_distances_at(&self, points: &[DVec3]) -> Vec<[f32; 2]> {
        let edges = self.boundary_edges();
        let positions = self.positions();
        if edges.is_empty() {
            return vec![[NO_BOUNDARY; 2]; points.len()];
        }
        let segments: Vec<(DVec3, DVec3)> =
            edges.iter().map(|e| (positions[e[0] as usize].as_dvec3(), positions[e[1] as usize].as_dvec3())).collect();
        points
            .par_iter()
            .map(|&p| {
                let distance = |(a, b): &(DVec3, DVec3)| {
                    let ab = *b - *a;
                    let s = ((p - *a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
                    p.distance(*a + s * ab)
                };
                let (mut d1, mut u1) = (f64::INFINITY, DVec3::ZERO);
                for s in &segments {
                    let d = distance(s);
                    if d < d1 {
                        (d1, u1) = (d, (s.1 - s.0).normalize_or_zero());
                    }
                }
                let d2 = segments
                    .iter()
                    .filter(|s| (s.1 - s.0).normalize_or_zero().dot(u1).abs() < SAME_DIRECTION)
                    .map(distance)
                    .fold(f64::INFINITY, f64::min);
                [d1, d2].map(|d| if d.is_finite() { d as f32 } else { NO_BOUNDARY })
            })
            .collect()
    }
}
