//! Poisson-disk (blue-noise) points by weighted sample elimination, after Cem Yuksel, "Sample
//! Elimination for Generating Poisson Disk Sample Sets" (Eurographics 2015): draw several times
//! more uniform candidates than wanted, give each a weight that grows with how crowded its
//! neighbourhood is, and repeatedly remove the heaviest candidate (updating its neighbours'
//! weights) until exactly N remain.
//!
//! Constants as in the paper: r_max = sqrt(A / (2 sqrt(3) N)) (the radius of N discs in hexagonal
//! packing on area A), weight (1 - d / (2 r_max))^8 for neighbours closer than 2 r_max, and
//! weight limiting that treats distances below r_min = r_max (1 - (N/M)^1.5) 0.65 as r_min.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::DVec3;
use rayon::prelude::*;

use super::hash::SpatialHash;
use super::walk::SurfacePoint;
use crate::mesh::Mesh;

/// Settings of the sample elimination.
#[derive(Clone, Debug, PartialEq)]
pub struct PoissonParams {
    /// Candidates drawn per output point (Yuksel uses 5).
    pub candidate_factor: usize,
}

impl Default for PoissonParams {
    fn default() -> Self {
        PoissonParams { candidate_factor: 5 }
    }
}

const ALPHA: i32 = 8;
const BETA: f64 = 0.65;
const GAMMA: f64 = 1.5;

/// Candidates are grouped in blocks of this size when neighbour lists are built in parallel, a
/// fixed size so the output does not depend on the thread count.
const BLOCK: usize = 1024;

#[derive(PartialEq)]
struct Entry {
    weight: f64,
    index: u32,
}

impl Eq for Entry {}

impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        // Heaviest first; among equal weights the lower index, so runs are reproducible.
        self.weight.total_cmp(&other.weight).then_with(|| other.index.cmp(&self.index))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

/// Keep `n` of `candidates` by weighted sample elimination. Returns the survivors in their
/// original order.
pub fn eliminate(mesh: &Mesh, candidates: &[SurfacePoint], n: usize) -> Vec<SurfacePoint> {
    let m = candidates.len();
    if n >= m {
        return candidates.to_vec();
    }
    let positions: Vec<DVec3> = candidates.par_iter().map(|c| c.position(mesh)).collect();
    let normals = mesh.face_normals();
    let r_max = (mesh.total_area() / (2.0 * 3f64.sqrt() * n as f64)).sqrt();
    let r_min = r_max * (1.0 - (n as f64 / m as f64).powf(GAMMA)) * BETA;
    let reach = 2.0 * r_max;
    let hash = SpatialHash::new(&positions, reach);
    let weight = |d: f64| (1.0 - d.max(r_min) / reach).max(0.0).powi(ALPHA);

    // Neighbour lists (index, weight) in CSR form, built block by block: each block gives its
    // per-candidate counts and its concatenated lists.
    type Block = (Vec<u32>, Vec<(u32, f64)>);
    let blocks: Vec<Block> = (0..m.div_ceil(BLOCK))
        .into_par_iter()
        .map(|blk| {
            let range = blk * BLOCK..((blk + 1) * BLOCK).min(m);
            let mut counts = Vec::with_capacity(range.len());
            let mut list = Vec::new();
            for i in range {
                let ni = normals[candidates[i].triangle as usize];
                let before = list.len();
                hash.for_each_within(positions[i], reach, |j, d2| {
                    // Opposite-facing candidates sit on the other side of a thin sheet: they do
                    // not compete for the same stretch of surface.
                    if j as usize != i && normals[candidates[j as usize].triangle as usize].dot(ni) >= 0.0 {
                        list.push((j, weight(d2.sqrt())));
                    }
                });
                counts.push((list.len() - before) as u32);
            }
            (counts, list)
        })
        .collect();
    let mut offsets = Vec::with_capacity(m + 1);
    offsets.push(0usize);
    let mut neighbours = Vec::with_capacity(blocks.iter().map(|b| b.1.len()).sum());
    for (counts, list) in blocks {
        for c in counts {
            offsets.push(offsets.last().unwrap() + c as usize);
        }
        neighbours.extend(list);
    }

    let mut weights: Vec<f64> =
        (0..m).map(|i| neighbours[offsets[i]..offsets[i + 1]].iter().map(|e| e.1).sum()).collect();
    let mut heap: BinaryHeap<Entry> = (0..m).map(|i| Entry { weight: weights[i], index: i as u32 }).collect();
    let mut removed = vec![false; m];
    let mut alive = m;
    // Weights only decrease, so a popped entry whose weight no longer matches is stale: a fresher
    // entry for the same candidate is further down the heap.
    while alive > n {
        let Some(Entry { weight: w, index }) = heap.pop() else { break };
        let i = index as usize;
        if removed[i] || w != weights[i] {
            continue;
        }
        removed[i] = true;
        alive -= 1;
        for &(j, wij) in &neighbours[offsets[i]..offsets[i + 1]] {
            let j = j as usize;
            if !removed[j] {
                weights[j] -= wij;
                heap.push(Entry { weight: weights[j], index: j as u32 });
            }
        }
    }
    candidates.iter().zip(&removed).filter(|(_, r)| !**r).map(|(c, _)| *c).collect()
}
