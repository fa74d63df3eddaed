//! Single scattering between two surface points: Jensen et al. 2001's first-order term (their
//! Eq. 3, after Hanrahan and Krueger 1993) resolved in space, as a BSSRDF from the point where
//! light enters to the point where it leaves, rather than collapsed to the local half-space's
//! `R1` ([`super::single_scatter`]). f64, per colour channel.
//!
//! # The kernel
//!
//! Light that refracts in at `x_i` travels inside along `w_12` (Snell's law). Per unit flux that
//! entered, the beam's power at distance `t` along it is `e^(-sigma_t t)`, and it scatters at
//! the rate `sigma_s p(cos psi)` per unit length into each unit solid angle. Light scattered
//! at `y = x_i + t w_12` towards the surface point `x_o` (outward normal `n_o`) crosses
//! `r = |x_o - y|` of medium, meets the surface at cosine `cos theta = (x_o - y) . n_o / r` and
//! leaves through the Fresnel transmittance from inside. The radiant exitance at `x_o` per unit
//! entering flux is
//!
//! ```text
//! K1(x_i, w_12; x_o, n_o) = integral_0^inf sigma_s p(cos psi) e^(-sigma_t (t + r))
//!                           F_t(cos theta, 1/eta) cos theta / r^2 dt,
//! cos psi = w_12 . (x_o - y) / r
//! ```
//!
//! with `cos theta <= 0` contributing nothing (the point is behind `x_o`'s tangent plane).
//! Integrated over the points of a plane it is `R1` exactly (the tests check it): each scatter
//! point sees the plane's patches under the solid angle `cos theta dA / r^2`. On a curved
//! surface it keeps what `R1` loses: the beam carries light along `w_12` before it scatters, so
//! near a terminator light that entered on the lit side leaves on the dark side.
//!
//! What it leaves out: light reflected internally before it leaves (it is lost, as in `R1`),
//! and light whose straight path from `y` to `x_o` would leave and re-enter a concave surface.
//!
//! # Quadrature
//!
//! The beam passes the receiver at `t* = (x_o - x_i) . w_12`, at distance
//! `h = |(x_o - x_i) - t* w_12|`, and `1/r^2` is a Lorentzian of width `h` there. Substituting
//! `t = t* + h tan phi` makes `dt / r^2 = dphi / h` exactly, and leaves the exponential, which
//! falls over `1 / sigma_t`. The range of `phi` (from `t = 0` to `t` at infinity) is split at
//! the closest approach, where `t - t*` is 4^-4 to 16 mean free paths (by fours: when `h` is
//! small the exponential falls within the last `h / mfp` of the range) and where the path to
//! `x_o` crosses the critical angle. There the transmittance starts as a square root, so the
//! piece after it is taken in `u` with `phi = a + (b - a) u^2`. Each piece takes
//! [`POINTS`]-point Gauss-Legendre; the tests measure the rule against one four times finer.
//! The kernel grows as `1/|x_o - x_i|` where the two meet, and is infinite at `x_o = x_i`
//! (`h = 0`): `h` is held at least [`H_MIN`] mean free paths, so it stays finite (the
//! quadrature of the surface integral never puts a receiver on a source point). The f32 twin is
//! `glsl/common/beam_single.glsl`; `tests/optics_gpu.rs` compares the two.

use super::fresnel::fresnel_transmittance;
use super::quadrature::gauss_legendre;
use super::single_scatter::henyey_greenstein;
use glam::DVec3;
use std::f64::consts::FRAC_PI_2;
use std::sync::OnceLock;

/// Gauss-Legendre nodes per piece of the `phi` range.
pub const POINTS: usize = 8;
/// Below this reduced albedo a channel's light is mostly once scattered, and single
/// scattering is closer to the radiative transfer than the dipole: on the half-space `R1` beats
/// the dipole in all 75 preset channels under 0.3 and loses in all above 0.42 (docs/optics.md,
/// "Single scattering"); on the 2 cm ketchup sphere this kernel cuts green's and blue's error
/// 2 to 4 times (docs/STUDY.md).
pub const ALBEDO_BELOW: f64 = 0.3;
/// The least distance from the beam's line, in mean free paths, the kernel is evaluated at.
pub const H_MIN: f64 = 1e-6;

/// Once-scattered light of one channel: the scattering and extinction coefficients (per scene
/// unit), the Henyey-Greenstein `g` and the relative index `eta` (inside over outside).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamSingle {
    /// Scattering coefficient `sigma_s`, per scene unit.
    pub sigma_s: f64,
    /// Extinction coefficient `sigma_t = sigma_a + sigma_s`, per scene unit.
    pub sigma_t: f64,
    /// Henyey-Greenstein mean cosine.
    pub g: f64,
    /// Relative index of refraction, inside over outside.
    pub eta: f64,
}

impl BeamSingle {
    /// The medium a dipole channel stands for: reduced coefficients with isotropic scattering,
    /// the medium `reference::rte_mesh` walks.
    pub fn from_dipole(d: &super::Dipole) -> Self {
        Self { sigma_s: d.sigma_t_prime * d.alpha_prime, sigma_t: d.sigma_t_prime, g: 0.0, eta: d.eta }
    }

    /// `K1(x_i, w_12; x_o, n_o)`, the radiant exitance at `x_o` per unit flux that entered at
    /// `x_i` along `w_12` (see the module's documentation). `w_12` and `n_o` are unit vectors.
    pub fn exitance_per_flux(&self, x_i: DVec3, w_12: DVec3, x_o: DVec3, n_o: DVec3) -> f64 {
        self.exitance_with(x_i, w_12, x_o, n_o, rule())
    }

    /// [`Self::exitance_per_flux`] with `n` points per piece (for measuring the rule).
    pub fn exitance_points(&self, x_i: DVec3, w_12: DVec3, x_o: DVec3, n_o: DVec3, n: usize) -> f64 {
        self.exitance_with(x_i, w_12, x_o, n_o, &gauss_legendre(n))
    }

    fn exitance_with(&self, x_i: DVec3, w_12: DVec3, x_o: DVec3, n_o: DVec3, rule: &(Vec<f64>, Vec<f64>)) -> f64 {
        let d = x_o - x_i;
        let t_star = d.dot(w_12);
        let mfp = 1.0 / self.sigma_t;
        // At `x_o` on the beam's line the kernel is infinite; held finite at H_MIN mean free paths.
        let h = (d - t_star * w_12).length().max(H_MIN * mfp);
        if !h.is_finite() {
            return 0.0;
        }
        let phi_at = |t: f64| ((t - t_star) / h).atan();
        let start = phi_at(0.0);
        // (phi, whether the transmittance starts there as a square root).
        let mut breaks = vec![(start, false), (FRAC_PI_2, false)];
        // Past the closest approach the exponential falls over a mean free path in t, which is
        // the last h / mfp of the range in phi when h is small: geometric breaks follow it.
        let plain = [0.0, 1.0 / 256.0, 1.0 / 64.0, 1.0 / 16.0, 0.25, 1.0, 4.0, 16.0].map(|k| (t_star + k * mfp, false));
        for (t, kink) in plain.into_iter().chain(self.critical_distances(d, w_12, n_o).map(|t| (t, true))) {
            let phi = phi_at(t);
            if phi > start && phi < FRAC_PI_2 {
                breaks.push((phi, kink));
            }
        }
        breaks.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (nodes, weights) = rule;
        let mut sum = 0.0;
        for pair in breaks.windows(2) {
            let ((a, kink), (b, _)) = (pair[0], pair[1]);
            for (x, w) in nodes.iter().zip(weights) {
                let u = 0.5 * (x + 1.0);
                // After a kink, phi = a + (b - a) u^2 makes the square root smooth in u.
                let (phi, jacobian) =
                    if kink { (a + (b - a) * u * u, (b - a) * u * w) } else { (a + (b - a) * u, 0.5 * (b - a) * w) };
                sum += jacobian * self.integrand(phi, t_star, h, d, w_12, n_o);
            }
        }
        self.sigma_s * sum / h
    }

    /// The distances along the beam where the path to `x_o` meets the surface at the critical
    /// angle (where the transmittance starts, with a kink): the roots `t >= 0` of
    /// `((d - t w) . n)^2 = mu_c^2 |d - t w|^2` on the side where `(d - t w) . n > 0`.
    fn critical_distances(&self, d: DVec3, w: DVec3, n: DVec3) -> impl Iterator<Item = f64> {
        let mu_sq = 1.0 - 1.0 / (self.eta * self.eta);
        let (a, b, c, e) = (d.dot(n), w.dot(n), d.length_squared(), d.dot(w));
        let (qa, qb, qc) = (b * b - mu_sq, 2.0 * (mu_sq * e - a * b), a * a - mu_sq * c);
        let disc = qb * qb - 4.0 * qa * qc;
        let roots = if self.eta > 1.0 && disc >= 0.0 && qa.abs() > 1e-12 {
            let q = -0.5 * (qb + qb.signum() * disc.sqrt());
            [q / qa, if q != 0.0 { qc / q } else { f64::NAN }]
        } else {
            [f64::NAN; 2]
        };
        roots.into_iter().filter(move |t| *t >= 0.0 && a - t * b > 0.0)
    }

    /// The integrand in `phi` (`t = t* + h tan phi`, `r = h sec phi`), without `sigma_s / h`.
    fn integrand(&self, phi: f64, t_star: f64, h: f64, d: DVec3, w_12: DVec3, n_o: DVec3) -> f64 {
        let t = (t_star + h * phi.tan()).max(0.0);
        let v = d - t * w_12;
        let r = v.length();
        let cos_theta = v.dot(n_o) / r;
        // Behind x_o's tangent plane, or at x_o itself (also NaN): nothing leaves towards it.
        if cos_theta.is_nan() || cos_theta <= 0.0 || r <= 0.0 {
            return 0.0;
        }
        let travel = self.sigma_t * (t + r);
        if travel > 700.0 {
            return 0.0;
        }
        let cos_psi = w_12.dot(v) / r;
        henyey_greenstein(cos_psi, self.g)
            * (-travel).exp()
            * fresnel_transmittance(cos_theta, 1.0 / self.eta)
            * cos_theta
    }
}

/// The [`POINTS`]-point rule, computed once.
fn rule() -> &'static (Vec<f64>, Vec<f64>) {
    static RULE: OnceLock<(Vec<f64>, Vec<f64>)> = OnceLock::new();
    RULE.get_or_init(|| gauss_legendre(POINTS))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::directional_dipole::refract_in;
    use crate::optics::single_scatter::reflectance;
    use std::f64::consts::PI;

    /// `integral K1 dA` over the plane `z = 0` (normal +z) for light from `w_in`, by
    /// `rho = e^u` Gauss-Legendre in `u` and `alpha`.
    fn plane_total(m: &BeamSingle, w_in: DVec3) -> f64 {
        let n = DVec3::Z;
        let w_12 = refract_in(w_in, n, m.eta).unwrap();
        let (u_lo, u_hi) = ((1e-7 / m.sigma_t).ln(), (60.0 / m.sigma_t).ln());
        let (xu, wu) = gauss_legendre(48);
        let (xa, wa) = gauss_legendre(24);
        let pieces = 24;
        let mut sum = 0.0;
        for p in 0..pieces {
            let (a, b) = (
                u_lo + (u_hi - u_lo) * p as f64 / pieces as f64,
                u_lo + (u_hi - u_lo) * (p + 1) as f64 / pieces as f64,
            );
            for (x, w) in xu.iter().zip(&wu) {
                let u = 0.5 * (a + b) + 0.5 * (b - a) * x;
                let rho = u.exp();
                for (y, v) in xa.iter().zip(&wa) {
                    let alpha = PI * (y + 1.0);
                    let x_o = DVec3::new(rho * alpha.cos(), rho * alpha.sin(), 0.0);
                    let k = m.exitance_per_flux(DVec3::ZERO, w_12, x_o, n);
                    sum += 0.5 * (b - a) * w * PI * v * k * rho * rho;
                }
            }
        }
        sum
    }

    #[test]
    fn over_a_plane_it_sums_to_the_half_spaces_r1() {
        for (albedo, eta) in [(0.02, 1.3), (0.067, 1.3), (0.5, 1.5), (0.9, 1.0)] {
            for cos_i in [1.0, 0.5] {
                let sigma_t = 1.3;
                let m = BeamSingle { sigma_s: albedo * sigma_t, sigma_t, g: 0.0, eta };
                let w_in = DVec3::new((1.0f64 - cos_i * cos_i).sqrt(), 0.0, cos_i);
                let total = plane_total(&m, w_in);
                let r1 = reflectance(albedo, 0.0, eta, cos_i);
                assert!((total / r1 - 1.0).abs() < 2e-3, "albedo {albedo} eta {eta} cos {cos_i}: {total} vs R1 {r1}");
            }
        }
    }

    #[test]
    fn the_8_point_rule_is_within_1e_3_of_a_32_point_rule() {
        let m = BeamSingle { sigma_s: 0.1, sigma_t: 1.5, g: 0.0, eta: 1.3 };
        let mut worst = 0.0f64;
        for cos_i in [1.0, 0.6, 0.1] {
            let w_12 = refract_in(DVec3::new((1.0f64 - cos_i * cos_i).sqrt(), 0.0, cos_i), DVec3::Z, m.eta).unwrap();
            for rho in [1e-4, 0.01, 0.3, 1.0, 3.0] {
                for alpha in [0.0, 1.0, 2.5, PI] {
                    let x_o = DVec3::new(rho * f64::cos(alpha), rho * f64::sin(alpha), 0.0);
                    // A tilted receiver too, as on a curved surface.
                    for n_o in [DVec3::Z, DVec3::new(0.3, 0.1, 1.0).normalize()] {
                        let fine = m.exitance_points(DVec3::ZERO, w_12, x_o, n_o, 32);
                        let got = m.exitance_per_flux(DVec3::ZERO, w_12, x_o, n_o);
                        if fine < 1e-12 {
                            continue;
                        }
                        let e = (got / fine - 1.0).abs();
                        assert!(e < 1e-3, "cos {cos_i} rho {rho} alpha {alpha}: {got} vs {fine}");
                        worst = worst.max(e);
                    }
                }
            }
        }
        eprintln!("8-point rule against 32: worst relative difference {worst:.2e}");
    }

    #[test]
    fn light_that_enters_obliquely_leaves_further_on_in_its_direction() {
        let m = BeamSingle { sigma_s: 0.1, sigma_t: 1.5, g: 0.0, eta: 1.3 };
        // Light comes from +x, so inside it travels towards -x.
        let w_12 = refract_in(DVec3::new(0.8, 0.0, 0.6), DVec3::Z, m.eta).unwrap();
        let ahead = m.exitance_per_flux(DVec3::ZERO, w_12, DVec3::new(-0.5, 0.0, 0.0), DVec3::Z);
        let behind = m.exitance_per_flux(DVec3::ZERO, w_12, DVec3::new(0.5, 0.0, 0.0), DVec3::Z);
        assert!(ahead > 1.5 * behind, "ahead {ahead}, behind {behind}");
    }
}
