//! The dipole diffusion model (Jensen et al. 2001; seed paper section 2): the f64 reference.
//!
//! Every formula here has an f32 twin in `glsl/common/dipole.glsl`, written to stay finite over
//! the same inputs; `tests/optics_gpu.rs` evaluates both side by side.
//!
//! - [`material`]: a [`Material`] (per-channel `sigma_a`, `sigma_s_prime` in 1/mm, `eta`) and the
//!   derived per-channel [`Dipole`] in scene units (`sigma_tr`, `z_r`, `z_v`, `F_dr`, `A`, ...).
//! - [`albedo`]: the reduced albedo whose dipole reflects a given diffuse colour (`R_d,total`
//!   inverted), for materials given by their colour (glTF scenes).
//! - [`beam_single`]: single scattering between two surface points, the BSSRDF form of
//!   Jensen et al. 2001 Eq. 3 (the light carried along the refracted beam before it scatters).
//! - [`dipole`]: the diffuse reflectance profile `R_d(r)` (seed Eq. 8), its total, its exact
//!   disk and ring integrals, and the BSSRDF `S_d` (seed Eq. 9) with an energy-conserving
//!   normalization.
//! - [`directional_dipole`]: the directional dipole of Frisvad et al. 2014: the BSSRDF of a ray
//!   source, with the incident direction and the normals at entry and exit.
//! - [`fresnel`]: exact dielectric Fresnel reflectance and transmission, the first Fresnel moment,
//!   and the fits for the diffuse Fresnel reflectance `F_dr`.
//! - [`kernel`]: the near-field kernel: what one sample point of area `dA` contributes to a
//!   receiver at distance `r` in the discrete dipole sum (seed Eq. 11), so that the sum conserves
//!   energy whatever the ratio of diffusion length to sample spacing.
//! - [`model_error`]: the dipole's error against the radiative transfer equation, predicted
//!   from the object's size against the medium's lengths and the albedo (what `model = "auto"`
//!   weighs).
//! - [`presets`]: the measured materials of Jensen et al. 2001 and Narasimhan et al. 2006.
//! - [`single_scatter`]: the single-scattering reflectance of a half-space (Jensen et al. 2001,
//!   Eq. 3), the first-order term the dipole leaves out.
//! - [`quadrature`]: Gauss-Legendre nodes and weights, the rule the integrals above are taken
//!   with.
//! - [`gpu`]: the std430 records shared with the shaders, mirrored with `#[repr(C)]` + bytemuck.

pub mod albedo;
pub mod beam_single;
pub mod beam_table;
pub mod dipole;
pub mod directional_dipole;
pub mod fresnel;
pub mod gpu;
pub mod kernel;
pub mod material;
pub mod model_error;
pub mod presets;
pub mod quadrature;
pub mod single_scatter;
pub mod transport;

pub use dipole::Dipole;
pub use material::Material;
pub use presets::{MeasuredMaterial, Source};

/// Why a material or a query was refused. Every variant names the offending value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum OpticsError {
    /// A coefficient that is NaN, infinite or negative.
    #[error("{name} = {value} in channel {} is not a finite number >= 0 (1/mm)", channel_name(*channel))]
    BadCoefficient {
        /// The coefficient: `sigma_a`, `sigma_s'` or `sigma_s`.
        name: &'static str,
        /// Colour channel, 0 to 2 (R, G, B).
        channel: usize,
        /// The value refused: per mm from a [`Material`], per scene unit from [`Dipole::new`].
        value: f64,
    },
    /// Neither absorption nor scattering: there is no medium to diffuse in.
    #[error(
        "sigma_a = 0 and sigma_s' = 0 in channel {}: the medium neither absorbs nor \
         scatters, so the dipole model has nothing to describe",
        channel_name(*channel)
    )]
    NoExtinction {
        /// Colour channel, 0 to 2 (R, G, B).
        channel: usize,
    },
    /// The relative index of refraction is not in the range where the `F_dr` fits hold.
    #[error(
        "eta = {0} is not supported: the relative index of refraction must lie in \
         [{min:.4}, {max}], where the F_dr fits stay below 1",
        min = fresnel::ETA_MIN,
        max = fresnel::ETA_MAX
    )]
    BadEta(f64),
    /// The Henyey-Greenstein mean cosine is not in (-1, 1).
    #[error("g = {0} is not supported: the mean scattering cosine must lie in (-1, 1)")]
    BadG(f64),
    /// The scene scale is not a finite positive number.
    #[error("scale = {0} mm per scene unit is not a finite number > 0")]
    BadScale(f64),
    /// A coefficient converted to scene units falls outside the range the f32 twin handles.
    #[error(
        "sigma_t' = {value:e} per scene unit in channel {} (sigma_t' in 1/mm times the scale) \
         is outside [{min:e}, {max:e}], the range the f32 GPU twin represents safely",
        channel_name(*channel),
        min = material::SIGMA_T_PRIME_MIN,
        max = material::SIGMA_T_PRIME_MAX
    )]
    OutOfRange {
        /// Colour channel, 0 to 2 (R, G, B).
        channel: usize,
        /// `sigma_t'` per scene unit.
        value: f64,
    },
    /// No measured material has this name.
    #[error("unknown material preset {0:?}: `translucent material --list` shows the presets")]
    UnknownPreset(String),
}

/// "R", "G", "B" for channel 0, 1, 2 (error messages).
fn channel_name(channel: usize) -> &'static str {
    ["R", "G", "B"].get(channel).copied().unwrap_or("?")
}
