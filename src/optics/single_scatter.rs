//! Single scattering of a homogeneous half-space behind a smooth dielectric boundary: the
//! first-order term the dipole leaves out (Jensen et al. 2001, Eq. 3, after Hanrahan and
//! Krueger 1993). The f32 twin is `glsl/common/single_scatter.glsl`; `tests/optics_gpu.rs`
//! compares the two.
//!
//! # The term
//!
//! A collimated beam refracts in (incidence cosine `mu_i` inside, by Snell's law) with flux
//! `E_t` per unit area of the surface. At depth `z` its irradiance across the beam is
//! `(E_t / mu_i) e^(-sigma_t z / mu_i)`, and it scatters into direction `w` at the rate
//! `sigma_s p(w_i . w)` per unit volume, `p` the Henyey-Greenstein phase function (normalised
//! over the sphere). Light scattered once towards the surface at cosine `mu` crosses `z / mu`
//! of medium to reach it, so the radiance arriving at the surface from inside is
//!
//! ```text
//! L(w) = integral_0^inf sigma_s p (E_t / mu_i) e^(-sigma_t z (1/mu_i + 1/mu)) dz / mu
//!      = albedo p(w_i . w) E_t / (mu_i + mu)
//! ```
//!
//! (Jensen et al.'s Eq. 3 with `sigma_tc` the sum of the two path's extinctions, integrated over
//! the points of a plane). The share that leaves is the Fresnel transmittance from inside,
//! `F_t(mu, 1/eta)`, and the exitance it makes is `integral L mu F_t dw`. Per unit flux that
//! enters, as the dipole's `R_d,total` is, the single-scattering reflectance is
//!
//! ```text
//! R1(mu_i) = albedo integral_{mu_c}^1 integral_0^{2 pi} p(cos psi) F_t(mu, 1/eta) mu / (mu_i + mu) dphi dmu,
//! cos psi = -mu_i mu + sqrt(1 - mu_i^2) sqrt(1 - mu^2) cos phi
//! ```
//!
//! with `mu_c = sqrt(1 - 1/eta^2)` the critical cosine inside (0 when `eta <= 1`). For an
//! isotropic phase function the azimuth integral is `1/2`, and at `eta = 1` the whole is closed
//! form: `R1 = (albedo / 2) (1 - mu_i ln((1 + mu_i) / mu_i))` ([`index_matched_isotropic`]),
//! the first-order term of Chandrasekhar's plane albedo.
//!
//! # Quadrature
//!
//! `F_t(mu, 1/eta)` rises like `sqrt(mu - mu_c)` from the critical cosine, so `mu` is
//! substituted `mu = mu_c + (1 - mu_c) s^2`, which makes the integrand smooth in `s`; then
//! Gauss-Legendre in `s` on [0, 1] and, for `g != 0`, in `phi` on [0, pi] (the integrand is
//! even in `phi`). [`reflectance`] uses [`POINTS`] nodes in each, as the GLSL twin does; the
//! tests measure that rule against the closed form and against a rule four times finer.
//!
//! In a renderer the exitance of once-scattered light at a surface point is `E_t R1(mu_i)`
//! per light, local to a mean free path: the half-space's figure applied where the surface is
//! flat over a few mean free paths.

use super::fresnel::fresnel_transmittance;
pub use super::quadrature::gauss_legendre;
use std::f64::consts::PI;

/// Gauss-Legendre nodes per dimension of [`reflectance`] (and of the GLSL twin).
pub const POINTS: usize = 16;

/// Henyey-Greenstein phase function of mean cosine `g` at scattering cosine `cos`, normalised
/// over the sphere: `(1 - g^2) / (4 pi (1 + g^2 - 2 g cos)^(3/2))` (Henyey and Greenstein 1941).
pub fn henyey_greenstein(cos: f64, g: f64) -> f64 {
    let denom = 1.0 + g * g - 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
}

/// The cosine of the refracted direction inside for incidence cosine `cos_out` outside (Snell's
/// law, `eta` inside over outside); `None` when nothing enters (total internal reflection
/// outside, only for `eta < 1`, or a cosine not in (0, 1]).
pub fn refracted_cosine(cos_out: f64, eta: f64) -> Option<f64> {
    if !(cos_out > 0.0 && cos_out <= 1.0) {
        return None;
    }
    // Without the cancellation of 1 - sin^2 at grazing incidence (as `fresnel` forms it).
    let cos_sq = (cos_out * cos_out + (eta - 1.0) * (eta + 1.0)) / (eta * eta);
    (cos_sq > 0.0).then(|| cos_sq.sqrt())
}

/// The critical cosine inside, below which light cannot leave: `sqrt(1 - 1/eta^2)`, 0 for
/// `eta <= 1`.
pub fn critical_cosine(eta: f64) -> f64 {
    if eta > 1.0 { (1.0 - 1.0 / (eta * eta)).sqrt() } else { 0.0 }
}

/// Single-scattering reflectance `R1` of a half-space (see the module's documentation): of the
/// flux that enters through the plane at incidence cosine `cos_out` outside, the share that
/// leaves after exactly one scattering. `albedo = sigma_s / sigma_t`, `g` the
/// Henyey-Greenstein mean cosine, `eta` inside over outside. 0 where nothing enters.
pub fn reflectance(albedo: f64, g: f64, eta: f64, cos_out: f64) -> f64 {
    reflectance_with(albedo, g, eta, cos_out, &gauss_legendre(POINTS))
}

/// [`reflectance`] with `n`-point Gauss-Legendre in each dimension (for measuring the rule).
pub fn reflectance_points(albedo: f64, g: f64, eta: f64, cos_out: f64, n: usize) -> f64 {
    reflectance_with(albedo, g, eta, cos_out, &gauss_legendre(n))
}

fn reflectance_with(albedo: f64, g: f64, eta: f64, cos_out: f64, rule: &(Vec<f64>, Vec<f64>)) -> f64 {
    let Some(mu_i) = refracted_cosine(cos_out, eta) else { return 0.0 };
    let mu_c = critical_cosine(eta);
    let sin_i = ((1.0 - cos_out) * (1.0 + cos_out)).sqrt() / eta;
    let (nodes, weights) = rule;
    let mut sum = 0.0;
    for (x, w) in nodes.iter().zip(weights) {
        // s in [0, 1], mu = mu_c + (1 - mu_c) s^2, dmu = 2 (1 - mu_c) s ds.
        let s = 0.5 * (x + 1.0);
        let mu = mu_c + (1.0 - mu_c) * s * s;
        let jacobian = 0.5 * w * 2.0 * (1.0 - mu_c) * s;
        let angular = if g == 0.0 {
            1.0 / (4.0 * PI) * 2.0 * PI
        } else {
            // 2 integral_0^pi p dphi, phi = pi (y + 1) / 2.
            let sin_o = (1.0 - mu * mu).max(0.0).sqrt();
            nodes
                .iter()
                .zip(weights)
                .map(|(y, v)| {
                    let phi = 0.5 * PI * (y + 1.0);
                    v * 0.5 * PI * henyey_greenstein(-mu_i * mu + sin_i * sin_o * phi.cos(), g)
                })
                .sum::<f64>()
                * 2.0
        };
        sum += jacobian * angular * fresnel_transmittance(mu, 1.0 / eta) * mu / (mu_i + mu);
    }
    albedo * sum
}

/// The closed form at `eta = 1` for isotropic scattering: `(albedo / 2) (1 - mu ln((1 + mu) /
/// mu))`, `mu` the incidence cosine (Chandrasekhar 1960, the first order of the plane albedo).
pub fn index_matched_isotropic(albedo: f64, mu: f64) -> f64 {
    0.5 * albedo * (1.0 - mu * ((1.0 + mu) / mu).ln())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_rule_matches_the_closed_form_at_eta_1() {
        for albedo in [0.02, 0.5, 0.999] {
            for mu in [1.0, 0.7, 0.3, 0.05] {
                let exact = index_matched_isotropic(albedo, mu);
                let got = reflectance(albedo, 0.0, 1.0, mu);
                assert!((got / exact - 1.0).abs() < 1e-6, "albedo {albedo} mu {mu}: {got} vs {exact}");
            }
        }
    }

    #[test]
    fn the_16_point_rule_is_within_1e_5_of_a_64_point_rule_for_g_from_minus_half_to_0_8() {
        let mut worst = 0.0f64;
        for g in [-0.5, -0.2, 0.0, 0.3, 0.8] {
            for eta in [1.0 / 3.0, 0.8, 1.0, 1.3, 1.5, 3.0] {
                for cos in [1.0, 0.7, 0.3, 0.05] {
                    let (fine, got) = (reflectance_points(0.5, g, eta, cos, 64), reflectance(0.5, g, eta, cos));
                    if fine == 0.0 {
                        // Nothing enters (eta < 1 beyond the critical angle outside).
                        assert_eq!(got, 0.0, "g {g} eta {eta} cos {cos}");
                        continue;
                    }
                    let e = (got / fine - 1.0).abs();
                    assert!(e < 1e-5, "g {g} eta {eta} cos {cos}: {e:e}");
                    worst = worst.max(e);
                }
            }
        }
        eprintln!("16-point rule against 64 points: worst relative difference {worst:.2e}");
    }

    #[test]
    fn henyey_greenstein_integrates_to_one_and_has_mean_cosine_g() {
        let (x, w) = gauss_legendre(64);
        for g in [-0.5, 0.0, 0.3, 0.7] {
            let total: f64 = x.iter().zip(&w).map(|(c, w)| w * 2.0 * PI * henyey_greenstein(*c, g)).sum();
            let mean: f64 = x.iter().zip(&w).map(|(c, w)| w * 2.0 * PI * c * henyey_greenstein(*c, g)).sum();
            assert!((total - 1.0).abs() < 1e-6 && (mean - g).abs() < 1e-6, "g {g}: {total}, {mean}");
        }
    }
}
