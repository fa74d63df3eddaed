//! The kernel integral at each receiver: a coarse Barnes-Hut pass over the cluster tree, then
//! the adaptive quadrature of each piece of lit surface until it is fine.

use super::LIT_FLOOR;
use super::clusters::{Cluster, Clusters};
use super::source::{Moments, RADON, Source, Summary, WHOLE, linear_moments, split};
use super::store::Sources;
use crate::optics::Dipole;
use crate::scene::build::PreparedObject;
use glam::DVec3;
use rayon::prelude::*;

/// Deepest split of one piece of surface (a guard: `kappa` bounds the depth long before).
const MAX_DEPTH: u32 = 40;

/// The exact exitance at every vertex of `subset` of `o` (NaN at the others).
///
/// The lit triangles are gathered in a [`Clusters`] tree. A first pass sums it Barnes-Hut
/// style (a cluster as one point once it is small seen from `x`): a coarse `M_0(x)`, which
/// only sets what "negligible" means. The refinement then measures each piece's error against
/// `max(its own bound, TAU M_ref)`, with `M_ref = max(M_0(x), LIT_FLOOR max M_0)`: a piece
/// whose whole contribution is negligible next to the receiver's exitance needs no accuracy of
/// its own (far pieces, where `R_d` has decayed by `e^(-sigma_tr d)`, would otherwise be split
/// to the diffusion length).
///
/// Receivers go in blocks: each receiver's far field from the tree and the triangles' summaries
/// first, noting the triangles it must integrate piece by piece; then those triangles' grids,
/// a chunk that fits the budget at a time ([`Sources::chunks`]). A receiver adds its pieces in
/// triangle order whatever the chunks, so the budget does not change a bit of the result.
pub(super) fn exitance_at_vertices(
    o: &PreparedObject,
    subset: &[usize],
    dipoles: &[Dipole; 3],
    sources: &Sources,
    eta: f64,
    pair_bytes: u64,
    progress: &(dyn Fn(usize) + Sync),
) -> Vec<[f64; 3]> {
    let lit = &sources.lit;
    if lit.is_empty() {
        progress(subset.len());
        return vec![[0.0; 3]; o.mesh.positions().len()];
    }
    let tree = Clusters::new(lit);
    let all = o.mesh.positions();
    let positions: Vec<DVec3> = subset.iter().map(|&v| all[v].as_dvec3()).collect();
    let coarse: Vec<[f64; 3]> = positions.par_iter().map(|&x| coarse_exitance(&tree, x, dipoles, eta)).collect();
    let floor = [0, 1, 2].map(|c| LIT_FLOOR * coarse.iter().map(|m| m[c]).fold(0.0, f64::max));
    let far = |k: usize| {
        let m_ref = [0, 1, 2].map(|c| coarse[k][c].max(floor[c]));
        let q = Quadrature { x: positions[k], dipoles, eta, m_ref };
        let (m, needs) = q.far_field(&tree, lit);
        Receiver { x: q.x, m_ref, m, needs }
    };
    let mut at_subset = Vec::with_capacity(subset.len());
    while at_subset.len() < subset.len() {
        let mut block: Vec<Receiver> = Vec::new();
        let mut pairs = 0usize;
        while at_subset.len() + block.len() < subset.len() && (block.is_empty() || 4 * pairs as u64 <= pair_bytes) {
            let lo = at_subset.len() + block.len();
            let batch: Vec<Receiver> = (lo..(lo + BATCH).min(subset.len())).into_par_iter().map(far).collect();
            pairs += batch.iter().map(|r| r.needs.len()).sum::<usize>();
            block.extend(batch);
        }
        near_field(&mut block, sources, dipoles, eta, progress);
        at_subset.extend(block.into_iter().map(|r| r.m));
    }
    if subset.len() == all.len() {
        return at_subset;
    }
    let mut exitance = vec![[f64::NAN; 3]; all.len()];
    for (&v, m) in subset.iter().zip(at_subset) {
        exitance[v] = m;
    }
    exitance
}

/// Receivers whose far field is taken together before their pieces: enough to keep the
/// threads busy, few enough that their notes of triangles stay small.
pub(super) const BATCH: usize = 64;

/// A receiver between its far field and its pieces.
struct Receiver {
    x: DVec3,
    m_ref: [f64; 3],
    /// The exitance summed so far.
    m: [f64; 3],
    /// The lit triangles to integrate piece by piece, sorted.
    needs: Vec<u32>,
}

/// The coarse `M_0(x)`: every cluster small enough seen from `x` as one point.
fn coarse_exitance(tree: &Clusters, x: DVec3, dipoles: &[Dipole; 3], eta: f64) -> [f64; 3] {
    let q = Quadrature { x, dipoles, eta, m_ref: [0.0; 3] };
    let mut m = [0.0; 3];
    tree.walk(
        |c| c.radius <= COARSE_OPENING * (x.distance(c.centre) - c.radius),
        |c| q.monopole(&c.moments.flux, &c.centroid, &mut m),
    );
    m
}

/// Add to each receiver of `block` the triangles it needs piece by piece, their sources a chunk
/// at a time. One task per receiver: a receiver's recursion can take minutes (a large object in
/// diffusion lengths), so chunks of receivers would leave cores idle and the progress bar still.
fn near_field(
    block: &mut [Receiver],
    sources: &Sources,
    dipoles: &[Dipole; 3],
    eta: f64,
    progress: &(dyn Fn(usize) + Sync),
) {
    let mut needed: Vec<u32> = block.iter().flat_map(|r| r.needs.iter().copied()).collect();
    needed.sort_unstable();
    needed.dedup();
    let chunks = sources.chunks(&needed);
    if chunks.is_empty() {
        progress(block.len());
    }
    for (k, run) in chunks.iter().enumerate() {
        let ids = &needed[run.clone()];
        let made = sources.make(ids);
        let (lo, hi) = (ids[0], ids[ids.len() - 1]);
        block.par_iter_mut().with_max_len(1).for_each(|r| {
            let q = Quadrature { x: r.x, dipoles, eta, m_ref: r.m_ref };
            let from = r.needs.partition_point(|&i| i < lo);
            let to = r.needs.partition_point(|&i| i <= hi);
            for &i in &r.needs[from..to] {
                q.piece(sources.get(i, &made), WHOLE, 0, 0, &mut r.m);
            }
            if k + 1 == chunks.len() {
                progress(1);
            }
        });
    }
}

/// The coarse pass takes a cluster whole once its radius is at most this fraction of its
/// distance (an error of a few percent in `M_0`, which only scales what "negligible" means).
const COARSE_OPENING: f64 = 0.3;

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

    /// The far field at `x`: every cluster fine as a whole as one multipole, and every lit
    /// triangle fine as a whole too; the triangles that are not, returned sorted, are
    /// integrated piece by piece ([`Quadrature::piece`]).
    fn far_field(&self, tree: &Clusters, lit: &[Summary]) -> ([f64; 3], Vec<u32>) {
        let (mut m, mut needs) = ([0.0; 3], Vec::new());
        let near = |centre: DVec3, radius: f64| (self.x.distance(centre) - radius).max(0.0);
        let fine = |c: &Cluster| {
            c.source.is_none() && self.fine(near(c.centre, c.radius), c.radius, &c.moments.flux, self.eta / 2.0)
        };
        tree.walk(fine, |c| match c.source {
            Some(i) => {
                let s = &lit[i];
                if self.fine(near(s.centre, s.radius), s.radius, &s.flux, self.eta / 2.0) {
                    self.multipole(&s.flux, &s.centroid, &s.quadrupole, &mut m);
                } else {
                    needs.push(i as u32);
                }
            }
            None => self.multipole(&c.moments.flux, &c.centroid, &c.quadrupole, &mut m),
        });
        needs.sort_unstable();
        (m, needs)
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
    /// pyramid. (Whether the whole triangle is fine as one multipole, [`Quadrature::far_field`]
    /// has asked.)
    fn piece(&self, s: &Source, uv: [[f64; 2]; 3], depth: u32, node: usize, m: &mut [f64; 3]) {
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
