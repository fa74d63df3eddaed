//! The transport kernel of a rigid translucent object (`material.model = "transport"`): the
//! radiative transfer through its own mesh and medium, tabulated between patches of its
//! surface (`mesh::patches`), which corrects the dipole's half-space answer where the object's
//! shape returns light the half-space loses (on a 2 cm marble sphere the dipole is 26% too
//! dark).
//!
//! The light enters along its own refracted direction `d`, which the kernel carries in a
//! low-order basis: per pair of patches, the flux that leaves through `I` per unit flux
//! transmitted into `J` is
//!
//! `W_IJ(d, x) = W0_IJ + Wmu_IJ (mu - mu_bar) + Wt_IJ (t . u_JI) + Wx_IJ ((x - x_J) . u_JI)`,
//!
//! `mu` the cosine of `d` with the inward normal, `t` its tangential part, `u_JI` the unit
//! direction in `J`'s tangent plane towards `I` (`Patches::toward`) and `mu_bar` the mean cosine
//! of the walks' entries ([`EntryBasis`]); `Wmu` and `Wt` are 0 between patches more than
//! [`entry_reach`] apart ([`TransportKernel::near`] lists those within). The last
//! term carries where in `J` the light enters, `x` against the entries' mean `x_J`
//! (`Patches::entry_centres`): at a terminator the light enters on a patch's lit side, and a
//! kernel of uniform entry moved it towards the unlit side, 8 to 13% too bright there on a
//! marble sphere in green and blue. The four
//! rows are the least-squares projection of the walks' response on that basis, estimated once
//! by random walks in the mesh
//! (`reference::rte_mesh::kernel`) with entry directions drawn as diffuse light refracts in,
//! with no light or camera in it. A kernel of the normal entry alone was -10% at a marble
//! sphere's terminator, where grazing light refracts into a beam running sideways just under
//! the surface (docs/PHYSICS.md, "The transport kernel").
//!
//! Per frame, with `E_t` the splat's transmitted irradiance at a sample, `mu_s` and `t_s` its
//! lights' refracted cosine and tangential direction averaged by their flux, and `M_d` the
//! dipole's exitance at the vertices:
//!
//! - `Phi_J = sum A_s E_t`, `Phimu_J = sum A_s E_t (mu_s - mu_bar)`, `T_J = sum A_s E_t t_s`
//!   and `X_J = sum A_s E_t (x_s - x_J)` over the samples in `J` ([`PatchFlux`]);
//! - `F_I = max(0, sum_J (W0_IJ Phi_J exp(g_IJ X_J . u_JI / Phi_J) + Wmu_IJ Phimu_J + Wt_IJ
//!   T_J . u_JI)) / A_I` with `g_IJ = Wx_IJ / W0_IJ` (the offset's row read as an
//!   exponential's rate, [`offset_factor`]), the
//!   kernel's exitance averaged over `I` (the basis is linear in the entry, and may extrapolate
//!   below zero);
//! - `D_I = sum_(v in I) A_v M_d(v) / A_I`, the dipole's, alike (`A_v` the vertex's dual cell);
//! - `M(v) = M_d(v) sum_I w_vI (F_I / D_I) / sum_I w_vI` over the vertex's nearest patches
//!   with `D_I > 0`, with the weights of `Patches::neighbours`.
//!
//! The dipole keeps the detail under a patch (it follows the irradiance at every sample), the
//! kernel sets each patch's level. The patches' ratios are blended, not their fluxes: a blend of
//! fluxes leans on the brightest patch, and at a terminator that is the lit one, whose ratio is
//! the lowest (docs/PHYSICS.md, "Blending the patches' ratios"). The f32 twin is
//! `glsl/transport.comp`.

use crate::mesh::Mesh;
use crate::mesh::patches::Patches;
use glam::DVec3;

/// How far the entry's rows reach, in patch radii (`Patches::radius`), at least
/// ([`entry_reach`]): `Wmu_IJ` and `Wt_IJ` are walked only between patches whose centres are
/// closer, and are 0 beyond. Farther, the entry's depth and tilt move little light while their
/// rows' estimates are the noisiest (their weights are the basis functions over their
/// variances). On the 2 cm marble sphere, against the photon reference at 24 and 48 divisions,
/// this reach took the terminator's bias from -10% to -3 to -5%, where unbounded rows added 3 to
/// 7 points of noise and bias on the unlit side (docs/PHYSICS.md, "The transport kernel").
pub const ENTRY_REACH: f64 = 3.0;

/// How far the entry's rows reach in a channel of diffusion length `diffusion_length`, between
/// patches of radius `radius`: [`ENTRY_REACH`] radii, or one diffusion length where that is
/// farther. Grazing light's tilt carries about a diffusion length: on the 2 cm skim milk sphere
/// (18.4, 10.4, 3.5 mm) three radii (5 mm) left red and green 6 and 4% too dark, 10.1, 7.53% per
/// vertex; a diffusion length took them to 5.45, 6.32%, and the marble sphere moved within 0.2
/// points (docs/PHYSICS.md).
pub fn entry_reach(radius: f64, diffusion_length: f64) -> f64 {
    (ENTRY_REACH * radius).max(diffusion_length)
}

/// The largest exponent [`offset_factor`] takes, either way: a factor of `e^2`. On the marble
/// sphere the exponents stay under 1 (limits of 1, 2 and 4 gave the same figures); the limit
/// only bounds a far pair whose few walks gave a noisy `Wx / W0`.
pub const OFFSET_EXPONENT_LIMIT: f64 = 2.0;

/// How `W0_IJ Phi_J` changes where the light enters `J` off its entry centre:
/// `exp(g delta)` with the rate `g = Wx_IJ / W0_IJ` and `delta = X_J . u_JI / Phi_J` the light's
/// mean offset towards `I` (`x_u` is `X_J . u_JI`, `phi` is `Phi_J`); 1 where `W0_IJ Phi_J` is
/// not positive. The walks estimate `Wx` as a least-squares slope, and for a Gaussian spread
/// of entries the slope over the mean is an exponential's rate exactly (Stein's lemma). The
/// transport falls off exponentially with the distance the light runs, so the exponential
/// follows a patch whose light sits at its edge where the line falls short (the marble sphere:
/// 4.69, 4.95, 5.00% with the line, 4.28, 4.56, 4.11% with the exponential, docs/PHYSICS.md).
pub fn offset_factor(w0: f64, wx: f64, x_u: f64, phi: f64) -> f64 {
    let den = w0 * phi;
    if den > 0.0 { ((wx * x_u) / den).clamp(-OFFSET_EXPONENT_LIMIT, OFFSET_EXPONENT_LIMIT).exp() } else { 1.0 }
}

/// How the kernel's walks enter, and the moments of that entry the basis needs: directions
/// refracted from diffuse light, `sin^2 theta_t` uniform on `[0, S]` with `S = min(1,
/// 1/eta^2)` (a cosine-weighted incidence has `sin^2 theta_i` uniform, and Snell's law divides
/// it by `eta^2`), the azimuth uniform.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EntryBasis {
    /// `S`, the largest `sin^2 theta_t`.
    pub s_max: f64,
}

impl EntryBasis {
    /// The entry into a medium of relative index `eta`.
    pub fn new(eta: f64) -> EntryBasis {
        EntryBasis { s_max: (1.0 / (eta * eta)).min(1.0) }
    }

    /// The entry's cosine `mu = sqrt(1 - S u)` and azimuth `2 pi v` for uniform `u`, `v`.
    pub fn sample(&self, u: f64, v: f64) -> (f64, f64) {
        ((1.0 - self.s_max * u).max(0.0).sqrt(), std::f64::consts::TAU * v)
    }

    /// `mu_bar = E[mu] = 2 (1 - (1 - S)^(3/2)) / (3 S)`.
    pub fn mu_mean(&self) -> f64 {
        let s = self.s_max;
        2.0 * (1.0 - (1.0 - s).powf(1.5)) / (3.0 * s)
    }

    /// `Var mu = E[mu^2] - mu_bar^2`, `E[mu^2] = 1 - S / 2`.
    pub fn mu_variance(&self) -> f64 {
        (1.0 - self.s_max / 2.0 - self.mu_mean().powi(2)).max(0.0)
    }

    /// `E[(t . u)^2] = E[sin^2 theta_t] / 2 = S / 4` for any unit tangent `u`.
    pub fn tilt_variance(&self) -> f64 {
        self.s_max / 4.0
    }
}

/// Per patch and channel, the transmitted fluxes the kernel's three rows act on.
#[derive(Clone, Debug, PartialEq)]
pub struct PatchFlux {
    /// `Phi_J`.
    pub phi: PerPatch,
    /// `Phimu_J`.
    pub phi_mu: PerPatch,
    /// `T_J`, per channel a tangential vector.
    pub tilt: Vec<[DVec3; 3]>,
    /// `X_J`, per channel a vector from the entries' mean.
    pub offset: Vec<[DVec3; 3]>,
}

/// One sample's part of [`PatchFlux`]: its patch, its area, its transmitted irradiance per
/// channel, and its lights' flux-weighted refracted cosine `mu_s` and tangential direction
/// `t_s` ([`SampleFlux::from_splat`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleFlux {
    /// Its patch.
    pub patch: u32,
    /// Its area `A_s`.
    pub area: f64,
    /// `E_t`, RGB.
    pub e: [f64; 3],
    /// `mu_s`.
    pub mu: f64,
    /// `t_s`.
    pub tilt: DVec3,
    /// `x_s`, where it lies (for a vertex standing for its cell, the cell's centroid,
    /// `patches::cell_centroids`).
    pub position: DVec3,
}

impl SampleFlux {
    /// A sample's part from what the splat writes: `e` its transmitted irradiance (every
    /// light's), `d_key` the key lights' refracted directions summed weighted by their
    /// transmitted flux (the sum over channels) and `w_key` that flux, `n` its outward normal.
    /// The other lights' (the environment's directions) are taken to enter as the kernel's
    /// walks do, diffusely: at `mu_bar`, without tilt. So, with `w` the flux of every light,
    /// `mu_s = (-d_key . n + (w - w_key) mu_bar) / w` and `t_s = (d_key - (d_key . n) n) / w`.
    pub fn from_splat(
        (patch, position): (u32, DVec3),
        area: f64,
        e: [f64; 3],
        (d_key, w_key): (DVec3, f64),
        n: DVec3,
        mu_bar: f64,
    ) -> SampleFlux {
        let w = e.iter().sum::<f64>();
        let (mu, tilt) = if w > 0.0 {
            let along = d_key.dot(n);
            ((-along + (w - w_key) * mu_bar) / w, (d_key - n * along) / w)
        } else {
            (mu_bar, DVec3::ZERO)
        };
        SampleFlux { patch, area, e, mu, tilt, position }
    }
}

/// The kernel of one object (see the module's documentation).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TransportKernel {
    /// The patches it is tabulated between.
    pub patches: Patches,
    /// Per channel, `W0_IJ` at `[I * K + J]`, `K` patches.
    pub flux: [Vec<f64>; 3],
    /// Per channel, `Wmu_IJ`, alike.
    pub depth: [Vec<f64>; 3],
    /// Per channel, `Wt_IJ`, alike.
    pub sideways: [Vec<f64>; 3],
    /// Per channel, `Wx_IJ` (per unit length), alike.
    pub shift: [Vec<f64>; 3],
    /// `mu_bar` of the walks' entry ([`EntryBasis::mu_mean`]).
    pub mu_mean: f64,
    /// Walks per patch and channel it was estimated with.
    pub walks: u64,
}

/// Per patch, RGB.
pub type PerPatch = Vec<[f64; 3]>;

impl TransportKernel {
    /// The fluxes of `points` per patch ([`PatchFlux`]), their offsets taken from `entry`,
    /// the entries' means where the object stands now (`Patches::entry_centres`).
    pub fn patch_flux(&self, points: impl Iterator<Item = SampleFlux>, entry: &[DVec3]) -> PatchFlux {
        let k = self.patches.len();
        let zero = || vec![[DVec3::ZERO; 3]; k];
        let mut flux = PatchFlux { phi: vec![[0.0; 3]; k], phi_mu: vec![[0.0; 3]; k], tilt: zero(), offset: zero() };
        for s in points {
            let j = s.patch as usize;
            for c in 0..3 {
                let f = s.area * s.e[c];
                flux.phi[j][c] += f;
                flux.phi_mu[j][c] += f * (s.mu - self.mu_mean);
                flux.tilt[j][c] += s.tilt * f;
                flux.offset[j][c] += (s.position - entry[j]) * f;
            }
        }
        flux
    }

    /// `F_I`: per patch, the kernel's exitance averaged over it under the fluxes `flux` (at
    /// least 0), its
    /// patches `placed` where the object stands now ([`TransportKernel::placed`]: the tilt's
    /// axes follow a rigid move).
    pub fn transport_exitance(&self, flux: &PatchFlux, placed: &Patches) -> PerPatch {
        let k = self.patches.len();
        let near = self.near();
        (0..k)
            .map(|i| {
                let mut f = [0.0; 3];
                for j in 0..k {
                    let (at, u) = (i * k + j, placed.toward(j, i));
                    for (c, f) in f.iter_mut().enumerate() {
                        let (w0, phi) = (self.flux[c][at], flux.phi[j][c]);
                        *f += w0 * phi * offset_factor(w0, self.shift[c][at], flux.offset[j][c].dot(u), phi);
                    }
                }
                for &j in &near[i] {
                    let (j, at) = (j as usize, i * k + j as usize);
                    let u = placed.toward(j, i);
                    for (c, f) in f.iter_mut().enumerate() {
                        *f += self.depth[c][at] * flux.phi_mu[j][c] + self.sideways[c][at] * flux.tilt[j][c].dot(u);
                    }
                }
                // The basis is linear in the entry: where a noisy or strongly tilted row would
                // take a patch below zero, it receives nothing.
                f.map(|f| (f / self.patches.area[i]).max(0.0))
            })
            .collect()
    }

    /// The kernel with each pair's `W0` replaced by the mean of its two estimates. The transfer
    /// is reciprocal: under a uniform irradiance what `J` sends out through `I` equals what `I`
    /// sends out through `J`, `A_J W0_IJ = A_I W0_JI` (the walks enter as diffuse light
    /// refracts in and leave through the same Fresnel boundary). The walks entering `J` and
    /// those entering `I` estimate that one number on independent streams, so their mean has
    /// about half the variance of either; the far pairs, which a few walks reach, gain most.
    /// `Wmu`, `Wt` and `Wx` have no such partner and are kept.
    pub fn reciprocal(mut self) -> TransportKernel {
        let (k, area) = (self.patches.len(), &self.patches.area);
        for w in &mut self.flux {
            for i in 0..k {
                for j in (i + 1)..k {
                    let both = 0.5 * (area[j] * w[i * k + j] + area[i] * w[j * k + i]);
                    if area[i] > 0.0 && area[j] > 0.0 {
                        (w[i * k + j], w[j * k + i]) = (both / area[j], both / area[i]);
                    }
                }
            }
        }
        self
    }

    /// Per patch `I`, the patches `J` whose `Wmu_IJ` or `Wt_IJ` is not 0 in some channel (those
    /// within a channel's [`entry_reach`]), ascending.
    pub fn near(&self) -> Vec<Vec<u32>> {
        let k = self.patches.len();
        let nonzero = |at: usize| (0..3).any(|c| self.depth[c][at] != 0.0 || self.sideways[c][at] != 0.0);
        (0..k).map(|i| (0..k).filter(|&j| nonzero(i * k + j)).map(|j| j as u32).collect()).collect()
    }

    /// Its four rows, `W0`, `Wmu`, `Wt` and `Wx`, each per channel.
    pub fn rows(&self) -> impl Iterator<Item = &[Vec<f64>; 3]> {
        [&self.flux, &self.depth, &self.sideways, &self.shift].into_iter()
    }

    /// `D_I`: per patch, the dipole's exitance `dipole` (per vertex) averaged over it by the
    /// vertices' `cells` (the mesh's dual cells, or a level of detail's: zero off the level);
    /// 0 where none of its vertices has a cell.
    pub fn dipole_exitance(&self, dipole: &[[f64; 3]], cells: &[f64]) -> PerPatch {
        let (mut d, mut area) = (vec![[0.0; 3]; self.patches.len()], vec![0.0; self.patches.len()]);
        for (v, &i) in self.patches.of_vertex.iter().enumerate() {
            if cells[v] > 0.0 {
                (0..3).for_each(|c| d[i as usize][c] += cells[v] * dipole[v][c]);
                area[i as usize] += cells[v];
            }
        }
        d.iter_mut().zip(&area).for_each(|(d, &a)| d.iter_mut().for_each(|x| *x = if a > 0.0 { *x / a } else { 0.0 }));
        d
    }

    /// `M(v)`: the dipole's `m` at a point with patch neighbours `near` scaled by the blend of
    /// their ratios `F / D` over those with `D > 0`; `m` itself where none has, or where the
    /// scaled value is not finite (an overflowed `m` or ratio stays the dipole's, never NaN).
    pub fn scaled(m: [f64; 3], near: &[(u32, f64)], f: &[[f64; 3]], d: &[[f64; 3]]) -> [f64; 3] {
        [0, 1, 2].map(|c| {
            let (mut ratio, mut weight) = (0.0, 0.0);
            for &(i, w) in near {
                let (f, d) = (f[i as usize][c], d[i as usize][c]);
                if d > 0.0 {
                    ratio += w * (f / d);
                    weight += w;
                }
            }
            let scaled = m[c] * (ratio / weight);
            if weight > 0.0 && scaled.is_finite() { scaled } else { m[c] }
        })
    }

    /// The model's exitance at every vertex from the dipole's `dipole` at the vertices whose
    /// `cells` are positive (the whole mesh's dual cells, or a level of detail's) and the
    /// fluxes `flux` (the f64 twin of `glsl/transport.comp`), each vertex blended from `near`
    /// (per vertex, its `Patches::neighbours` among the patches `placed`); the others as they
    /// are.
    pub fn exitance(
        &self,
        (flux, placed): (&PatchFlux, &Patches),
        (dipole, cells): (&[[f64; 3]], &[f64]),
        near: &[Vec<(u32, f64)>],
    ) -> Vec<[f64; 3]> {
        let (f, d) = (self.transport_exitance(flux, placed), self.dipole_exitance(dipole, cells));
        (0..dipole.len())
            .map(|v| if cells[v] > 0.0 { Self::scaled(dipole[v], &near[v], &f, &d) } else { dipole[v] })
            .collect()
    }

    /// Its patches on `mesh`, the object as it stands now (`Patches::placed_on`): a rigid move
    /// keeps the kernel, and the patches' centres follow the vertices.
    pub fn placed(&self, mesh: &Mesh) -> Patches {
        self.patches.placed_on(mesh)
    }

    /// Each vertex's patch neighbours on `mesh` (`placed` its patches there).
    pub fn vertex_neighbours(placed: &Patches, mesh: &Mesh) -> Vec<Vec<(u32, f64)>> {
        use rayon::prelude::*;
        mesh.positions()
            .par_iter()
            .zip(mesh.vertex_normals())
            .map(|(p, n)| placed.neighbours(&placed.features(p.as_dvec3(), n.as_dvec3())))
            .collect()
    }

    /// The patch of a sample on `triangle` of `mesh` at `barycentric`: that of the corner
    /// whose dual cell holds it (the largest coordinate), so that the samples split the
    /// transmitted flux between patches as the vertices' cells split the surface.
    pub fn sample_patch(&self, mesh: &Mesh, triangle: u32, barycentric: [f32; 3]) -> u32 {
        let b = barycentric;
        let corner = if b[0] >= b[1] && b[0] >= b[2] {
            0
        } else if b[1] >= b[2] {
            1
        } else {
            2
        };
        self.patches.of_vertex[mesh.triangles()[triangle as usize][corner] as usize]
    }

    /// Bytes of device memory the kernel takes: `W0` and `Wx` as f32 RGBA per pair of
    /// patches, and two RGBA per pair within the reach ([`TransportKernel::near`]).
    pub fn device_bytes(&self) -> u64 {
        let near: usize = self.near().iter().map(Vec::len).sum();
        (self.patches.len() as u64).pow(2) * 32 + near as u64 * 32
    }
}

#[cfg(test)]
mod tests {
    use super::{EntryBasis, OFFSET_EXPONENT_LIMIT, TransportKernel, offset_factor};

    #[test]
    fn a_vertex_blends_its_patches_ratios_so_a_lit_patch_does_not_set_a_terminators_scale() {
        // A lit patch (ratio 1.1) and a dark one (ratio 2) weighed alike: the scale is their mean,
        // where a blend of fluxes would give 13 / 11, the lit patch's nearly.
        let (f, d) = ([[11.0; 3], [2.0; 3]], [[10.0; 3], [1.0; 3]]);
        let near = [(0u32, 1.0), (1, 1.0)];
        assert!(TransportKernel::scaled([1.0; 3], &near, &f, &d).iter().all(|m| (m - 1.55).abs() < 1e-12));
        // A patch the dipole leaves dark has no ratio; with none the dipole's value stays.
        let dark = [[0.0; 3], [1.0; 3]];
        assert!(TransportKernel::scaled([1.0; 3], &near, &f, &dark).iter().all(|m| (m - 2.0).abs() < 1e-12));
        assert_eq!(TransportKernel::scaled([3.0; 3], &near, &f, &[[0.0; 3]; 2]), [3.0; 3]);
        // An overflowed ratio leaves the dipole's value, never Inf.
        let tiny = [[1e-310; 3], [1.0; 3]];
        assert_eq!(TransportKernel::scaled([3.0; 3], &near, &[[1e10; 3], [1.0; 3]], &tiny), [3.0; 3]);
    }

    #[test]
    fn the_offset_factor_is_the_rows_exponential_and_one_where_no_light_or_no_pair() {
        // g = Wx / W0 = 50 per unit length, the light's mean 4 mm towards I: e^0.2.
        let (w0, wx, phi) = (0.02, 1.0, 3.0);
        let f = offset_factor(w0, wx, 0.004 * phi, phi);
        assert!((f - 0.2f64.exp()).abs() < 1e-12, "{f}");
        // A slope close to the line's near 0, and the exponent held at its limit far out.
        assert!((offset_factor(w0, wx, 1e-5 * phi, phi) - (1.0 + 50.0 * 1e-5)).abs() < 1e-6);
        assert_eq!(offset_factor(w0, wx, -phi, phi), (-OFFSET_EXPONENT_LIMIT).exp());
        // No light in J, or no pair: W0 Phi stands as it is (and is 0).
        assert_eq!(offset_factor(w0, wx, 0.0, 0.0), 1.0);
        assert_eq!(offset_factor(0.0, wx, 0.01, phi), 1.0);
    }

    #[test]
    fn the_entrys_closed_form_moments_are_those_of_its_samples() {
        for eta in [1.0, 1.3, 1.5] {
            let entry = EntryBasis::new(eta);
            let n = 200_000;
            let (mut m1, mut m2, mut t2) = (0.0, 0.0, 0.0);
            for k in 0..n {
                // A stratified grid in (u, v): the sample mean converges fast.
                let (u, v) = ((k as f64 + 0.5) / n as f64, ((k * 7919) % n) as f64 / n as f64);
                let (mu, phi) = entry.sample(u, v);
                m1 += mu;
                m2 += mu * mu;
                t2 += (1.0 - mu * mu) * phi.cos().powi(2);
            }
            let (m1, m2, t2) = (m1 / n as f64, m2 / n as f64, t2 / n as f64);
            assert!((m1 - entry.mu_mean()).abs() < 1e-4, "eta {eta}: mean {m1} against {}", entry.mu_mean());
            assert!((m2 - m1 * m1 - entry.mu_variance()).abs() < 1e-4, "eta {eta}: variance");
            assert!(
                (t2 - entry.tilt_variance()).abs() < 1e-3,
                "eta {eta}: tilt {t2} against {}",
                entry.tilt_variance()
            );
        }
    }
}
