//! The `Renderer`: one prepared scene's passes over its GPU data, recording the passes each
//! frame needs. This file makes it and answers what it holds; recording is `record`, reading
//! back `readback`, editing the scene `edit`, and the table of passes `passes`.

mod edit;
mod marks;
mod passes;
mod readback;
mod record;

use super::camera::CameraView;
use super::error::RenderError;
use super::fit::{check_fits, check_host_formats};
use super::gpu_scene::GpuScene;
use super::graph::{Resource, Resources};
use super::options::{FRAMES_IN_FLIGHT, MAX_FRAMES_IN_FLIGHT, RendererOptions};
use super::pass::PassContext;
use super::plan::{self, Change, Plan, Planner};
use super::target::{DepthConvention, TargetDesc};
use super::targets::FrameTargets;
use crate::gpu::{Gpu, GpuTimer, Hazards};
use crate::scene::build::PreparedScene;
use crate::scene::needs::SceneNeeds;
use ash::vk;
use passes::Passes;
use std::cell::RefCell;
use std::sync::Arc;

/// Renders one prepared scene: its passes over its GPU data, recording the passes each frame
/// needs into a command buffer (the host's, or its own for `frame`).
///
/// **Lifetime.** Frames recorded with `record_frame`, `record_exitance` or `record_plan` into a
/// host's command buffer use the renderer's pipelines, buffers and images until their
/// submission finishes, and the host's own commands after them may too. Dropping the renderer
/// (and the edits that replace some of them: a resize, a transform, `bake_static_levels`)
/// therefore first waits for the `Gpu`'s queue to go idle (`vkQueueWaitIdle`) whenever a frame
/// was recorded into a host's command buffer since the last such wait, whatever the order the
/// host submitted them in. So no order of safe calls destroys what a frame in flight uses. A
/// host must submit the command buffers it recorded into before dropping the renderer, or never
/// (a buffer recorded against a dropped renderer is invalid, as after any destroyed object);
/// one it will never submit it hands to `discard`.
///
/// **Threads.** A renderer is `Send`, not `Sync`: it moves to the thread an engine records on,
/// and one thread uses it at a time. The `Gpu` it shares locks its queue for its own
/// submissions; a host that submits on the same queue from other threads locks it too
/// (docs/GPU.md).
pub struct Renderer {
    gpu: Arc<Gpu>,
    scene: PreparedScene,
    needs: SceneNeeds,
    // Passes drop before the data their descriptor sets point into.
    /// Every registered pass built for this scene and target (`registry::for_each_pass!`).
    passes: Passes,
    /// One timer per frame that may be in flight (empty without timestamps).
    timers: Vec<GpuTimer>,
    /// The generation of the frame each slot (of `frames_in_flight`) holds.
    slot_frames: Vec<u64>,
    /// Each frame's mark of having run, per slot: what `read_timings` trusts.
    marks: marks::FrameMarks,
    /// Frames recorded so far (the last one's generation).
    generation: u64,
    /// A frame was recorded into a host's command buffer since the queue was last waited for:
    /// Drop and the edits that replace resources wait for it.
    host_frames: bool,
    /// The state before the last frame was recorded, for `discard`.
    undo: Option<record::Undo>,
    /// The extent of the last `HostTarget`: the planner's levels of detail follow it.
    host_extent: Option<vk::Extent2D>,
    /// Tells its `RecordedFrame`s from another renderer's (`NEXT_RENDERER`).
    id: usize,
    /// The shadow maps and camera images the passes' descriptor sets point into.
    targets: FrameTargets,
    gpu_scene: GpuScene,
    /// What every frame resource last went through, across frames: the barriers come from it.
    hazards: RefCell<Hazards<Resource>>,
    background: [f32; 3],
    target: TargetDesc,
    /// The host's choices it was made with.
    options: RendererOptions,
    camera: CameraView,
    /// The frames' history: pending change, stale objects, gathered levels, baked levels.
    planner: Planner,
}

/// Share of an opaque object's brightest per-vertex sky light by which two neighbouring
/// vertices may differ and still be simplified away (`Renderer::bake_static_levels`): 0.2%,
/// under what a person sees in a smooth gradient. Measured on the default scene's floor
/// (README, "Performance").
pub const SKY_LOCK_SHARE: f32 = 0.002;

/// The next renderer's `id`: a frame handed to another renderer's `read_timings` would read
/// that renderer's queries.
static NEXT_RENDERER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

impl Renderer {
    /// Frames a host may have in flight at once unless it chooses
    /// (`RendererOptions::frames_in_flight`): each has its own timestamp queries.
    pub const FRAMES_IN_FLIGHT: usize = FRAMES_IN_FLIGHT;
    /// The most frames in flight a renderer takes (`options::MAX_FRAMES_IN_FLIGHT`).
    pub const MAX_FRAMES_IN_FLIGHT: usize = MAX_FRAMES_IN_FLIGHT;

    /// A renderer drawing into its own HDR image, tone-mapped for readback (the CLI's path).
    pub fn new(gpu: &Arc<Gpu>, scene: PreparedScene) -> Result<Renderer, RenderError> {
        Renderer::with_target(gpu, scene, TargetDesc::Own)
    }

    /// A renderer drawing into `target`: its own images, or a host engine's of the given
    /// formats (then `record_frame` takes the host's attachments, and there is no tone map).
    pub fn with_target(gpu: &Arc<Gpu>, scene: PreparedScene, target: TargetDesc) -> Result<Renderer, RenderError> {
        Renderer::with_options(gpu, scene, target, RendererOptions::default())
    }

    /// As `with_target`, with the host's choices (`RendererOptions`: frames in flight, the
    /// depth test), checked before anything is made.
    pub fn with_options(
        gpu: &Arc<Gpu>,
        scene: PreparedScene,
        target: TargetDesc,
        options: RendererOptions,
    ) -> Result<Renderer, RenderError> {
        options.check(gpu, target)?;
        check_fits(gpu, &scene)?;
        if let TargetDesc::Host { color_format, depth_format } = target {
            check_host_formats(gpu, color_format, depth_format)?;
        }
        let planner = Planner::new(scene.objects.len(), Change::Everything);
        let needs = Self::needs_of(&scene, target, &planner);
        if needs.host_target && needs.pixel_gather {
            return Err(RenderError::PixelGatherOnHostTarget);
        }
        if let Some(i) = scene.objects.iter().position(|o| o.single_channels().contains(&true))
            && needs.pixel_gather
        {
            return Err(RenderError::SingleScatteringOnPixelGather(i));
        }
        let gpu_scene = GpuScene::new(gpu, &scene)?;
        let settings = &scene.scene.file.render;
        let camera = (target == TargetDesc::Own).then_some((scene.scene.file.camera.resolution, needs.pixel_gather));
        let targets = FrameTargets::new(gpu, settings.shadow_map_size, scene.shadow_layers, camera)?;
        let resources = Resources { scene: &gpu_scene, targets: &targets };
        let context = PassContext { gpu, resources, scene: &scene, needs: &needs, target, options: &options };
        let passes = Passes::build(&context)?;
        let mut hazards = Hazards::new();
        targets.track(&mut hazards);
        // Timing is optional: a queue without timestamps still renders.
        let timers = (0..options.frames_in_flight)
            .map(|_| GpuTimer::new(gpu, 8))
            .collect::<Result<Vec<_>, _>>()
            .inspect_err(|e| log::warn!("no GPU timings: {e}"))
            .unwrap_or_default();
        Ok(Renderer {
            gpu: gpu.clone(),
            passes,
            slot_frames: vec![0; options.frames_in_flight],
            marks: marks::FrameMarks::new(gpu, options.frames_in_flight)?,
            timers,
            generation: 0,
            host_frames: false,
            undo: None,
            host_extent: None,
            id: NEXT_RENDERER.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            targets,
            gpu_scene,
            hazards: RefCell::new(hazards),
            background: scene.background(),
            needs,
            target,
            camera: match options.depth.convention {
                DepthConvention::Standard => CameraView::of_scene(&scene),
                DepthConvention::Reversed => CameraView::of_scene(&scene).reversed_depth(),
            },
            options,
            planner,
            scene,
        })
    }

    /// The host's choices this renderer was made with.
    pub fn options(&self) -> RendererOptions {
        self.options
    }

    /// The prepared scene this renderer draws.
    pub fn scene(&self) -> &PreparedScene {
        &self.scene
    }

    /// The scene's data on the GPU (for readback, or an engine binding it elsewhere).
    pub fn scene_data(&self) -> &GpuScene {
        &self.gpu_scene
    }

    /// The scene's data on the GPU, to write (a test feeding the gather its own input) with no
    /// frame in flight: the next frame's readers of any of it wait for those writes.
    pub fn scene_data_mut(&mut self) -> &mut GpuScene {
        let mut hazards = self.hazards.borrow_mut();
        for r in super::graph::SCENE_BUFFERS.iter().copied() {
            hazards.written_outside(r);
        }
        drop(hazards);
        &mut self.gpu_scene
    }

    /// The passes a frame with this change would run, seen from the current camera, and what
    /// each object gets.
    pub fn plan(&self, change: Change) -> Plan {
        self.planner.plan_for(&self.needs, &self.view(), change)
    }

    /// The current camera as the planner sees it.
    /// Its height in pixels is the host target's (the last `HostTarget` given) or the own
    /// image's: levels of detail follow the pixels really drawn, not `camera.resolution`.
    pub fn view(&self) -> plan::View {
        let height = self.host_extent.map_or(self.scene.scene.file.camera.resolution[1], |e| e.height);
        plan::View::of_camera(&self.camera, height)
    }

    /// What the planner knows of the scene (per-object facts included).
    pub fn needs(&self) -> &SceneNeeds {
        &self.needs
    }

    /// What changed since the last recorded frame (`record_frame` plans from it).
    pub fn pending_change(&self) -> Option<Change> {
        self.planner.pending()
    }

    /// The frames' history the planner keeps.
    pub fn planner(&self) -> &Planner {
        &self.planner
    }

    /// The camera the next frames are drawn from.
    pub fn camera(&self) -> CameraView {
        self.camera
    }

    /// What the planner weighs for `scene` drawn into `target`, with the baked levels as
    /// `planner` has them (`plan::needs`).
    fn needs_of(scene: &PreparedScene, target: TargetDesc, planner: &Planner) -> SceneNeeds {
        plan::needs(scene, target != TargetDesc::Own, planner.baked_levels())
    }

    /// An error unless `object` is an index of the scene's objects.
    fn check_object(&self, object: usize) -> Result<(), RenderError> {
        let objects = self.scene.objects.len();
        if object < objects { Ok(()) } else { Err(RenderError::NoSuchObject { object, objects }) }
    }

    /// Bytes of device memory in use by the allocator.
    pub fn device_memory(&self) -> u64 {
        self.gpu.memory_usage().0
    }

    /// Wait for the queue to go idle if a frame was recorded into a host's command buffer since
    /// the last wait (the lifetime rule on `Renderer`).
    fn wait_for_recorded(&mut self) -> Result<(), RenderError> {
        if self.host_frames {
            self.gpu.wait_queue_idle()?;
            self.host_frames = false;
        }
        Ok(())
    }

    /// What the shading pass clears the colour to: the background's radiance, or under
    /// `Output::Display` its display value, as the tone map would draw it (so that a host's
    /// swapchain image shows what `translucent render` writes).
    fn clear_color(&self) -> [f32; 3] {
        match self.options.output {
            crate::render::options::Output::Linear => self.background,
            crate::render::options::Output::Display => {
                let exposure = f64::from(self.scene.scene.file.render.exposure);
                self.background.map(|c| f32::from(crate::render::tonemap::display_value(f64::from(c), exposure)) / 255.0)
            }
        }
    }

    /// Identifies this renderer's frames: a number no other renderer of this process has.
    fn id(&self) -> usize {
        self.id
    }
}


impl Drop for Renderer {
    fn drop(&mut self) {
        if let Err(e) = self.wait_for_recorded() {
            // A lost device: nothing will run again, so destroying is safe.
            log::error!("dropping a renderer: {e}");
        }
    }
}


/// A renderer moves to the thread an engine records on (issue 47): every field is `Send`.
const _: fn() = || {
    fn send<T: Send>() {}
    send::<Renderer>();
};
