//! Fresnel terms: exact dielectric reflectance and transmission, the first Fresnel moment, and the
//! polynomial fits for the diffuse Fresnel reflectance `F_dr` used by the dipole boundary condition.
//!
//! Convention: `eta` is the ratio of refractive indices across the interface in the direction the
//! light travels, `n_transmitted / n_incident`. Light entering a material of index 1.3 from air
//! sees `eta = 1.3`; light leaving it sees `1 / 1.3`.

/// Smallest relative index accepted: below it the `eta < 1` fit of `F_dr` climbs past 1.
pub const ETA_MIN: f64 = 1.0 / 3.0;
/// Largest relative index accepted: the `eta >= 1` fit of `F_dr` passes 1 near `eta = 3.9`.
pub const ETA_MAX: f64 = 3.0;

/// Exact Fresnel reflectance of a smooth dielectric interface for unpolarized light
/// (the average of the s and p reflectances from the Fresnel equations; see Born & Wolf, or
/// pbrt's `FrDielectric`). `cos_theta_i` is the cosine of the angle of incidence (its sign is
/// ignored), `eta = n_t / n_i`.
///
/// Returns 1 under total internal reflection (`eta < 1` beyond the critical angle) and exactly 0
/// for `eta = 1`, where there is no interface. `cos^2 theta_t` is formed as
/// `(cos^2 theta_i + (eta - 1)(eta + 1)) / eta^2` rather than `1 - sin^2 theta_t` so that it does
/// not cancel at grazing incidence.
pub fn fresnel_reflectance(cos_theta_i: f64, eta: f64) -> f64 {
    if eta == 1.0 {
        return 0.0;
    }
    let cos_i = cos_theta_i.abs().min(1.0);
    let cos_t_sq = (cos_i * cos_i + (eta - 1.0) * (eta + 1.0)) / (eta * eta);
    if cos_t_sq <= 0.0 {
        return 1.0; // total internal reflection (or exactly at the critical angle)
    }
    let cos_t = cos_t_sq.sqrt();
    // With eta != 1 the denominators are > 0: cos_i = 0 forces cos_t > 0 (eta > 1) or TIR.
    let r_s = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let r_p = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// Fresnel transmittance `F_t = 1 - F_r` of a smooth dielectric interface (seed Eq. 9 uses it on
/// both the incoming and the outgoing side).
pub fn fresnel_transmittance(cos_theta_i: f64, eta: f64) -> f64 {
    1.0 - fresnel_reflectance(cos_theta_i, eta)
}

/// Diffuse Fresnel reflectance `F_dr`: the polynomial fits used by Jensen et al. 2001 (after Egan
/// & Hilgeman 1979), as docs/optics.md gives them ("Per colour channel"):
/// `eta >= 1`: `-1.440/eta^2 + 0.710/eta + 0.668 + 0.0636 eta`;
/// `eta < 1`: `-0.4399 + 0.7099/eta - 0.3319/eta^2 + 0.0636/eta^3`.
/// `eta` is the relative index of the material (inside over outside). The fits are not exactly
/// 0 at `eta = 1` (they give 0.0016 and 0.0017): that is the fit, not a bug.
///
/// Near `eta = 1` the terms of either fit cancel to those small values, which costs f32 about
/// three digits. So both are evaluated expanded about `eta = 1` (the same polynomials, the
/// coefficients worked out exactly in decimal; [`F_dr_as_published`] is the form above, and a
/// test checks that the two agree):
/// `eta >= 1`, `u = eta - 1`: `(0.0016 + 2.2368 u + 0.8588 u^2 + 0.0636 u^3) / eta^2`;
/// `eta < 1`, `w = 1/eta - 1`: `0.0017 + 0.2369 w - 0.1411 w^2 + 0.0636 w^3`.
#[allow(non_snake_case)]
pub fn F_dr(eta: f64) -> f64 {
    if eta >= 1.0 {
        let u = eta - 1.0;
        (0.0016 + u * (2.2368 + u * (0.8588 + u * 0.0636))) / (eta * eta)
    } else {
        let w = 1.0 / eta - 1.0;
        0.0017 + w * (0.2369 + w * (-0.1411 + w * 0.0636))
    }
}

/// The `F_dr` fits in their published form (see [`F_dr`]).
#[allow(non_snake_case)]
pub fn F_dr_as_published(eta: f64) -> f64 {
    if eta >= 1.0 {
        -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta
    } else {
        -0.4399 + 0.7099 / eta - 0.3319 / (eta * eta) + 0.0636 / (eta * eta * eta)
    }
}

/// The boundary coefficient `A = (1 + F_dr) / (1 - F_dr)` (seed section 2, Jensen et al. 2001):
/// how much further the virtual source sits above the surface because of internal reflection.
#[allow(non_snake_case)]
pub fn A(eta: f64) -> f64 {
    let f = F_dr(eta);
    (1.0 + f) / (1.0 - f)
}

/// First Fresnel moment `FM1(eta) = integral_0^1 F_r(mu, eta) mu dmu`, so `2 FM1(eta)` is the
/// hemispherical reflectance of the interface under uniform (Lambertian) illumination
/// (d'Eon & Irving 2011 use the same moments; pbrt-v3 fits them with polynomials; we integrate).
///
/// Computed by Gauss-Legendre quadrature on panels graded geometrically towards the lower end,
/// where the integrand has its only sharp feature (the critical angle when `eta < 1`, with an
/// infinite slope; near-grazing incidence when `eta` is just above 1). Under total internal
/// reflection, `[0, mu_c]` contributes exactly `mu_c^2 / 2`. Accurate to about 1e-12.
pub fn fresnel_moment1(eta: f64) -> f64 {
    if eta == 1.0 {
        return 0.0;
    }
    // Below mu_c (only when eta < 1) F_r = 1.
    let mu_c = if eta < 1.0 { ((1.0 - eta) * (1.0 + eta)).sqrt() } else { 0.0 };
    let tir = 0.5 * mu_c * mu_c;
    let f = |mu: f64| fresnel_reflectance(mu, eta) * mu;
    tir + graded_integral(f, mu_c, 1.0)
}

/// Second Fresnel moment `FM2(eta) = integral_0^1 F_r(mu, eta) mu^2 dmu`, the weight of the
/// net-flux term of a diffusion radiance crossing the interface (d'Eon and Irving 2011's `C_2`;
/// the directional dipole's `C_E = (1 - 3 FM2) / 2`, `optics::directional_dipole`). Computed
/// as [`fresnel_moment1`] is; under total internal reflection `[0, mu_c]` contributes
/// `mu_c^3 / 3`.
pub fn fresnel_moment2(eta: f64) -> f64 {
    if eta == 1.0 {
        return 0.0;
    }
    let mu_c = if eta < 1.0 { ((1.0 - eta) * (1.0 + eta)).sqrt() } else { 0.0 };
    let tir = mu_c * mu_c * mu_c / 3.0;
    let f = |mu: f64| fresnel_reflectance(mu, eta) * mu * mu;
    tir + graded_integral(f, mu_c, 1.0)
}

/// Hemispherical Fresnel transmittance `T(eta) = 1 - 2 FM1(eta)`: the fraction of Lambertian
/// light that crosses the interface. Across one interface `T(1/eta) = T(eta) / eta^2` (radiance
/// is compressed by `eta^2` on refraction), which the tests check.
pub fn diffuse_transmittance(eta: f64) -> f64 {
    1.0 - 2.0 * fresnel_moment1(eta)
}

/// Integral of `f` over `[lo, hi]` on panels `lo + (hi - lo) 2^-k`, k = 0..40, with 16-point
/// Gauss-Legendre on each: resolves features at any scale near `lo`.
fn graded_integral(f: impl Fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
    let (nodes, weights) = super::quadrature::gauss_legendre(16);
    let width = hi - lo;
    let mut sum = 0.0;
    let mut b = 1.0_f64;
    for _ in 0..40 {
        let a = 0.5 * b;
        let (x0, x1) = (lo + width * a, lo + width * b);
        let (mid, half) = (0.5 * (x0 + x1), 0.5 * (x1 - x0));
        sum += half * nodes.iter().zip(&weights).map(|(x, w)| w * f(mid + half * x)).sum::<f64>();
        b = a;
    }
    // The last sliver [lo, lo + width 2^-40] holds a negligible share of a bounded integrand.
    sum
}
