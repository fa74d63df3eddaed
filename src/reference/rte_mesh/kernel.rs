//! The transport kernel's walks (`optics::transport`): for each patch `J` of the mesh
//! (`mesh::patches`), walks that enter uniformly over its vertices' cells straight in along the
//! inward shading normal (the entry of [`ModelEntry::Normal`](super::ModelEntry)) and walk the
//! radiative transfer as the photon walk does (`walk`, expected-value splitting at the
//! boundary); the flux each leaves through patch `I`'s cells, summed and divided by the walks,
//! is `W_IJ`. Each patch has its own random stream, so the kernel does not depend on the
//! threads.

use super::geometry::Geometry;
use super::tally::Exit;
use super::walk::{Start, walk};
use crate::mesh::Mesh;
use crate::mesh::patches::Patches;
use crate::optics::transport::TransportKernel;
use crate::reference::rte::{Medium, chunk_rng};
use rand::RngExt;
use rand_pcg::Pcg64;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};

/// The kernel of `mesh` in `media` between `patches`, `walks` walks per patch and channel,
/// seeded with `seed`; `progress` hears the patches done and their count.
pub fn transport_kernel(
    mesh: &Mesh,
    media: &[Medium; 3],
    patches: Patches,
    (walks, seed): (u64, u64),
    progress: &(dyn Fn(usize, usize) + Sync),
) -> TransportKernel {
    let geometry = Geometry::new(mesh, true);
    let k = patches.len();
    // Per patch, its vertices' corners with their share of the triangle's area.
    let mut corners: Vec<Vec<(usize, usize, f64)>> = vec![Vec::new(); k];
    for (t, tri) in mesh.triangles().iter().enumerate() {
        for (c, &v) in tri.iter().enumerate() {
            corners[patches.of_vertex[v as usize] as usize].push((t, c, mesh.triangle_areas()[t] / 3.0));
        }
    }
    let done = AtomicUsize::new(0);
    let columns: Vec<[Vec<f64>; 3]> = corners
        .par_iter()
        .enumerate()
        .map(|(j, list)| {
            let col = column(&geometry, media, &patches, list, walks, chunk_rng(seed, j as u64));
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, k);
            col
        })
        .collect();
    let mut flux = [vec![0.0; k * k], vec![0.0; k * k], vec![0.0; k * k]];
    for (j, col) in columns.iter().enumerate() {
        for c in 0..3 {
            for i in 0..k {
                flux[c][i * k + j] = col[c][i];
            }
        }
    }
    TransportKernel { patches, flux, walks }
}

/// Patch `j`'s column of the kernel: per channel, the flux out of each patch per unit flux into
/// `j`, from `walks` walks entering over `corners` (triangle, corner, area of its cell there).
fn column(
    geometry: &Geometry,
    media: &[Medium; 3],
    patches: &Patches,
    corners: &[(usize, usize, f64)],
    walks: u64,
    mut rng: Pcg64,
) -> [Vec<f64>; 3] {
    let k = patches.len();
    let mut out = [vec![0.0; k], vec![0.0; k], vec![0.0; k]];
    if corners.is_empty() || walks == 0 {
        return out;
    }
    let cdf: Vec<f64> = corners
        .iter()
        .scan(0.0, |sum, &(_, _, a)| {
            *sum += a;
            Some(*sum)
        })
        .collect();
    let total = cdf[cdf.len() - 1];
    let mut exits: Vec<Exit> = Vec::new();
    for _ in 0..walks {
        let x = rng.random::<f64>() * total;
        let (t, corner, _) = corners[cdf.partition_point(|&c| c <= x).min(corners.len() - 1)];
        let bary = point_in_cell(corner, &mut rng);
        let p = geometry.mesh.point(t, bary);
        let inward = -geometry.shading_normal(t, bary);
        let d = if inward.dot(geometry.normals[t]) < 0.0 { inward } else { -geometry.normals[t] };
        for (channel, medium) in media.iter().enumerate() {
            exits.clear();
            let start = Start { p, d, triangle: t, channel, weight: 1.0 };
            walk(geometry, medium, &start, true, &mut rng, &mut exits);
            for e in &exits {
                out[channel][patches.of_vertex[e.vertex] as usize] += e.weight;
            }
        }
    }
    let n = walks as f64;
    out.iter_mut().for_each(|col| col.iter_mut().for_each(|w| *w /= n));
    out
}

/// A uniform point of a triangle's cell of `corner` (where its barycentric coordinate is the
/// largest), by rejection (a third of the triangle: three tries on average).
fn point_in_cell(corner: usize, rng: &mut Pcg64) -> [f64; 3] {
    loop {
        let (r1, r2) = (rng.random::<f64>().sqrt(), rng.random::<f64>());
        let b = [1.0 - r1, r1 * (1.0 - r2), r1 * r2];
        if (0..3).all(|o| b[corner] >= b[o]) {
            return b;
        }
    }
}
