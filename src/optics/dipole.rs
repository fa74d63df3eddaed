//! The dipole: per colour channel, the derived quantities and the diffuse reflectance profile
//! `R_d(r)` (seed Eq. 8, from Jensen et al. 2001), its exact disk and ring integrals
//! (docs/optics.md, "Reflectance profile, its integrals, and the BSSRDF"), its total, and the
//! BSSRDF `S_d` (seed Eq. 9).
//!
//! Lengths are in scene units and coefficients per scene unit; [`crate::optics::Material`]
//! converts from 1/mm with the scene scale.

use super::OpticsError;
use super::fresnel;
use std::f64::consts::PI;

/// One colour channel of a material, with every quantity the dipole model derives from
/// `sigma_a`, `sigma_s_prime` and `eta`. Field names follow the paper's symbols.
#[allow(non_snake_case)] // D, F_dr, A are the paper's names
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Dipole {
    /// Absorption coefficient `sigma_a` (per scene unit).
    pub sigma_a: f64,
    /// Reduced scattering coefficient `sigma_s' = sigma_s (1 - g)` (per scene unit).
    pub sigma_s_prime: f64,
    /// Relative index of refraction of the material (inside over outside).
    pub eta: f64,
    /// Reduced extinction coefficient `sigma_t' = sigma_a + sigma_s'`.
    pub sigma_t_prime: f64,
    /// Reduced albedo `alpha' = sigma_s' / sigma_t'`.
    pub alpha_prime: f64,
    /// `1 - alpha' = sigma_a / sigma_t'`, kept apart because `1 - alpha'` cancels when
    /// `alpha'` is close to 1 (the common case: marble, milk).
    pub one_minus_alpha_prime: f64,
    /// Diffusion constant `D = 1 / (3 sigma_t')` (seed Eq. 4).
    pub D: f64,
    /// Effective transport coefficient `sigma_tr = sqrt(sigma_a / D) = sqrt(3 sigma_a sigma_t')`
    /// (seed Eq. 7), formed as `sigma_t' sqrt(3 (1 - alpha'))` so that it neither overflows nor
    /// underflows in f32.
    pub sigma_tr: f64,
    /// Diffuse Fresnel reflectance `F_dr` (fit, see [`fresnel::F_dr`]).
    pub F_dr: f64,
    /// Boundary coefficient `A = (1 + F_dr) / (1 - F_dr)`.
    pub A: f64,
    /// Depth of the real source below the surface, `z_r = 1 / sigma_t'` (one mean free path).
    pub z_r: f64,
    /// Height of the virtual source above the surface, `z_v = z_r + 4 A D = z_r (1 + 4A/3)`.
    pub z_v: f64,
}

impl Dipole {
    /// Derives the dipole of one channel from coefficients per scene unit (seed section 2).
    /// Errors name the bad value; `channel` only labels it.
    pub fn new(sigma_a: f64, sigma_s_prime: f64, eta: f64, channel: usize) -> Result<Self, OpticsError> {
        check_coefficient("sigma_a", channel, sigma_a)?;
        check_coefficient("sigma_s'", channel, sigma_s_prime)?;
        check_eta(eta)?;
        let sigma_t_prime = sigma_a + sigma_s_prime;
        if sigma_t_prime == 0.0 {
            return Err(OpticsError::NoExtinction { channel });
        }
        let alpha_prime = sigma_s_prime / sigma_t_prime;
        let one_minus_alpha_prime = sigma_a / sigma_t_prime;
        let f_dr = fresnel::F_dr(eta);
        let a = (1.0 + f_dr) / (1.0 - f_dr);
        let z_r = 1.0 / sigma_t_prime;
        Ok(Dipole {
            sigma_a,
            sigma_s_prime,
            eta,
            sigma_t_prime,
            alpha_prime,
            one_minus_alpha_prime,
            D: z_r / 3.0,
            sigma_tr: sigma_t_prime * (3.0 * one_minus_alpha_prime).sqrt(),
            F_dr: f_dr,
            A: a,
            z_r,
            z_v: z_r * (1.0 + 4.0 * a / 3.0),
        })
    }

    /// Mean free path `1 / sigma_t'` (equal to `z_r`).
    pub fn mean_free_path(&self) -> f64 {
        self.z_r
    }

    /// Diffusion length `1 / sigma_tr`: the e-folding distance of `R_d` far from the source.
    /// Infinite without absorption.
    pub fn diffusion_length(&self) -> f64 {
        1.0 / self.sigma_tr
    }

    /// Diffuse reflectance profile `R_d(r)` (seed Eq. 8; Jensen et al. 2001): radiant
    /// exitance at distance `r` from where a unit flux enters, per unit area.
    ///
    /// Each pole's term `z (sigma_tr + 1/d) e^(-sigma_tr d) / d^2` is evaluated as
    /// `(z/d) (1/d) (sigma_tr + 1/d) e^(-sigma_tr d)` so no intermediate overflows (`z/d <= 1`).
    pub fn r_d(&self, r: f64) -> f64 {
        self.r_d_sq(r * r)
    }

    /// `R_d` at squared distance `r2` (seed Eq. 8), for loops that already have `r^2`: the
    /// exact integral of `reference::truth` evaluates it billions of times.
    pub fn r_d_sq(&self, r2: f64) -> f64 {
        let pole = |z: f64| {
            let d = (z * z + r2).sqrt();
            let inv_d = 1.0 / d;
            (z * inv_d) * inv_d * (self.sigma_tr + inv_d) * (-self.sigma_tr * d).exp()
        };
        self.alpha_prime / (4.0 * PI) * (pole(self.z_r) + pole(self.z_v))
    }

    /// `R_d` with its radial derivatives at squared distance `r2`: `(R_d, R_d'(r)/r, R_d''(r))`,
    /// for the quadrupole term of a far cluster (`reference::truth`). Per pole, with
    /// `d^2 = r^2 + z^2` and `k = alpha' z / (4 pi)`, `R_d = k (sigma_tr d + 1) e^(-sigma_tr d) / d^3`,
    /// `R_d'/r = -k e^(-sigma_tr d) (s^2 + 3 s + 3) / d^5` and
    /// `R_d'' = R_d'/r + k r^2 e^(-sigma_tr d) (s^3 + 6 s^2 + 15 s + 15) / d^7`, `s = sigma_tr d`.
    pub fn r_d_derivatives(&self, r2: f64) -> (f64, f64, f64) {
        let (mut g, mut g1, mut g2) = (0.0, 0.0, 0.0);
        for z in [self.z_r, self.z_v] {
            let d = (z * z + r2).sqrt();
            let inv_d = 1.0 / d;
            let s = self.sigma_tr * d;
            // z/d <= 1 first, so nothing overflows before the exponential shrinks it.
            let k = (z * inv_d) * (-s).exp() * inv_d * inv_d;
            g += k * (s + 1.0);
            let first = -k * (s * s + 3.0 * s + 3.0) * inv_d * inv_d;
            g1 += first;
            g2 += first + k * (r2 * inv_d * inv_d) * (s * s * s + 6.0 * s * s + 15.0 * s + 15.0) * inv_d * inv_d;
        }
        let c = self.alpha_prime / (4.0 * PI);
        (c * g, c * g1, c * g2)
    }

    /// Total diffuse reflectance `R_d,total = integral R_d(r) 2 pi r dr` in closed form
    /// (docs/optics.md, "Reflectance profile, its integrals, and the BSSRDF"; Jensen and Buhler
    /// 2002 use it to map reflectance to albedo):
    /// `(alpha'/2) (1 + e^(-(4/3) A sqrt(3(1-alpha')))) e^(-sqrt(3(1-alpha')))`.
    /// Exactly `alpha' = 1` without absorption.
    pub fn r_d_total(&self) -> f64 {
        let s = (3.0 * self.one_minus_alpha_prime).sqrt();
        0.5 * self.alpha_prime * (1.0 + (-4.0 / 3.0 * self.A * s).exp()) * (-s).exp()
    }

    /// RMS radius of the profile: `sqrt(integral r^2 R_d(r) 2 pi r dr / R_d,total)`, the width
    /// of the blur subsurface transport gives an image, in closed form. Each pole's share of
    /// `R_d 2 pi r` is `(alpha'/2) (-d/dr) [z e^(-sigma_tr d) / d]`; integrating `r^2` against it
    /// by parts gives `alpha' z e^(-sigma_tr z) / sigma_tr`, so
    /// `<r^2> = alpha' sum_z z e^(-sigma_tr z) / (sigma_tr R_d,total)`.
    /// Why it matters: the local answer `M = R_d,total E(x)` is off from the dipole integral by
    /// `R_d,total <r^2> laplacian(E) / 4` to second order (planner, `render::plan`). Infinite
    /// without absorption.
    pub fn profile_radius(&self) -> f64 {
        if self.sigma_tr == 0.0 {
            return f64::INFINITY;
        }
        let pole = |z: f64| z * (-self.sigma_tr * z).exp();
        let moment = self.alpha_prime * (pole(self.z_r) + pole(self.z_v)) / self.sigma_tr;
        (moment / self.r_d_total()).sqrt()
    }

    /// Exact disk integral `P(R) = integral_0^R R_d(r) 2 pi r dr` (docs/optics.md,
    /// "Reflectance profile, its integrals, and the BSSRDF"):
    /// `(alpha'/2) sum_{z in z_r, z_v} [e^(-sigma_tr z) - z e^(-sigma_tr d(R)) / d(R)]`.
    /// Rises monotonically from 0 to [`Self::r_d_total`]. Evaluated without cancellation (see
    /// [`ring_term`]), so it is accurate even for `R` far below `z_r`.
    pub fn r_d_disk(&self, radius: f64) -> f64 {
        self.r_d_ring_sq(0.0, radius * radius)
    }

    /// Exact ring integral `integral_{r1}^{r2} R_d(r) 2 pi r dr = P(r2) - P(r1)`, evaluated
    /// without forming the difference. Requires `0 <= r1 <= r2`.
    pub fn r_d_ring(&self, r1: f64, r2: f64) -> f64 {
        self.r_d_ring_sq(r1 * r1, (r2 - r1) * (r2 + r1))
    }

    /// Ring integral between the radii `sqrt(r1_sq)` and `sqrt(r1_sq + delta_sq)`: the squared
    /// inner radius and the difference of the squared radii, which callers often know exactly.
    pub fn r_d_ring_sq(&self, r1_sq: f64, delta_sq: f64) -> f64 {
        let s = self.sigma_tr;
        0.5 * self.alpha_prime * (ring_term(self.z_r, s, r1_sq, delta_sq) + ring_term(self.z_v, s, r1_sq, delta_sq))
    }

    /// What lies outside a disk: `R_d,total - P(R) = (alpha'/2) sum_z z e^(-sigma_tr d(R)) / d(R)`,
    /// evaluated directly (no difference), so it stays accurate when tiny.
    pub fn r_d_outside(&self, radius: f64) -> f64 {
        let pole = |z: f64| {
            let d = z.hypot(radius);
            (z / d) * (-self.sigma_tr * d).exp()
        };
        0.5 * self.alpha_prime * (pole(self.z_r) + pole(self.z_v))
    }

    /// The smallest radius outside which at most `fraction` of `R_d,total` lies: where a
    /// gather can stop. Found by bisection on [`Self::r_d_outside`], which decreases with the
    /// radius; without absorption it falls only as `z/R`, so small fractions mean large radii.
    pub fn truncation_radius(&self, fraction: f64) -> f64 {
        let target = fraction * self.r_d_total();
        if self.r_d_outside(0.0) <= target {
            return 0.0;
        }
        let mut hi = self.z_v;
        while self.r_d_outside(hi) > target && hi < f64::MAX / 4.0 {
            hi *= 2.0;
        }
        let mut lo = 0.0;
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if self.r_d_outside(mid) > target {
                lo = mid
            } else {
                hi = mid
            }
            if hi - lo <= 1e-12 * hi {
                break;
            }
        }
        hi
    }

    /// The BSSRDF `S_d(r, w_i, w_o)` (seed Eq. 9, after Jensen et al. 2001) with the seed's
    /// unspecified normalization `rho / pi` chosen to conserve energy:
    ///
    /// `S_d = F_t(eta, cos theta_i) R_d(r) F_t(eta, cos theta_o) / (pi T(eta))`,
    /// `T(eta) = 1 - 2 FM1(eta)`, the hemispherical Fresnel transmittance from outside.
    ///
    /// Why: of an irradiance `E` arriving at `theta_i`, the flux `F_t(theta_i) E` enters; `R_d`
    /// (whose boundary condition already accounts for internal reflection through `A`) turns it
    /// into radiant exitance `M`; the outgoing radiance is shaped by `F_t(theta_o)` and divided
    /// by `pi T` so that `integral L_o cos theta_o dw_o = M` exactly. Then a plane under uniform
    /// light reflects `F_t(theta_i) R_d,total E <= E`. pbrt-v3's `SeparableBSSRDF` writes the
    /// same lobe with `c = 1 - 2 FM1(1/eta)`, the transmittance from inside; the two differ by
    /// the `eta^2` radiance compression at the interface (`T(1/eta) = T(eta) / eta^2`).
    ///
    /// `t_eta` is `T(eta)` ([`fresnel::diffuse_transmittance`]), passed in because it is a
    /// per-material constant computed by quadrature.
    pub fn s_d(&self, r: f64, cos_theta_i: f64, cos_theta_o: f64, t_eta: f64) -> f64 {
        fresnel::fresnel_transmittance(cos_theta_i, self.eta)
            * self.r_d(r)
            * fresnel::fresnel_transmittance(cos_theta_o, self.eta)
            / (PI * t_eta)
    }
}

/// One pole's share of a ring integral of `R_d`, without the factor `alpha'/2`:
/// `z [e^(-s d1)/d1 - e^(-s d2)/d2]` with `d_i = sqrt(r_i^2 + z^2)` (from
/// `d/dr [e^(-s d)/d] = -(s + 1/d) e^(-s d) r / d^2`; docs/optics.md, "Reflectance profile, its
/// integrals, and the BSSRDF").
///
/// The difference cancels catastrophically for thin rings and for disks much smaller than `z`.
/// Rewritten as `(z/d1) e^(-s d1) [(d2 - d1)/d2 + (d1/d2)(1 - e^(-s (d2 - d1)))]`, with
/// `d2 - d1 = (r2^2 - r1^2) / (d1 + d2)`, every term is >= 0 and nothing cancels; `1 - e^-x` is
/// `-expm1(-x)`.
pub fn ring_term(z: f64, s: f64, r1_sq: f64, delta_sq: f64) -> f64 {
    let d1 = (r1_sq + z * z).sqrt();
    let d2 = (r1_sq + delta_sq + z * z).sqrt();
    let gap = delta_sq / (d1 + d2);
    (z / d1) * (-s * d1).exp() * (gap / d2 + (d1 / d2) * -(-s * gap).exp_m1())
}

pub(crate) fn check_coefficient(name: &'static str, channel: usize, value: f64) -> Result<(), OpticsError> {
    if value.is_finite() && value >= 0.0 { Ok(()) } else { Err(OpticsError::BadCoefficient { name, channel, value }) }
}

pub(crate) fn check_eta(eta: f64) -> Result<(), OpticsError> {
    if (fresnel::ETA_MIN..=fresnel::ETA_MAX).contains(&eta) { Ok(()) } else { Err(OpticsError::BadEta(eta)) }
}
