//! std430 records shared with the shaders, mirrored with `#[repr(C)]` + bytemuck. Each struct is
//! written once in GLSL (named in its doc) and here; `tests/optics.rs` pins sizes and offsets.
//! Only 4-byte scalars, so std430 and `repr(C)` agree on every offset.

use super::Dipole;
use bytemuck::{Pod, Zeroable};

/// The dipole constants one channel needs in a shader: `DipoleChannel` in
/// `glsl/common/dipole.glsl`. The renderer uploads three of these per material.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DipoleChannelGpu {
    /// Reduced albedo `alpha'` ([`Dipole::alpha_prime`]).
    pub alpha_prime: f32,
    /// Effective transport coefficient `sigma_tr` per scene unit ([`Dipole::sigma_tr`]).
    pub sigma_tr: f32,
    /// Depth of the real source, scene units ([`Dipole::z_r`]).
    pub z_r: f32,
    /// Height of the virtual source, scene units ([`Dipole::z_v`]).
    pub z_v: f32,
}

impl From<&Dipole> for DipoleChannelGpu {
    fn from(d: &Dipole) -> Self {
        DipoleChannelGpu {
            alpha_prime: d.alpha_prime as f32,
            sigma_tr: d.sigma_tr as f32,
            z_r: d.z_r as f32,
            z_v: d.z_v as f32,
        }
    }
}

/// One parameter record read by `glsl/dipole_eval.comp` (`EvalInput` there): a channel's
/// coefficients in 1/mm, the scene scale, and where to evaluate.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DipoleEvalInput {
    /// Absorption coefficient `sigma_a` (1/mm).
    pub sigma_a: f32,
    /// Reduced scattering coefficient `sigma_s'` (1/mm).
    pub sigma_s_prime: f32,
    /// Relative index of refraction.
    pub eta: f32,
    /// Scene scale, mm per scene unit.
    pub mm_per_unit: f32,
    /// Distance from the source (scene units): for `R_d`, the kernels and the disk radius.
    pub r: f32,
    /// Sample area `dA` (scene units squared) for the kernels.
    pub area: f32,
    /// Cosine of the incident angle, for `F_r` and `S_d`.
    pub cos_theta_i: f32,
    /// Cosine of the outgoing angle, for `F_t` and `S_d`.
    pub cos_theta_o: f32,
    /// `T(eta) = 1 - 2 FM1(eta)` computed on the CPU (the BSSRDF normalization).
    pub t_eta: f32,
    /// Padding to 48 bytes, the GLSL record's `pad0..pad2`.
    pub _pad: [f32; 3],
}

/// One result record written by `glsl/dipole_eval.comp` (`EvalOutput` there): every function
/// of `glsl/common/dipole.glsl` evaluated for the matching input.
#[allow(non_snake_case)] // F_dr, A: the paper's symbols
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DipoleEvalOutput {
    /// Reduced extinction coefficient `sigma_t'` per scene unit.
    pub sigma_t_prime: f32,
    /// Reduced albedo `alpha'`.
    pub alpha_prime: f32,
    /// Effective transport coefficient `sigma_tr` per scene unit (seed Eq. 7).
    pub sigma_tr: f32,
    /// Diffuse Fresnel reflectance `F_dr`.
    pub F_dr: f32,
    /// Boundary coefficient `A = (1 + F_dr) / (1 - F_dr)`.
    pub A: f32,
    /// Depth of the real source, scene units.
    pub z_r: f32,
    /// Height of the virtual source, scene units.
    pub z_v: f32,
    /// `R_d(r)` (seed Eq. 8).
    pub r_d: f32,
    /// Total diffuse reflectance `R_d,total`.
    pub r_d_total: f32,
    /// Disk integral `P(r)`.
    pub r_d_disk: f32,
    /// [`crate::optics::kernel::footprint_kernel`]`(r, area)`.
    pub kernel: f32,
    /// [`crate::optics::kernel::near_energy`]`(b)`, `b = 1.5 sqrt(area)`.
    pub near_energy: f32,
    /// [`crate::optics::kernel::r_d_far`]`(r, b)`.
    pub r_d_far: f32,
    /// [`crate::optics::kernel::r_d_far_cluster`]`(r, b, 0.3 r^2, 0.1 r^2)`.
    pub r_d_far_cluster: f32,
    /// `F_r(cos_theta_i, eta)`.
    pub fresnel_r: f32,
    /// `F_t(cos_theta_o, eta)`.
    pub fresnel_t: f32,
    /// `S_d(r, cos_theta_i, cos_theta_o)` (seed Eq. 9, normalized by `t_eta`).
    pub s_d: f32,
    /// [`crate::optics::kernel::near_kept_at_edge`]`(b, t = r)`.
    pub near_kept_edge: f32,
}
