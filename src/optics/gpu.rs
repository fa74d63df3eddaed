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
    pub alpha_prime: f32,
    pub sigma_tr: f32,
    pub z_r: f32,
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
    pub sigma_a: f32,
    pub sigma_s_prime: f32,
    pub eta: f32,
    /// Scene scale, mm per scene unit.
    pub mm_per_unit: f32,
    /// Distance from the source (scene units): for `R_d`, the kernels and the disk radius.
    pub r: f32,
    /// Sample area `dA` (scene units squared) for the kernels.
    pub area: f32,
    pub cos_theta_i: f32,
    pub cos_theta_o: f32,
    /// `T(eta) = 1 - 2 FM1(eta)` computed on the CPU (the BSSRDF normalization).
    pub t_eta: f32,
    pub _pad: [f32; 3],
}

/// One result record written by `glsl/dipole_eval.comp` (`EvalOutput` there): every function
/// of `glsl/common/dipole.glsl` evaluated for the matching input.
#[allow(non_snake_case)] // F_dr, A: the paper's symbols
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DipoleEvalOutput {
    pub sigma_t_prime: f32,
    pub alpha_prime: f32,
    pub sigma_tr: f32,
    pub F_dr: f32,
    pub A: f32,
    pub z_r: f32,
    pub z_v: f32,
    /// `R_d(r)` (seed Eq. 8).
    pub r_d: f32,
    pub r_d_total: f32,
    /// Disk integral `P(r)`.
    pub r_d_disk: f32,
    /// [`crate::optics::kernel::footprint_kernel`]`(r, area)`.
    pub kernel: f32,
    /// [`crate::optics::kernel::near_energy`]`(b)`, `b = 1.5 sqrt(area)`.
    pub near_energy: f32,
    /// [`crate::optics::kernel::r_d_far`]`(r, b)`.
    pub r_d_far: f32,
    /// `F_r(cos_theta_i, eta)`.
    pub fresnel_r: f32,
    /// `F_t(cos_theta_o, eta)`.
    pub fresnel_t: f32,
    /// `S_d(r, cos_theta_i, cos_theta_o)` (seed Eq. 9, normalized by `t_eta`).
    pub s_d: f32,
}
