//! `translucent`: translucent materials rendered with the dipole diffusion BSSRDF on raw Vulkan.
//!
//! The modules follow the data flow: `optics` (the dipole model, f64 reference), `mesh` (loading
//! and geometry), `sampling` (sample points with area weights), `gpu` (the Vulkan core, one concept
//! per file), `render` (one module per GPU pass, each with a GLSL file of the same name).
//! docs/ARCHITECTURE.md follows one frame through them.
//!
//! The types an application or a host engine needs are re-exported here:
//!
//! ```no_run
//! use translucent::{Change, Gpu, GpuOptions, Overrides, PreparedScene, Renderer, Scene};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let gpu = Gpu::new(&GpuOptions::default())?;
//! let scene = PreparedScene::new(&Scene::builtin(), &Overrides::default())?;
//! let mut renderer = Renderer::new(&gpu, scene)?;
//! let timings = renderer.frame(&renderer.plan(Change::Everything))?;
//! let (rgba8, _non_finite) = renderer.image()?;
//! # Ok(()) }
//! ```
//!
//! An engine with its own device wraps it with `Gpu::from_host` and draws into its own images
//! with `Renderer::with_target` and `Renderer::record_frame` (docs/GPU.md, examples/embed.rs).
//!
//! Features: `cli` (the `translucent` binary's dependencies) and `study` (`translucent::study`,
//! its charts and FLIP), both on by default. An engine can depend on it with
//! `default-features = false` for the renderer alone; `shaderc-from-source` builds glslang from
//! source instead of linking the distribution's static archives.

#![warn(missing_docs)]

#[macro_use]
mod names;

pub mod gpu;
pub mod mesh;
pub mod optics;
pub mod output;
pub mod reference;
pub mod render;
pub mod sampling;
pub mod scene;
#[cfg(feature = "study")]
pub mod study;

/// The `ash` this crate was built with: a host can name `translucent::ash::vk` and need not
/// match the version by hand (`HostVulkan` takes ash's handles and function tables).
pub use ash;
/// The `glam` this crate was built with: `CameraView` and the lights take its vectors and
/// matrices.
pub use glam;

pub use gpu::{EnabledFeatures, Gpu, GpuError, GpuOptions, HostVulkan, RequiredFeatures, required_features};
pub use optics::Material;
pub use output::{OutputError, OutputSet};
pub use render::camera::CameraView;
pub use render::edit::SceneEdit;
pub use render::error::RenderError;
pub use render::frame::{FrameTimings, LevelExitance, NonFinite, RecordedFrame};
pub use render::options::RendererOptions;
pub use render::plan::{Change, Pass, Plan};
pub use render::renderer::Renderer;
pub use render::target::{
    DeclaredImage, DepthConvention, DepthTest, HostAttachment, HostSync, HostTarget, ImageState, TargetDesc,
};
pub use scene::build::{Overrides, PreparedScene};
pub use scene::{GatherMode, Scene, SceneError};
