//! Area weights that follow the local sample density: the surface is cut into many small equal
//! pieces (each triangle split regularly into m^2 sub-triangles), and each piece's area goes to
//! the sample nearest its centroid, a discrete restricted Voronoi diagram. The weights then sum
//! to the mesh area exactly (up to f64 rounding), and a sample in a sparse region stands for more
//! area than one in a crowded region, where A/N would give them the same.

use glam::DVec3;
use rayon::prelude::*;

use super::hash::SpatialHash;
use super::walk::SurfacePoint;
use crate::mesh::Mesh;

/// Settings of the area assignment.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightParams {
    /// Target number of surface pieces per sample; more pieces give a finer Voronoi boundary.
    pub pieces_per_sample: f64,
    /// Upper bound on the total number of pieces, which bounds time and memory for huge counts.
    pub max_pieces: usize,
}

impl Default for WeightParams {
    fn default() -> Self {
        WeightParams { pieces_per_sample: 64.0, max_pieces: 1 << 23 }
    }
}

/// Triangles per parallel block; fixed so results do not depend on the thread count.
const BLOCK: usize = 2048;

/// A triangle is split at most this many times per edge (so at most MAX_SPLIT^2 pieces).
const MAX_SPLIT: usize = 1024;

/// The area each of `points` stands for; see the module documentation.
pub fn area_weights(mesh: &Mesh, points: &[SurfacePoint], params: &WeightParams) -> Vec<f64> {
    let n = points.len();
    let total = mesh.total_area();
    if n == 1 {
        return vec![total];
    }
    let positions: Vec<DVec3> = points.par_iter().map(|p| p.position(mesh)).collect();
    let normals = mesh.face_normals();
    let spacing = (total / n as f64).sqrt();
    let hash = SpatialHash::new(&positions, spacing);
    let pieces = (params.pieces_per_sample * n as f64).min(params.max_pieces as f64).max(1.0);
    let piece_area = total / pieces;
    let areas = mesh.triangle_areas();
    let tris = mesh.triangles().len();

    // Each block lists (sample, area) contributions, merging runs that go to the same sample;
    // they are added up in block order afterwards, so the sums are reproducible.
    let blocks: Vec<Vec<(u32, f64)>> = (0..tris.div_ceil(BLOCK))
        .into_par_iter()
        .map(|blk| {
            let mut out: Vec<(u32, f64)> = Vec::new();
            for t in blk * BLOCK..((blk + 1) * BLOCK).min(tris) {
                let m = ((areas[t] / piece_area).sqrt().ceil() as usize).clamp(1, MAX_SPLIT);
                let [a, b, c] = mesh.corners(t);
                let nt = normals[t];
                let each = areas[t] / (m * m) as f64;
                let inv = 1.0 / m as f64;
                let mut assign = |u: f64, v: f64| {
                    let centroid = a + (b - a) * u + (c - a) * v;
                    // Prefer samples on the same side of a thin sheet as this piece.
                    let best = hash
                        .nearest_preferring(centroid, spacing, |j| {
                            normals[points[j as usize].triangle as usize].dot(nt) > 0.0
                        })
                        .expect("there is at least one sample");
                    match out.last_mut() {
                        Some((s, w)) if *s == best => *w += each,
                        _ => out.push((best, each)),
                    }
                };
                // Sub-triangles of the regular split, by their centroids in (u, v) coordinates:
                // "upright" ones at ((i + 1/3) / m, (j + 1/3) / m) and "inverted" ones at
                // ((i + 2/3) / m, (j + 2/3) / m).
                for i in 0..m {
                    for j in 0..m - i {
                        assign((i as f64 + 1.0 / 3.0) * inv, (j as f64 + 1.0 / 3.0) * inv);
                        if i + j + 1 < m {
                            assign((i as f64 + 2.0 / 3.0) * inv, (j as f64 + 2.0 / 3.0) * inv);
                        }
                    }
                }
            }
            out
        })
        .collect();

    let mut weights = vec![0.0; n];
    for block in &blocks {
        for &(s, w) in block {
            weights[s as usize] += w;
        }
    }
    weights
}
