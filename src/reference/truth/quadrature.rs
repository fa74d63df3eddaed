//! The kernel integral at each receiver: a coarse Barnes-Hut pass over the cluster tree, then
//! the adaptive quadrature of each piece of lit surface until it is fine.

use super::LIT_FLOOR;
use super::clusters::{Cluster, Clusters};
use super::source::{Moments, RADON, Source, WHOLE, linear_moments, split};
use crate::optics::Dipole;
use crate::scene::build::PreparedObject;
use glam::DVec3;
use rayon::prelude::*;

/// Deepest split of one piece of surface (a guard: `kappa` bounds the depth long before).
const MAX_DEPTH: u32 = 40;

/// The exact exitance at every vertex of `o`.
///
/// The lit triangles are gathered in a [`Clusters`] tree. A first pass sums it Barnes-Hut
/// style (a cluster as one point once it is small seen from `x`): a coarse `M_0(x)`, which
/// only sets what "negligible" means. The refinement then measures each piece's error against
/// `max(its own bound, TAU M_ref)`, with `M_ref = max(M_0(x), LIT_FLOOR max M_0)`: a piece
/// whose whole contribution is negligible next to the receiver's exitance needs no accuracy of
/// its own (far pieces, where `R_d` has decayed by `e^(-sigma_tr d)`, would otherwise be split
/// to the diffusion length).
pub(super) fn exitance_at_vertices(
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
    // One task per receiver: a receiver's recursion can take minutes (a large object in
    // diffusion lengths), so chunks would leave cores idle and the progress bar still.
    let at_subset: Vec<[f64; 3]> = positions
        .par_iter()
        .zip(&coarse)
        .with_max_len(1)
        .map(|(x, m0)| {
            let x = x.as_dvec3();
            let m_ref = [0, 1, 2].map(|c| m0[c].max(floor[c]));
            let q = Quadrature { x, dipoles, eta, m_ref };
            let mut m = [0.0; 3];
            // A cluster that is fine as a whole is one multipole; a triangle that is not is
            // integrated piece by piece.
            let fine = |c: &Cluster| {
                let d = (x.distance(c.centre) - c.radius).max(0.0);
                c.source.is_none() && q.fine(d, c.radius, &c.moments.flux, eta / 2.0)
            };
            tree.walk(fine, |c| match c.source {
                Some(s) => q.piece(lit[s], WHOLE, 0, 0, &mut m),
                None => q.multipole(&c.moments.flux, &c.centroid, &c.quadrupole, &mut m),
            });
            progress(1);
            m
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
