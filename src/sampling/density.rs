//! How many sample points an error target needs: a model of the per-vertex error of the
//! discrete dipole sum against the exact integral, fitted to the accuracy study's measurements
//! (docs/STUDY.md, "The error model"), and its inverse.
//!
//! Per colour channel, with `s = sqrt(A / N)` the spacing of `N` samples over area `A` and `r`
//! the profile's RMS radius (`optics::Dipole::profile_radius`):
//!
//! ```text
//! e(N) = C (r / R_k)^a (s / r)^p (1 + k_o Omega)
//! ```
//!
//! - `(s / r)^p`: the quadrature error of samples `s` apart under a kernel `r` wide, of order
//!   `p` (Turk's even spacing converges faster than random points, seed section 3).
//! - `(r / R_k)^a`, the **thin-part term**: `R_k` is the surface's curvature radius (the
//!   area-weighted RMS of the mean curvature, inverted). Where the profile is wide against the
//!   bends of the surface (ears, rims, small spheres), light that crosses the bend is summed
//!   over samples that straddle it, and the error grows.
//! - `1 + k_o Omega`, the **shadow-edge term**: `Omega` is the share of the hemisphere above the
//!   surface that shadow casters block (ambient occlusion, light-independent, so the count does
//!   not change when a light moves). Cast shadows put edges into `E_t` that samples resolve only
//!   at their spacing.
//!
//! The constants are fitted, in log space, to Turk's rows of the study with the hierarchical
//! gather at epsilon 0.3 on the four study scenes and the built-in one.

/// Scale `C`: the least-squares fit's 0.294 times [`FIT_MARGIN`].
pub const FIT_SCALE: f64 = 0.294 * FIT_MARGIN;
/// Exponent `a` of the thin-part term.
pub const FIT_THIN_EXPONENT: f64 = 1.06;
/// Order `p` of the quadrature.
pub const FIT_ORDER: f64 = 2.21;
/// Weight `k_o` of the shadow-edge term (the best of a grid search; `C`, `a` and `p` are least
/// squares for each).
pub const FIT_SHADOW_WEIGHT: f64 = 10.0;
/// How much the prediction leans high: the fit's residuals span measured errors from 0.46 to
/// 1.8 times the prediction, and a target is a bound the user relies on.
pub const FIT_MARGIN: f64 = 1.35;

/// Fewest samples an error target may choose for an object.
pub const MIN_CHOSEN: usize = 100;
/// Most samples an error target may choose for an object: what placement and the gather can
/// afford (Turk's repulsion at this count takes seconds).
pub const MAX_CHOSEN: usize = 65_536;

/// What the model weighs about an object's surface, independent of its material and lights.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SurfaceFacts {
    /// Total area, scene units squared.
    pub area: f64,
    /// Curvature radius `R_k`: one over the area-weighted RMS mean curvature, scene units.
    pub curvature_radius: f64,
    /// Share of the hemisphere above the surface that shadow casters block, area-weighted
    /// (0 to 1).
    pub occlusion: f64,
}

/// One channel's predicted error and the terms behind it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ChannelError {
    /// `s / r`: sample spacing over the profile's RMS radius.
    pub spacing_over_radius: f64,
    /// `(r / R_k)^a`.
    pub thin_term: f64,
    /// `1 + k_o Omega`.
    pub shadow_term: f64,
    /// The predicted relative RMS error per vertex.
    pub error: f64,
}

/// The predicted error of each channel (profile radii `radii`, scene units) for `count`
/// samples on a surface with `facts`.
pub fn predict(facts: &SurfaceFacts, radii: [f64; 3], count: usize) -> [ChannelError; 3] {
    let spacing = (facts.area / count.max(1) as f64).sqrt();
    radii.map(|r| {
        let r = r.max(f64::MIN_POSITIVE);
        let x = spacing / r;
        let thin_term = (r / facts.curvature_radius.max(f64::MIN_POSITIVE)).powf(FIT_THIN_EXPONENT);
        let shadow_term = 1.0 + FIT_SHADOW_WEIGHT * facts.occlusion.clamp(0.0, 1.0);
        let error = FIT_SCALE * thin_term * x.powf(FIT_ORDER) * shadow_term;
        ChannelError { spacing_over_radius: x, thin_term, shadow_term, error }
    })
}

/// The fewest samples (within [`MIN_CHOSEN`] to [`MAX_CHOSEN`]) whose predicted error is at
/// most `max_error` in every channel of `radii`, inverting [`predict`]:
/// `N = A / s^2` with `s = r (e / (C thin shadow))^(1/p)`, for the channel that needs most.
pub fn count_for(facts: &SurfaceFacts, radii: [f64; 3], max_error: f64) -> usize {
    let unit = predict(facts, radii, 1);
    let needed = radii
        .iter()
        .zip(&unit)
        .map(|(&r, c)| {
            let per_x = c.error / c.spacing_over_radius.powf(FIT_ORDER);
            let x = (max_error / per_x).powf(1.0 / FIT_ORDER);
            let s = x * r;
            (facts.area / (s * s)).ceil()
        })
        .fold(0.0, f64::max);
    if needed.is_nan() {
        return MAX_CHOSEN;
    }
    (needed as usize).clamp(MIN_CHOSEN, MAX_CHOSEN)
}

#[cfg(test)]
mod tests {
    use super::*;

    const FACTS: SurfaceFacts = SurfaceFacts { area: 1e-3, curvature_radius: 0.01, occlusion: 0.1 };

    #[test]
    fn the_count_for_a_target_predicts_at_most_that_target() {
        let radii = [0.005, 0.003, 0.001];
        for target in [0.003, 0.01, 0.03, 0.1] {
            let n = count_for(&FACTS, radii, target);
            let worst = predict(&FACTS, radii, n).iter().map(|c| c.error).fold(0.0, f64::max);
            assert!(worst <= target * (1.0 + 1e-9) || n == MAX_CHOSEN || n == MIN_CHOSEN, "{target}: {n} -> {worst}");
            let fewer = predict(&FACTS, radii, n - 1).iter().map(|c| c.error).fold(0.0, f64::max);
            assert!(fewer > target || n == MIN_CHOSEN, "{target}: {} samples would do", n - 1);
        }
    }

    #[test]
    fn error_falls_with_density_and_grows_with_occlusion() {
        let radii = [0.004; 3];
        let e = |f: &SurfaceFacts, n| predict(f, radii, n)[0].error;
        assert!(e(&FACTS, 1600) < e(&FACTS, 400));
        let shadowed = SurfaceFacts { occlusion: 0.3, ..FACTS };
        assert!(e(&shadowed, 400) > e(&FACTS, 400));
    }
}
