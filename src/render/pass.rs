//! The one interface every GPU pass records through. A pass is built once from the scene's GPU
//! data (`GpuScene`) and records each frame from `FrameInputs`, followed by the barriers that
//! make its own writes visible to whatever reads them next (later passes, the next frame, or the
//! host after the fence). Adding a pass: one GLSL file, one module implementing `RenderPass`,
//! one entry in `plan::Pass` and in `Renderer::pass`.

use super::gpu_scene::GpuScene;
use super::plan::Plan;
use super::shade::HostTarget;
use crate::gpu::Gpu;
use ash::vk;
use glam::{Mat4, Vec3};

/// What one frame gives the passes besides the scene data they were built with.
pub struct FrameInputs<'a> {
    /// The device the pass records through.
    pub gpu: &'a Gpu,
    /// The scene's GPU data: buffers, draw ranges, receivers, shadow matrices.
    pub scene: &'a GpuScene,
    /// The frame's plan.
    pub plan: &'a Plan,
    /// Shadow-map layers to redraw; `None` redraws every layer.
    pub shadow_layers: Option<&'a [u32]>,
    /// World -> clip of the camera, and its position.
    pub view_proj: Mat4,
    /// Camera position in world space (for the specular lobe).
    pub eye: Vec3,
    /// Clear colour of the HDR image.
    pub background: [f32; 3],
    /// The host's attachments, when the renderer draws into a host engine's images.
    pub target: Option<&'a HostTarget>,
    /// Multiplier on linear radiance before the tone curve (`render.exposure`).
    pub exposure: f32,
}

/// A GPU pass: built once over the scene's GPU data, then recorded into the command buffer of every
/// frame whose plan runs it, followed by the barriers from its own writes to their readers.
/// `Renderer::pass` maps each `plan::Pass` to one.
pub trait RenderPass {
    /// Record the pass into `cmd` (recording, outside any rendering), then its barriers.
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs);
}
