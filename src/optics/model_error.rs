//! The dipole's error against the radiative transfer equation, predicted from what it depends
//! on: how the object's size compares with the medium's lengths, and the albedo.
//!
//! The dipole (seed Eq. 8) is the diffusion solution of a half-space. A real object departs from
//! it in three ways, each a term of the prediction, summed in quadrature:
//!
//! - **On a half-space** the diffusion approximation itself is off, more so at low albedo: the
//!   total reflectance against the RTE is within 1.7% above albedo 0.99 and +6.8% to +24.9%
//!   between 0.3 and 0.9 (docs/PHYSICS.md, "On a half-space"). Term: `e_h = E_0 + K_H (1 - a')`.
//! - **Light the half-space loses below comes back out** of a finite object: it diffuses about
//!   one diffusion length `l_d = 1/sigma_tr` before it is absorbed, so what matters is `x =
//!   l_d / L` with `L` the object's size. The term grows as `x` for a large object (a first-order
//!   correction in the curvature) and saturates once the light fills the object:
//!   `e_s = E_S x / (x + X_0)`.
//! - **Light that crosses the object** in a few transport mean free paths `l' = 1/sigma_t'`,
//!   which diffusion cannot describe at all: `e_c = min(K_C l' / L, 1)`.
//!
//! `L` is `3 V / A` of a closed mesh (a sphere's radius), else the RMS curvature radius.
//! The constants are fitted to the study's measurements against the RTE reference
//! (`study --physics`; docs/PHYSICS.md, "Predicted model error", has the table and the fit's
//! residuals), the way `sampling::density` is fitted for the discretisation.

/// The dipole's error on a half-space at albedo 1 (`E_0`).
pub const FIT_HALF_SPACE_FLOOR: f64 = 0.012;
/// The half-space error's growth as the albedo falls (`K_H`): ketchup's red, albedo 0.75, is
/// +10.7% on a half-space.
pub const FIT_HALF_SPACE_SLOPE: f64 = 0.39;
/// The returned light's saturated error (`E_S`).
pub const FIT_SHAPE_SCALE: f64 = 0.33;
/// The diffusion length per size at which the returned light's error is half saturated (`X_0`).
pub const FIT_SHAPE_KNEE: f64 = 0.11;
/// The crossing light's error per free path over size (`K_C`).
pub const FIT_CROSSING_SCALE: f64 = 1.3;
/// What the transport kernel leaves of the dipole's error: the median ratio of the kernel's
/// measured error to the dipole's over the study scenes (0.17 to 0.63, docs/PHYSICS.md).
pub const FIT_KERNEL_SHARE: f64 = 0.4;

/// What the dipole's error in one channel of one object depends on.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ModelFacts {
    /// The reduced albedo `alpha' = sigma_s' / sigma_t'`.
    pub alpha_prime: f64,
    /// The diffusion length over the object's size, `x = l_d / L`.
    pub diffusion_over_size: f64,
    /// The transport mean free path over the object's size, `l' / L`.
    pub free_path_over_size: f64,
}

impl ModelFacts {
    /// The facts of a channel with diffusion length `l_d`, mean free path `l'` and reduced
    /// albedo `alpha'`, in an object of size `size` (all lengths in the same unit).
    pub fn new(alpha_prime: f64, diffusion_length: f64, free_path: f64, size: f64) -> ModelFacts {
        let size = size.max(f64::MIN_POSITIVE);
        ModelFacts { alpha_prime, diffusion_over_size: diffusion_length / size, free_path_over_size: free_path / size }
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
    let x = facts.diffusion_over_size.max(0.0);
    let half_space = FIT_HALF_SPACE_FLOOR + FIT_HALF_SPACE_SLOPE * (1.0 - a);
    // x / (x + X_0) without inf / inf where the size is zero.
    let returned = if x.is_infinite() { FIT_SHAPE_SCALE } else { FIT_SHAPE_SCALE * x / (x + FIT_SHAPE_KNEE) };
    // At most all of the light: the dipole then misses it whole.
    let crossing = (FIT_CROSSING_SCALE * facts.free_path_over_size.max(0.0)).min(1.0);
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

    fn error(a: f64, x: f64, y: f64) -> f64 {
        dipole_error(&ModelFacts { alpha_prime: a, diffusion_over_size: x, free_path_over_size: y }).error
    }

    #[test]
    fn a_large_high_albedo_object_is_predicted_near_the_half_space_error() {
        let e = error(0.999, 1e-4, 1e-6);
        assert!((e - FIT_HALF_SPACE_FLOOR).abs() < 1e-3, "{e}");
    }

    #[test]
    fn the_prediction_grows_as_the_object_shrinks_and_as_the_albedo_falls() {
        let sizes = [1e-3, 0.01, 0.1, 0.5, 2.0, 10.0];
        for w in sizes.windows(2) {
            assert!(error(0.99, w[1], w[1] / 20.0) > error(0.99, w[0], w[0] / 20.0), "{w:?}");
        }
        assert!(error(0.7, 0.3, 0.05) > error(0.95, 0.3, 0.05));
    }

    #[test]
    fn a_degenerate_size_is_predicted_finite_and_at_its_worst() {
        let zero = dipole_error(&ModelFacts::new(0.99, 1.0, 0.1, 0.0));
        assert!(zero.error.is_finite() && zero.error >= 1.0, "{zero:?}");
        let huge = dipole_error(&ModelFacts::new(0.99, 1.0, 0.1, f64::INFINITY));
        assert!((huge.error - (FIT_HALF_SPACE_FLOOR + FIT_HALF_SPACE_SLOPE * 0.01)).abs() < 1e-12);
    }
}
