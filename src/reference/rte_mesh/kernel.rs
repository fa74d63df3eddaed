//! The transport kernel's walks (`optics::transport`): for each patch `J` of the mesh
//! (`mesh::patches`), walks that enter uniformly over its vertices' cells along a direction
//! drawn as diffuse light refracts in about the inward shading normal
//! (`optics::transport::EntryBasis`) and walk the radiative transfer as the photon walk does
//! (`walk`, expected-value splitting at the boundary). The flux `O_I` each leaves through patch
//! `I`'s cells, weighted by the entry's basis function over its variance and averaged over the
//! walks, is the least-squares coefficient of that basis: `W0_IJ = E[O_I]`,
//! `Wmu_IJ = E[O_I (mu - mu_bar)] / Var mu`, `Wt_IJ = E[O_I (t . u_JI)] / E[(t . u)^2]` and
//! `Wx_IJ = E[O_I s] / E[s^2]` with `s = (x - x_J) . u_JI` the entry point's offset towards `I`
//! (the basis functions are orthogonal under the entry's distribution: the tilt is odd in the
//! azimuth, and the point is drawn independently of the direction about its mean `x_J`; `E[s^2]`
//! is the cells' exact second moment), `Wmu` and `Wt` only within each channel's `entry_reach`.
//! Each patch has its own random stream, so the kernel does not depend on the threads.

use super::geometry::Geometry;
use super::tally::Exit;
use super::walk::{Start, walk};
use crate::mesh::Mesh;
use crate::mesh::patches::Patches;
use crate::optics::transport::{EntryBasis, TransportKernel, entry_reach};
use crate::reference::rte::{Medium, chunk_rng};
use glam::{DMat3, DVec3};
use rand::RngExt;
use rand::SeedableRng as _;
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
    let entry = EntryBasis::new(media[0].eta);
    let centres = patches.entry_centres(mesh);
    let columns: Vec<Column> = corners
        .par_iter()
        .enumerate()
        .map(|(j, list)| {
            let spread = second_moment(mesh, list, centres[j]);
            let at = Entering { patch: j, corners: list, entry, centre: centres[j], spread };
            let col = column(&geometry, media, &patches, &at, walks, chunk_rng(seed, j as u64));
            progress(done.fetch_add(1, Ordering::Relaxed) + 1, k);
            col
        })
        .collect();
    let table = || [vec![0.0; k * k], vec![0.0; k * k], vec![0.0; k * k]];
    let mut rows = [table(), table(), table(), table()];
    for (j, col) in columns.iter().enumerate() {
        for (row, col) in rows.iter_mut().zip(col) {
            for c in 0..3 {
                (0..k).for_each(|i| row[c][i * k + j] = col[c][i]);
            }
        }
    }
    let [flux, depth, sideways, shift] = rows;
    TransportKernel { patches, flux, depth, sideways, shift, mu_mean: entry.mu_mean(), walks }
}

/// One patch's column of the kernel's four rows (`W0`, `Wmu`, `Wt`, `Wx`), per channel and
/// patch.
type Column = [[Vec<f64>; 3]; 4];

/// Where one patch's walks enter: the patch, its vertices' corners (triangle, corner, area of
/// its cell there), the entry's directions, the entry points' mean and their second moment
/// about it (per unit area).
struct Entering<'a> {
    patch: usize,
    corners: &'a [(usize, usize, f64)],
    entry: EntryBasis,
    centre: DVec3,
    spread: DMat3,
}

/// The second moment about `about` of a point drawn uniformly over the cells `corners`: each
/// cell is two triangles of a sixth of its triangle (the corner, an edge's midpoint, the
/// centroid), and a triangle of area `A` with corners `q_i` (from `about`) has
/// `int q q^T dA = A / 12 (sum q_i q_i^T + s s^T)`, `s = sum q_i`.
fn second_moment(mesh: &Mesh, corners: &[(usize, usize, f64)], about: DVec3) -> DMat3 {
    let outer = |q: DVec3| DMat3::from_cols(q * q.x, q * q.y, q * q.z);
    let triangle = |q: [DVec3; 3], area: f64| {
        let s = q[0] + q[1] + q[2];
        (outer(q[0]) + outer(q[1]) + outer(q[2]) + outer(s)) * (area / 12.0)
    };
    let (mut m, mut total) = (DMat3::ZERO, 0.0);
    for &(t, c, third) in corners {
        let p = mesh.triangles()[t].map(|v| mesh.positions()[v as usize].as_dvec3() - about);
        let (a, b, e) = (p[c], p[(c + 1) % 3], p[(c + 2) % 3]);
        let g = (a + b + e) / 3.0;
        m += triangle([a, (a + b) * 0.5, g], third * 0.5) + triangle([a, g, (a + e) * 0.5], third * 0.5);
        total += third;
    }
    if total > 0.0 { m * (1.0 / total) } else { m }
}

/// A patch's column of the kernel: per row of the basis and channel, the flux out of each patch
/// per unit flux in, from `walks` walks entering as `at` says.
fn column(
    geometry: &Geometry,
    media: &[Medium; 3],
    patches: &Patches,
    at: &Entering,
    walks: u64,
    mut rng: Pcg64,
) -> Column {
    let k = patches.len();
    let mut out: Column = std::array::from_fn(|_| [vec![0.0; k], vec![0.0; k], vec![0.0; k]]);
    let corners = at.corners;
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
    let near: Vec<Vec<bool>> = media
        .iter()
        .map(|m| {
            let reach = entry_reach(patches.radius, m.diffusion_length());
            (0..k).map(|i| patches.centre(at.patch).distance(patches.centre(i)) <= reach).collect()
        })
        .collect();
    let toward: Vec<DVec3> = (0..k).map(|i| patches.toward(at.patch, i)).collect();
    // Each basis function over its variance; the offset's along `u_JI` is `u^T S u`.
    let offset_var: Vec<f64> = toward.iter().map(|u| u.dot(at.spread * *u)).collect();
    let (mu_bar, mu_var, tilt_var) = (at.entry.mu_mean(), at.entry.mu_variance(), at.entry.tilt_variance());
    let mut exits: Vec<Exit> = Vec::new();
    for _ in 0..walks {
        let x = rng.random::<f64>() * total;
        let (t, corner, _) = corners[cdf.partition_point(|&c| c <= x).min(corners.len() - 1)];
        let bary = point_in_cell(corner, &mut rng);
        let p = geometry.mesh.point(t, bary);
        let inward = -geometry.shading_normal(t, bary);
        let (d, tilt) = entry_direction(inward, -geometry.normals[t], &at.entry, &mut rng);
        let depth = if mu_var > 0.0 { (d.dot(inward) - mu_bar) / mu_var } else { 0.0 };
        let offset = p - at.centre;
        // The three channels walk on the same random numbers, so that their noise is alike
        // and a patch's scale errs in brightness rather than in hue.
        let shared = rng.random::<u64>();
        for (channel, medium) in media.iter().enumerate() {
            exits.clear();
            let start = Start { p, d, triangle: t, channel, weight: 1.0 };
            walk(geometry, medium, &start, true, &mut Pcg64::seed_from_u64(shared), &mut exits);
            for e in &exits {
                let i = patches.of_vertex[e.vertex] as usize;
                out[0][channel][i] += e.weight;
                if near[channel][i] {
                    out[1][channel][i] += e.weight * depth;
                    out[2][channel][i] += e.weight * tilt.dot(toward[i]) / tilt_var;
                }
                if offset_var[i] > 0.0 {
                    out[3][channel][i] += e.weight * offset.dot(toward[i]) / offset_var[i];
                }
            }
        }
    }
    let n = walks as f64;
    out.iter_mut().flatten().for_each(|col| col.iter_mut().for_each(|w| *w /= n));
    out
}

/// An entry direction about the inward shading normal `inward` drawn from `entry`, and its
/// tangential part; redrawn while it would not enter through the face (inward geometric normal
/// `face`), and straight along `face` after eight tries (a shading normal far off its face).
fn entry_direction(inward: DVec3, face: DVec3, entry: &EntryBasis, rng: &mut Pcg64) -> (DVec3, DVec3) {
    let (a, b) = inward.any_orthonormal_pair();
    for _ in 0..8 {
        let (mu, phi) = entry.sample(rng.random::<f64>(), rng.random::<f64>());
        let tilt = (a * phi.cos() + b * phi.sin()) * (1.0 - mu * mu).max(0.0).sqrt();
        let d = inward * mu + tilt;
        if d.dot(face) > 0.0 {
            return (d, tilt);
        }
    }
    (face, face - inward * face.dot(inward))
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
