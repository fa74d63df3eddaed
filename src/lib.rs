//! `translucent`: translucent materials rendered with the dipole diffusion BSSRDF on raw Vulkan.
//!
//! The modules follow the data flow: `optics` (the dipole model, f64 reference), `mesh` (loading
//! and geometry), `sampling` (sample points with area weights), `gpu` (the Vulkan core, one concept
//! per file), `render` (one module per GPU pass, each with a GLSL file of the same name).

pub mod gpu;
pub mod mesh;
pub mod optics;
pub mod output;
pub mod reference;
pub mod render;
pub mod sampling;
pub mod scene;
