//! The dipole's error against the radiative transfer equation, predicted from what it depends
//! on: how the object's size compares with the medium's lengths, and the albedo.
//!
//! The dipole (seed Eq. 8) is the diffusion solution of a half-space. A real object departs from
//! it in three ways, each a term of the prediction, summed in quadrature:
//!
//! - **On a half-space** the diffusion approximation itself is off, more so at low albedo: the
//!   total reflectance against the RTE is within 1.7% above albedo 0.99 and +6.8% to +24.9%
//!   between 0.3 and 0.9 (docs/PHYSICS.md, "On a half-space"). Term: `e_h = E_0 + K_H (1 - a')`.
//! - **Light the half-space loses below comes back out** of a finite object, and grazing light
//!   refracts into a beam that runs about a free path under a surface that curves away. Both
//!   grow with the transport mean free path `l' = 1/sigma_t'` against the object's size `L`,
//!   and saturate once the light fills the object: `e_s = E_S y / (y + Y_0)`, `y = l' / L`.
//!   The diffusion length `l_d / L` in its place fitted worse (RMS log residual 0.24 against
//!   0.16): on one sphere the three channels, whose diffusion lengths differ twofold, err alike.
//! - **Light that crosses the object** in a few free paths, which diffusion cannot describe at
//!   all: `e_c = min(K_C y, 1)`.
//!
//! `L` is `3 V / A` of a closed mesh (a sphere's radius), else the RMS curvature radius.
//! The constants are fitted to the study's measurements against the RTE reference
//! (`study --physics`; docs/PHYSICS.md, "Which model a channel takes", has the table and the
//! fit's residuals), the way `sampling::density` is fitted for the discretisation.

/// The dipole's error on a half-space at albedo 1 (`E_0`).
pub const FIT_HALF_SPACE_FLOOR: f64 = 0.012;
/// The half-space error's growth as the albedo falls (`K_H`): ketchup's red, albedo 0.75, is
/// +10.7% on a half-space.
pub const FIT_HALF_SPACE_SLOPE: f64 = 0.39;
/// The returned light's saturated error (`E_S`).
pub const FIT_SHAPE_SCALE: f64 = 0.40;
/// The free path per size at which the returned light's error is half saturated (`Y_0`).
pub const FIT_SHAPE_KNEE: f64 = 0.033;
/// The crossing light's error per free path over size (`K_C`).
pub const FIT_CROSSING_SCALE: f64 = 1.1;
/// What the transport kernel leaves of the dipole's error: about the median ratio of the
/// kernel's measured error to the dipole's over the study scenes (0.17 to 0.63,
/// docs/PHYSICS.md).
pub const FIT_KERNEL_SHARE: f64 = 0.4;

/// What the dipole's error in one channel of one object depends on.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ModelFacts {
    /// The reduced albedo `alpha' = sigma_s' / sigma_t'`.
    pub alpha_prime: f64,
    /// The transport mean free path over the object's size, `y = l' / L`.
    pub free_path_over_size: f64,
}

impl ModelFacts {
    /// The facts of a channel with transport mean free path `l'` and reduced albedo `alpha'`,
    /// in an object of size `size` (in the same unit).
    pub fn new(alpha_prime: f64, free_path: f64, size: f64) -> ModelFacts {
        ModelFacts { alpha_prime, free_path_over_size: free_path / size.max(f64::MIN_POSITIVE) }
    }
}

/// The dipole's predicted error in one channel, with its terms.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DipoleError {
    /// `e_h`: the half-space's own error.
    pub half_space: f64,
    /// `e_s`: the light a finite object returns.
    pub returned: f64,
    /// `e_c`: the light that crosses the object.
    pub crossing: f64,
    /// The predicted relative RMS error per lit vertex against the RTE,
    /// `sqrt(e_h^2 + e_s^2 + e_c^2)`.
    pub error: f64,
}

/// The dipole's predicted error for `facts` (see the module's documentation). Non-finite facts
/// give NaN, which every comparison treats as over any target.
pub fn dipole_error(facts: &ModelFacts) -> DipoleError {
    let a = facts.alpha_prime.clamp(0.0, 1.0);
    let y = facts.free_path_over_size.max(0.0);
    let half_space = FIT_HALF_SPACE_FLOOR + FIT_HALF_SPACE_SLOPE * (1.0 - a);
    // y / (y + Y_0) without inf / inf where the size is zero.
    let returned = if y.is_infinite() { FIT_SHAPE_SCALE } else { FIT_SHAPE_SCALE * y / (y + FIT_SHAPE_KNEE) };
    // At most all of the light: the dipole then misses it whole.
    let crossing = (FIT_CROSSING_SCALE * y).min(1.0);
    let error = half_space.hypot(returned).hypot(crossing);
    DipoleError { half_space, returned, crossing, error }
}

/// The transport kernel's predicted error where the dipole's is `dipole`.
pub fn kernel_error(dipole: f64) -> f64 {
    FIT_KERNEL_SHARE * dipole
}

#[cfg(test)]
mod tests {
    use super::*;

    fn error(a: f64, y: f64) -> f64 {
        dipole_error(&ModelFacts { alpha_prime: a, free_path_over_size: y }).error
    }

    #[test]
    fn a_large_high_albedo_object_is_predicted_near_the_half_space_error() {
        let e = error(0.999, 1e-6);
        assert!((e - FIT_HALF_SPACE_FLOOR).abs() < 1e-3, "{e}");
    }

    #[test]
    fn the_prediction_grows_as_the_object_shrinks_and_as_the_albedo_falls() {
        let paths = [1e-4, 1e-3, 0.01, 0.1, 0.5, 0.8];
        for w in paths.windows(2) {
            assert!(error(0.99, w[1]) > error(0.99, w[0]), "{w:?}");
        }
        assert!(error(0.7, 0.05) > error(0.95, 0.05));
    }

    #[test]
    fn a_degenerate_size_is_predicted_finite_and_at_its_worst() {
        let zero = dipole_error(&ModelFacts::new(0.99, 0.1, 0.0));
        assert!(zero.error.is_finite() && zero.error >= 1.0, "{zero:?}");
        let huge = dipole_error(&ModelFacts::new(0.99, 0.1, f64::INFINITY));
        assert!((huge.error - (FIT_HALF_SPACE_FLOOR + FIT_HALF_SPACE_SLOPE * 0.01)).abs() < 1e-12);
    }

    /// The dipole's measured error per lit vertex against the RTE reference, the reference's
    /// noise taken out (docs/PHYSICS.md, "Which model a channel takes"): scene and channel,
    /// `alpha'`, `l' / L`, error.
    const MEASURED: [(&str, f64, f64, f64); 19] = [
        ("marble sphere 100 mm r", 0.9990, 0.00456, 0.040),
        ("marble sphere 100 mm g", 0.9984, 0.00381, 0.042),
        ("marble sphere 100 mm b", 0.9976, 0.00333, 0.050),
        ("marble sphere 30 mm r", 0.9990, 0.0152, 0.125),
        ("marble sphere 30 mm g", 0.9984, 0.0127, 0.105),
        ("marble sphere 30 mm b", 0.9976, 0.0111, 0.097),
        ("marble sphere 10 mm r", 0.9990, 0.0456, 0.279),
        ("marble sphere 10 mm g", 0.9984, 0.0381, 0.297),
        ("marble sphere 10 mm b", 0.9976, 0.0333, 0.258),
        ("built-in bunny r", 0.9990, 0.0359, 0.188),
        ("built-in bunny g", 0.9984, 0.0300, 0.166),
        ("built-in bunny b", 0.9976, 0.0262, 0.161),
        ("bunny's ears r", 0.9990, 0.0338, 0.177),
        ("bunny's ears g", 0.9984, 0.0282, 0.187),
        ("bunny's ears b", 0.9976, 0.0246, 0.185),
        ("skim milk sphere 10 mm r", 0.9980, 0.1426, 0.296),
        ("skim milk sphere 10 mm g", 0.9980, 0.0818, 0.263),
        ("skim milk sphere 10 mm b", 0.9926, 0.0522, 0.311),
        ("ketchup sphere 10 mm r", 0.7469, 0.4149, 0.650),
    ];

    #[test]
    fn the_fit_predicts_the_measured_dipole_errors_within_its_stated_residual() {
        let log_residual = |(_, a, y, e): &(&str, f64, f64, f64)| (error(*a, *y) / e).ln();
        let rms = (MEASURED.iter().map(|m| log_residual(m).powi(2)).sum::<f64>() / MEASURED.len() as f64).sqrt();
        assert!(rms < 0.17, "RMS log residual {rms}");
        for m in &MEASURED {
            assert!(log_residual(m).abs() < 0.31, "{}: predicted {}, measured {}", m.0, error(m.1, m.2), m.3);
        }
    }
}
