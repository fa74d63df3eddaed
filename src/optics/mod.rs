//! The dipole diffusion model (Jensen et al. 2001; seed paper section 2): f64 reference.
