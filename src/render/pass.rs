//! The one interface every GPU pass records through. A pass is built once from the frame's
//! resources (`graph::Resources`: the scene's GPU data and the frame targets), declares each
//! frame which named resources it reads and writes (`uses`), and records from `FrameInputs`.
//! The pass loop records the barriers its declaration needs before it (`FrameInputs::before`),
//! so a pass knows nothing of who reads its output. Adding a pass: one GLSL file, one module
//! implementing `RenderPass` and `RegisteredPass`, and one line in `registry::for_each_pass!`.

use super::error::RenderError;
use super::gpu_scene::GpuScene;
use super::graph::{Resource, Resources, Use};
use super::options::RendererOptions;
use super::plan::{Plan, SceneNeeds};
use super::target::{HostTarget, TargetDesc};
use super::targets::FrameTargets;
use crate::gpu::{Gpu, Hazards};
use crate::scene::build::PreparedScene;
use ash::vk;
use glam::{Mat4, Vec3};
use std::cell::RefCell;
use std::sync::Arc;

/// What one frame gives the passes besides the scene data they were built with.
pub struct FrameInputs<'a> {
    /// The device the pass records through.
    pub gpu: &'a Gpu,
    /// The scene's GPU data: buffers, draw ranges, receivers, shadow matrices.
    pub scene: &'a GpuScene,
    /// The shadow maps and the camera's own images.
    pub targets: &'a FrameTargets,
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
    /// What every resource last went through, across frames: where barriers come from.
    pub hazards: &'a RefCell<Hazards<Resource>>,
}

impl FrameInputs<'_> {
    /// Record the barrier that `uses` need against everything recorded before (this frame's
    /// earlier passes and steps, and earlier frames). The pass loop calls it with each pass's
    /// declaration; a pass of several steps calls it between them for what one step hands the
    /// next.
    pub fn before(&self, cmd: vk::CommandBuffer, uses: &[Use]) {
        self.hazards.borrow_mut().before(self.gpu.device(), cmd, uses);
    }
}

/// A GPU pass: built once over the frame's resources, then recorded into the command buffer of
/// every frame whose plan runs it. The registry (`registry::for_each_pass!`) maps each
/// `plan::Pass` to one. `Send`, so that the renderer holding it moves to an engine's render
/// thread.
pub trait RenderPass: Send {
    /// Every access this frame's recording makes: what it reads and writes, and how. The pass
    /// loop records the barriers these need before `record`.
    fn uses(&self, frame: &FrameInputs) -> Vec<Use>;
    /// Record the pass into `cmd` (recording, outside any rendering).
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs);
}

/// A pass that runs in the gather's slot after the gather, on the frames that call for it (the
/// between-points single scattering, the transport kernel).
pub trait AfterGather: RenderPass {
    /// Whether this frame's plan has work for it.
    fn runs(frame: &FrameInputs) -> bool;
}

/// The gather's slot: the gather, then `then` where this frame calls for it, a barrier between
/// them from their declarations. Its uses are the gather's; `then` declares its own when it runs.
pub struct GatherThen<P> {
    /// What runs first: the gather `render.gather` names (itself perhaps a `GatherThen`).
    pub gather: Box<dyn RenderPass>,
    /// What runs after it.
    pub then: P,
}

impl<P: AfterGather> RenderPass for GatherThen<P> {
    fn uses(&self, frame: &FrameInputs) -> Vec<Use> {
        self.gather.uses(frame)
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        self.gather.record(cmd, frame);
        if P::runs(frame) {
            frame.before(cmd, &self.then.uses(frame));
            self.then.record(cmd, frame);
        }
    }
}

/// What a registered pass is built from: the device, the frame's shared resources, the scene
/// and what the planner knows of it, and the host's choices.
pub struct PassContext<'a> {
    /// The device the pass's pipelines are made on.
    pub gpu: &'a Arc<Gpu>,
    /// The scene's buffers and the frame targets, to bind by name.
    pub resources: Resources<'a>,
    /// The prepared scene (its settings choose among a pass's variants).
    pub scene: &'a PreparedScene,
    /// What the planner weighs for this scene and target (e.g. whether the gather is per pixel).
    pub needs: &'a SceneNeeds,
    /// Where shading draws.
    pub target: TargetDesc,
    /// The host's choices (depth test, samples).
    pub options: &'a RendererOptions,
}

/// When the renderer builds a pass anew, besides when it is made.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Rebuild {
    /// The own target was resized (`SceneEdit::Resize`): its camera images are new.
    Resize,
    /// The scene's GPU data was made anew (`SceneEdit::Transform`): every scene buffer is new.
    SceneData,
}

/// A pass the registry (`registry::for_each_pass!`) can build: how, and when again.
pub trait RegisteredPass: RenderPass + Sized {
    /// The events after which the pass is built anew, because it binds what they replace.
    const REBUILT_ON: &'static [Rebuild];
    /// The pass for `context`, or `None` where this renderer has none (the tone map of a host
    /// target).
    fn build(context: &PassContext) -> Result<Option<Self>, RenderError>;
}
