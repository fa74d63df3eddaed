//! The CPU reference (f64): splat with ray-cast visibility and the dipole gather, the ground truth for tests and the accuracy study.

pub mod bvh;
