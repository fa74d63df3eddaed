//! From a diffuse colour to a medium: the reduced albedo `alpha'` whose dipole reflects a given
//! fraction of the light that enters, `R_d,total` (the inversion Jensen and Buhler 2002 use to
//! paint translucent materials by their diffuse colour). `R_d,total` depends on `alpha'` and
//! `eta` alone, and rises monotonically with `alpha'` from 0 (at 0) to 1 (at 1), so bisection
//! finds it.

use super::{OpticsError, dipole, fresnel};

/// The reduced albedo [`reduced_albedo`] gives at most: `1 - alpha'` stays above 0, so the
/// medium keeps some absorption, its diffusion length finite (the planner and the gathers
/// reach by it).
pub const MAX_REDUCED_ALBEDO: f64 = 1.0 - 1e-6;

/// `R_d,total` of a dipole of reduced albedo `alpha_prime` and relative index `eta`, as
/// [`dipole::Dipole::r_d_total`] computes it: `(alpha'/2) (1 + e^(-(4/3) A s)) e^(-s)`,
/// `s = sqrt(3 (1 - alpha'))`.
pub fn total_reflectance(alpha_prime: f64, eta: f64) -> f64 {
    let f_dr = fresnel::F_dr(eta);
    let a = (1.0 + f_dr) / (1.0 - f_dr);
    let s = (3.0 * (1.0 - alpha_prime)).sqrt();
    0.5 * alpha_prime * (1.0 + (-4.0 / 3.0 * a * s).exp()) * (-s).exp()
}

/// The reduced albedo `alpha'` whose dipole's `R_d,total` is `r_d_total` at relative index
/// `eta`, to within 1e-12, at most [`MAX_REDUCED_ALBEDO`] (a reflectance of 1 or more gets it).
/// Errors: `eta` outside the `F_dr` fits' range, or a reflectance that is negative or not
/// finite.
pub fn reduced_albedo(r_d_total: f64, eta: f64) -> Result<f64, OpticsError> {
    dipole::check_eta(eta)?;
    dipole::check_coefficient("R_d,total", 0, r_d_total)?;
    let (mut lo, mut hi) = (0.0, MAX_REDUCED_ALBEDO);
    if total_reflectance(hi, eta) <= r_d_total {
        return Ok(hi);
    }
    // 50 halvings of [0, 1) leave an interval under 1e-15.
    for _ in 0..50 {
        let mid = 0.5 * (lo + hi);
        if total_reflectance(mid, eta) < r_d_total {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_albedo_found_gives_back_the_reflectance_asked_for() {
        for eta in [1.0, 1.3, 1.5] {
            for r in [0.0, 0.05, 0.3, 0.6, 0.8, 0.95] {
                let alpha = reduced_albedo(r, eta).unwrap();
                let d = dipole::Dipole::new(1.0 - alpha, alpha, eta, 0).unwrap();
                assert!((d.r_d_total() - r).abs() < 1e-12, "eta {eta} r {r}: {}", d.r_d_total());
                assert!((total_reflectance(alpha, eta) - d.r_d_total()).abs() < 1e-15);
            }
        }
        assert_eq!(reduced_albedo(1.0, 1.5).unwrap(), MAX_REDUCED_ALBEDO);
        assert!(reduced_albedo(-0.1, 1.5).is_err() && reduced_albedo(0.5, 9.0).is_err());
    }
}
