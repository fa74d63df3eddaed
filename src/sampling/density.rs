//! How many sample points an error target needs: a model of the per-vertex error of the
//! discrete dipole sum against the exact integral, fitted to the accuracy study's measurements
//! (docs/STUDY.md, "The error model"), and its inverse.
//!
//! Per colour channel, with `s = sqrt(A / N)` the spacing of `N` samples over area `A`, `r`
//! the profile's RMS radius (`optics::Dipole::profile_radius`) and `x = s / r`:
//!
//! ```text
//! e(N) = M [ C (r / R_k)^a x^p (1 + k_o Omega)  +  D Omega (l / R_k)^b x^q ]
//! ```
//!
//! - `x^p`: the quadrature error of samples `s` apart under a kernel `r` wide, of order `p`
//!   (Turk's even spacing converges faster than random points, seed section 3).
//! - `(r / R_k)^a`, the **thin-part term**: `R_k` is the surface's curvature radius (the
//!   area-weighted RMS of the mean curvature, inverted). Where the profile is wide against the
//!   bends of the surface (ears, rims, small spheres), light that crosses the bend is summed
//!   over samples that straddle it, and the error grows.
//! - `1 + k_o Omega`, the **shadow-edge term**: `Omega` is the share of the hemisphere above the
//!   surface that shadow casters block (ambient occlusion, light-independent, so the count does
//!   not change when a light moves). Cast shadows put edges into `E_t` that samples resolve only
//!   at their spacing.
//! - `D Omega (l / R_k)^b x^q`, the **facet term**: `l` is the mesh's mean edge length, so
//!   `l / R_k` is about the angle one facet turns from the next. Where shadows fall on a coarse
//!   mesh the error falls more slowly with density (the same 1.8k-vertex bunny under the
//!   built-in scene's lights falls as `N^-0.55` past 12,800 samples where the 37.7k-vertex one
//!   falls as `N^-1`), so the term has its own, low order `q`. Its steep exponent `b` keeps it
//!   negligible on fine meshes, and `Omega` leaves it out where nothing is shadowed.
//! - `M`, the margin: the prediction leans high, since a target is a bound the user relies on.
//!
//! The constants are fitted, in log space, to Turk's rows of the study with the hierarchical
//! gather: the three spheres (epsilon 0.3, 100 to 6,400 samples), and, with the splat's hybrid
//! visibility, the bunny ears, the built-in scene, the built-in scene with the coarse mesh and
//! the ears with no shadows (epsilon 0.1, 1,600 to 102,400 samples).

/// Scale `C` of the smooth term (least squares, before the margin).
pub const FIT_SCALE: f64 = 0.294;
/// Exponent `a` of the thin-part term.
pub const FIT_THIN_EXPONENT: f64 = 1.06;
/// Order `p` of the quadrature.
pub const FIT_ORDER: f64 = 2.21;
/// Weight `k_o` of the shadow-edge term (the best of a grid search; `C`, `a` and `p` are least
/// squares for each).
pub const FIT_SHADOW_WEIGHT: f64 = 10.0;
/// Scale `D` of the facet term (least squares with `b` and the smooth term's constants held).
pub const FIT_FACET_SCALE: f64 = 6.4;
/// Exponent `b` of `l / R_k` in the facet term: chosen, not fitted (the fit's log residual is
/// 0.443 at `b` = 1 and 0.457 at 5.3), so that the term stays under 4% of the prediction on the
/// 37.7k-vertex bunny, whose error falls as fast as the smooth term's up to 102,400 samples.
pub const FIT_FACET_EXPONENT: f64 = 4.0;
/// Order `q` of the facet term (least squares).
pub const FIT_FACET_ORDER: f64 = 0.18;
/// Margin `M`: the fit's residuals put measured errors at 0.46 to 2 times the prediction on the
/// study's scenes (up to 4 times on the ears with no shadows: docs/STUDY.md), and a target is a
/// bound the user relies on.
pub const FIT_MARGIN: f64 = 1.35;

/// Fewest samples an error target may choose for an object.
pub const MIN_CHOSEN: usize = 100;
/// Most samples an error target may choose for an object: what placement and the gather can
/// afford (Turk's repulsion of this many points takes about 4 s on two cores).
pub const MAX_CHOSEN: usize = 131_072;

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
    /// Mean edge length `l` of the mesh, scene units.
    pub edge_length: f64,
}

/// One channel's predicted error and the terms behind it.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ChannelError {
    /// `x = s / r`: sample spacing over the profile's RMS radius.
    pub spacing_over_radius: f64,
    /// `(r / R_k)^a`.
    pub thin_term: f64,
    /// `1 + k_o Omega`.
    pub shadow_term: f64,
    /// `D Omega (l / R_k)^b x^q`, before the margin.
    pub facet_term: f64,
    /// The predicted relative RMS error per vertex.
    pub error: f64,
}

/// The predicted error of each channel (profile radii `radii`, scene units) for `count`
/// samples on a surface with `facts`.
pub fn predict(facts: &SurfaceFacts, radii: [f64; 3], count: usize) -> [ChannelError; 3] {
    let spacing = (facts.area / count.max(1) as f64).sqrt();
    let curvature_radius = facts.curvature_radius.max(f64::MIN_POSITIVE);
    let occlusion = facts.occlusion.clamp(0.0, 1.0);
    let coarseness = (facts.edge_length.max(0.0) / curvature_radius).powf(FIT_FACET_EXPONENT);
    let facets = FIT_FACET_SCALE * occlusion * coarseness;
    radii.map(|r| {
        let r = r.max(f64::MIN_POSITIVE);
        let x = spacing / r;
        let thin_term = (r / curvature_radius).powf(FIT_THIN_EXPONENT);
        let shadow_term = 1.0 + FIT_SHADOW_WEIGHT * occlusion;
        let facet_term = facets * x.powf(FIT_FACET_ORDER);
        let error = FIT_MARGIN * (FIT_SCALE * thin_term * x.powf(FIT_ORDER) * shadow_term + facet_term);
        ChannelError { spacing_over_radius: x, thin_term, shadow_term, facet_term, error }
    })
}

/// The worst channel's predicted error of `predicted`; NaN if any channel's is (where
/// `f64::max` would drop it).
pub fn worst(predicted: &[ChannelError; 3]) -> f64 {
    predicted.iter().map(|c| c.error).fold(0.0, |w, e| if e.is_nan() || e > w { e } else { w })
}

/// The fewest samples (within [`MIN_CHOSEN`] to [`MAX_CHOSEN`]) whose predicted error is at
/// most `max_error` in every channel of `radii`. [`predict`] falls with the count in every term,
/// so a bisection over the count inverts it.
pub fn count_for(facts: &SurfaceFacts, radii: [f64; 3], max_error: f64) -> usize {
    let meets = |n: usize| worst(&predict(facts, radii, n)) <= max_error;
    if meets(MIN_CHOSEN) {
        return MIN_CHOSEN;
    }
    if !meets(MAX_CHOSEN) {
        // Also where the prediction is NaN: the most a target may choose.
        return MAX_CHOSEN;
    }
    // Invariant: `low` misses the target, `high` meets it.
    let (mut low, mut high) = (MIN_CHOSEN, MAX_CHOSEN);
    while high - low > 1 {
        let mid = low + (high - low) / 2;
        if meets(mid) { high = mid } else { low = mid }
    }
    high
}

#[cfg(test)]
mod tests {
    use super::*;

    const FACTS: SurfaceFacts = SurfaceFacts { area: 1e-3, curvature_radius: 0.01, occlusion: 0.1, edge_length: 1e-3 };

    #[test]
    fn the_count_for_a_target_predicts_at_most_that_target() {
        let radii = [0.005, 0.003, 0.001];
        for target in [0.003, 0.01, 0.03, 0.1] {
            let n = count_for(&FACTS, radii, target);
            let at_n = worst(&predict(&FACTS, radii, n));
            assert!(at_n <= target * (1.0 + 1e-9) || n == MAX_CHOSEN || n == MIN_CHOSEN, "{target}: {n} -> {at_n}");
            let fewer = worst(&predict(&FACTS, radii, n - 1));
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

    #[test]
    fn a_coarse_mesh_needs_more_samples_and_more_again_for_each_halving() {
        let radii = [0.004; 3];
        // The bunny ears' facts (mean edge 1.9 mm) against the built-in scene's mesh density.
        let coarse = SurfaceFacts { area: 5.6e-3, curvature_radius: 6.6e-3, occlusion: 0.11, edge_length: 1.9e-3 };
        let fine = SurfaceFacts { edge_length: 4.1e-4, ..coarse };
        let n = |f: &SurfaceFacts, e| count_for(f, radii, e);
        assert!(n(&coarse, 0.01) > n(&fine, 0.01));
        // The facet term's low order: halving the target multiplies the coarse mesh's count more.
        let growth = |f: &SurfaceFacts| n(f, 0.005) as f64 / n(f, 0.01) as f64;
        assert!(growth(&coarse) > 1.2 * growth(&fine), "{} against {}", growth(&coarse), growth(&fine));
        assert!(predict(&coarse, radii, 1000)[0].facet_term > 100.0 * predict(&fine, radii, 1000)[0].facet_term);
        // Nothing shadowed, no facet term: a coarse convex sphere converges like a fine one.
        let unshadowed = SurfaceFacts { occlusion: 0.0, ..coarse };
        assert_eq!(predict(&unshadowed, radii, 1000)[0].facet_term, 0.0);
    }

    #[test]
    fn a_prediction_that_is_not_a_number_chooses_the_most_samples_not_the_fewest() {
        let broken = SurfaceFacts { curvature_radius: f64::NAN, ..FACTS };
        assert_eq!(count_for(&broken, [0.004, f64::NAN, 0.004], 0.01), MAX_CHOSEN);
        assert_eq!(count_for(&FACTS, [0.004, f64::NAN, 0.004], 0.01), MAX_CHOSEN);
    }
}
