//! A translucent material: per colour channel (R, G, B) the absorption and reduced scattering
//! coefficients in 1/mm, and one relative index of refraction. [`Material::dipoles`] converts to
//! scene units with the scene scale (mm per scene unit) and derives each channel's [`Dipole`].

use super::dipole::{check_coefficient, check_eta};
use super::{Dipole, OpticsError, fresnel, presets};

/// Smallest `sigma_t'` per scene unit accepted: below it `z_r` and the distances the GPU squares
/// approach the f32 range.
pub const SIGMA_T_PRIME_MIN: f64 = 1e-12;
/// Largest `sigma_t'` per scene unit accepted (`R_d(0) ~ sigma_t'^2` must fit in f32).
pub const SIGMA_T_PRIME_MAX: f64 = 1e12;

/// Coefficients of a homogeneous translucent material, per channel, in 1/mm.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Material {
    /// A label: the preset's name, or "custom".
    pub name: String,
    /// Absorption coefficient `sigma_a` per channel (1/mm).
    pub sigma_a: [f64; 3],
    /// Reduced scattering coefficient `sigma_s' = sigma_s (1 - g)` per channel (1/mm).
    pub sigma_s_prime: [f64; 3],
    /// Relative index of refraction (material over surroundings).
    pub eta: f64,
}

impl Material {
    /// A material from `sigma_a` and `sigma_s'` in 1/mm. Refuses negative, NaN or infinite
    /// coefficients, a channel with neither absorption nor scattering, and an `eta` outside
    /// the range of the `F_dr` fits, naming the value.
    pub fn new(
        name: impl Into<String>,
        sigma_a: [f64; 3],
        sigma_s_prime: [f64; 3],
        eta: f64,
    ) -> Result<Self, OpticsError> {
        for c in 0..3 {
            check_coefficient("sigma_a", c, sigma_a[c])?;
            check_coefficient("sigma_s'", c, sigma_s_prime[c])?;
            if sigma_a[c] + sigma_s_prime[c] == 0.0 {
                return Err(OpticsError::NoExtinction { channel: c });
            }
        }
        check_eta(eta)?;
        Ok(Material { name: name.into(), sigma_a, sigma_s_prime, eta })
    }

    /// A material from the (unreduced) scattering coefficient `sigma_s` and the mean cosine `g`
    /// of the phase function: the diffusion approximation only sees `sigma_s' = sigma_s (1 - g)`
    /// (similarity relation; seed section 2 uses the reduced coefficients throughout).
    pub fn from_sigma_s(
        name: impl Into<String>,
        sigma_a: [f64; 3],
        sigma_s: [f64; 3],
        g: f64,
        eta: f64,
    ) -> Result<Self, OpticsError> {
        if !(g > -1.0 && g < 1.0) {
            return Err(OpticsError::BadG(g));
        }
        for (c, &s) in sigma_s.iter().enumerate() {
            check_coefficient("sigma_s", c, s)?;
        }
        Material::new(name, sigma_a, sigma_s.map(|s| s * (1.0 - g)), eta)
    }

    /// A measured material by name, case-insensitively (see [`presets::find`]).
    pub fn preset(name: &str) -> Result<Self, OpticsError> {
        Ok(presets::find(name)?.material())
    }

    /// The same material with another relative index of refraction.
    pub fn with_eta(self, eta: f64) -> Result<Self, OpticsError> {
        check_eta(eta)?;
        Ok(Material { eta, ..self })
    }

    /// The three channels' dipoles in scene units: a coefficient per mm times `mm_per_unit`
    /// is a coefficient per scene unit, and every derived length comes out in scene units.
    pub fn dipoles(&self, mm_per_unit: f64) -> Result<[Dipole; 3], OpticsError> {
        if !(mm_per_unit.is_finite() && mm_per_unit > 0.0) {
            return Err(OpticsError::BadScale(mm_per_unit));
        }
        let mut out = [None; 3];
        for (c, slot) in out.iter_mut().enumerate() {
            let sigma_a = self.sigma_a[c] * mm_per_unit;
            let sigma_s_prime = self.sigma_s_prime[c] * mm_per_unit;
            let sigma_t_prime = sigma_a + sigma_s_prime;
            if !(SIGMA_T_PRIME_MIN..=SIGMA_T_PRIME_MAX).contains(&sigma_t_prime) {
                return Err(OpticsError::OutOfRange { channel: c, value: sigma_t_prime });
            }
            *slot = Some(Dipole::new(sigma_a, sigma_s_prime, self.eta, c)?);
        }
        Ok(out.map(|d| d.expect("every channel was filled")))
    }

    /// `T(eta) = 1 - 2 FM1(eta)`, the hemispherical Fresnel transmittance that normalizes the
    /// BSSRDF (see [`Dipole::s_d`]).
    pub fn diffuse_transmittance(&self) -> f64 {
        fresnel::diffuse_transmittance(self.eta)
    }
}
