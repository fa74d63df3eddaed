//! The directional dipole's exitance at the vertices, f64: the truth's integral
//! (`reference::truth`) with the directional dipole (`optics::directional_dipole`, Frisvad et al.
//! 2014) in place of `R_d`:
//!
//! ```text
//! M(x_o) = sum over lights l of integral over the object's surface of
//!          R(x_i, n_i, w_12,l; x_o, n_o) E_l cos_i F_t(cos_i, eta) V_l(x_i) dA(x_i)
//! ```
//!
//! with `R` the exitance per unit entering flux ([`DirectionalDipole::exitance_per_flux`]),
//! `w_12,l` light `l`'s direction refracted in at `x_i`, shading normals (interpolated vertex
//! normals) at both ends and ray-cast visibility, as the truth has them. `M` is radiant
//! exitance as the truth's is: the flux per unit area that leaves, through the interface's
//! Fresnel transmittance (the model's `C_phi`, `C_E` weights), before any outgoing lobe.
//!
//! # Quadrature
//!
//! Per receiver and channel, each triangle is split in four recursively until a piece of
//! radius `R` at distance `d` from the receiver satisfies `2 R kappa <= fineness`, with
//! `kappa = sigma_tr + 3 / sqrt(d^2 + l^2)` (the truth's measure of how fast the kernel changes;
//! `l = 1 / (3 sigma_t')`, the width of the real source's peak, or a [`Custom`] kernel's; at
//! `l = 0` the pieces shrink with their distance to the receiver), and is then one point at its
//! centroid: `E_t` and the kernel evaluated there, times its area. Past 5 diffusion lengths
//! (`sigma_tr (d - R) > 5`, where the kernel is under `e^-5` of its value near the receiver, and
//! a receiver lit only from there is under the study's 1% lit floor) the fineness relaxes by
//! `e^((sigma_tr (d - R) - 5) / 4)`; pieces past 30 diffusion lengths are skipped. Without
//! that, a dark channel (ketchup's green, `sigma_tr` 1.25/mm) would be split to 0.1 mm over the
//! whole sphere for every receiver. The midpoint rule's error falls as
//! `fineness^2`; [`exitance`] takes [`FINENESS`], and the tests measure
//! the change against half of it.

use super::bvh::Bvh;
use super::{occluders, per_translucent_object, ray_offset, reaching};
use crate::mesh::Mesh;
use crate::optics::directional_dipole::{Diffusion, DirectionalDipole, Strength, refract_in};
use crate::optics::{Dipole, fresnel};
use crate::scene::build::PreparedScene;
use glam::DVec3;
use rayon::prelude::*;

/// A kernel in place of the directional dipole's: `(the object's dipole in this channel, x_i,
/// n_i, w_12, x_o, n_o)` to the exitance per unit entering flux.
pub type Kernel = dyn Fn(&Dipole, DVec3, DVec3, DVec3, DVec3, DVec3) -> f64 + Sync;

/// A [`Kernel`] in place of the directional dipole's, with the width of its peak at the receiver.
#[derive(Clone, Copy)]
pub struct Custom<'a> {
    /// The kernel.
    pub kernel: &'a Kernel,
    /// The width `l` of the kernel's peak at the receiver, in mean free paths `1 / sigma_t'`:
    /// 1/3 for the standard dipole (its real source's depth). 0 for a kernel that is singular
    /// there (as `1/d`): the pieces are then refined towards the receiver geometrically, at a
    /// fixed ratio of their radius to their distance.
    pub width: f64,
}

/// The fineness [`exitance`] integrates at.
pub const FINENESS: f64 = 0.4;
/// Pieces further than this many diffusion lengths from the receiver are left out (`e^-30`).
const CUT: f64 = 30.0;
/// Within this many diffusion lengths the fineness is [`FINENESS`]'s; past it, coarser.
const NEAR: f64 = 5.0;
/// Deepest split of one triangle.
const MAX_DEPTH: u32 = 16;

/// Per object (scene order), per vertex, RGB: the directional dipole's exitance (see the
/// module's documentation) with the paper's diffusion coefficient; zero for opaque objects.
pub fn exitance(scene: &PreparedScene) -> Vec<Vec<[f64; 3]>> {
    exitance_with(scene, Diffusion::Grosjean, Strength::Paper, FINENESS, None)
}

/// [`exitance`] with a chosen diffusion coefficient, source strength and fineness, and, with `kernel`, any other
/// kernel of `(x_i, n_i, w_12, x_o, n_o)` per channel in place of the directional dipole's (the
/// tests integrate the standard dipole's `R_d` so to check the quadrature against the truth).
pub fn exitance_with(
    scene: &PreparedScene,
    diffusion: Diffusion,
    strength: Strength,
    fineness: f64,
    kernel: Option<Custom>,
) -> Vec<Vec<[f64; 3]>> {
    let casters = occluders(scene);
    let eps = ray_offset(scene);
    per_translucent_object(scene, |o, dipoles, _| {
        let count = o.mesh.positions().len();
        let models = dipoles.map(|d| DirectionalDipole::with_options(&d, diffusion, strength));
        let source = Sources { scene, casters: &casters, eps, eta: dipoles[0].eta };
        (0..count)
            .into_par_iter()
            .map(|v| {
                let x_o = o.mesh.positions()[v].as_dvec3();
                let n_o = o.mesh.vertex_normals()[v].as_dvec3().normalize();
                [0, 1, 2].map(|c| {
                    let model = &models[c];
                    let eval = |x_i: DVec3, n_i: DVec3, w: DVec3| match kernel {
                        Some(k) => (k.kernel)(&dipoles[c], x_i, n_i, w, x_o, n_o),
                        None => model.exitance_per_flux(x_i, n_i, w, x_o, n_o),
                    };
                    let receiver = Receiver {
                        x_o,
                        channel: c,
                        sigma_tr: model.sigma_tr,
                        width: kernel.map_or(1.0 / 3.0, |k| k.width) / model.sigma_t_prime,
                        fineness,
                    };
                    (0..o.mesh.triangles().len())
                        .map(|t| {
                            let corners = o.mesh.corners(t);
                            let bary = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
                            receiver.piece(&o.mesh, Piece { triangle: t, corners, bary, depth: 0 }, &source, &eval)
                        })
                        .sum::<f64>()
                })
            })
            .collect()
    })
}

/// What lights a point of the surface.
struct Sources<'a> {
    scene: &'a PreparedScene,
    casters: &'a Bvh,
    eps: f64,
    eta: f64,
}

impl Sources<'_> {
    /// Sum over lights of the entering flux per unit area times `kernel(x_i, n_i, w_12)`.
    fn at(&self, p: DVec3, n: DVec3, kernel: &dyn Fn(DVec3, DVec3, DVec3) -> f64) -> [f64; 3] {
        let mut out = [0.0; 3];
        for (wi, e, cos_i) in self.scene.lights.iter().filter_map(|l| reaching(l, self.casters, p, n, self.eps)) {
            let Some(w_12) = refract_in(wi, n, self.eta) else { continue };
            let k = kernel(p, n, w_12) * cos_i * fresnel::fresnel_transmittance(cos_i, self.eta);
            (0..3).for_each(|c| out[c] += e[c] * k);
        }
        out
    }
}

/// A piece of one mesh triangle, split `depth` times from the whole: its corners and their
/// barycentric coordinates in the triangle.
#[derive(Clone, Copy)]
struct Piece {
    /// The mesh triangle it is a piece of.
    triangle: usize,
    corners: [DVec3; 3],
    bary: [[f64; 3]; 3],
    depth: u32,
}

/// One receiver and channel's quadrature settings.
struct Receiver {
    x_o: DVec3,
    channel: usize,
    sigma_tr: f64,
    width: f64,
    fineness: f64,
}

impl Receiver {
    /// The integral over `piece` of a triangle of `mesh`, split until fine (see the module's
    /// documentation).
    fn piece(&self, mesh: &Mesh, piece: Piece, source: &Sources, eval: &dyn Fn(DVec3, DVec3, DVec3) -> f64) -> f64 {
        let Piece { triangle: t, corners, bary, depth } = piece;
        let centre = (corners[0] + corners[1] + corners[2]) / 3.0;
        let radius = corners.iter().map(|c| c.distance(centre)).fold(0.0, f64::max);
        let d = centre.distance(self.x_o);
        let lengths = self.sigma_tr * (d - radius);
        if lengths > CUT {
            return 0.0;
        }
        let kappa = self.sigma_tr + 3.0 / (d * d + self.width * self.width).sqrt();
        // Past NEAR diffusion lengths the kernel is under e^-NEAR of its value near the
        // receiver, and the fineness relaxes as e^(lengths - NEAR)/4, so the pieces' error
        // there still falls as e^(-lengths/2).
        let fineness = self.fineness * ((lengths - NEAR).max(0.0) / 4.0).exp();
        if 2.0 * radius * kappa <= fineness || depth >= MAX_DEPTH {
            let b = [0, 1, 2].map(|k| (bary[0][k] + bary[1][k] + bary[2][k]) / 3.0);
            let n = mesh.normal_at(t, b).as_dvec3();
            let area = 0.5 * (corners[1] - corners[0]).cross(corners[2] - corners[0]).length();
            // One channel at a time: the kernel is this channel's, the irradiance its share.
            return area * source.at(centre, n, eval)[self.channel];
        }
        let mid =
            |a: usize, b: usize| ((corners[a] + corners[b]) * 0.5, [0, 1, 2].map(|k| 0.5 * (bary[a][k] + bary[b][k])));
        let (m01, b01) = mid(0, 1);
        let (m12, b12) = mid(1, 2);
        let (m20, b20) = mid(2, 0);
        let children = [
            ([corners[0], m01, m20], [bary[0], b01, b20]),
            ([m01, corners[1], m12], [b01, bary[1], b12]),
            ([m20, m12, corners[2]], [b20, b12, bary[2]]),
            ([m01, m12, m20], [b01, b12, b20]),
        ];
        children
            .iter()
            .map(|(c, b)| {
                self.piece(mesh, Piece { triangle: t, corners: *c, bary: *b, depth: depth + 1 }, source, eval)
            })
            .sum()
    }
}
