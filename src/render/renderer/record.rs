//! Recording frames: into a host's command buffer (`record_frame`, `record_exitance`,
//! `record_plan`) or a submission of the renderer's own (`frame`), each pass after the barrier
//! its declaration needs; and reading a recorded frame's timings.

use super::Renderer;
use crate::gpu::{Access, GpuTimer};
use crate::render::error::RenderError;
use crate::render::frame::{FrameTimings, RecordedFrame};
use crate::render::graph::{HOST_READ, Resource, read, write};
use crate::render::pass::FrameInputs;
use crate::render::plan::{Change, EveryReason, Pass, Plan, ReceiverScope};
use crate::render::target::{HostSync, HostTarget, TargetDesc};
use crate::scene::GatherMode;
use ash::vk;

impl Renderer {
    /// Record the frame that what changed since the last one calls for (the first: everything)
    /// into `cmd`, a primary command buffer the host is recording, outside any rendering. No
    /// submission and no wait: the host submits, and may read `read_timings` after its fence.
    /// `target` is the host's attachments for a `TargetDesc::Host` renderer, `None` otherwise.
    ///
    /// ```no_run
    /// use translucent::ash::vk;
    /// use translucent::{
    ///     Gpu, HostAttachment, HostSync, HostTarget, Overrides, PreparedScene, Renderer, Scene, TargetDesc,
    /// };
    /// # fn frame(
    /// #     gpu: &std::sync::Arc<Gpu>,
    /// #     cmd: vk::CommandBuffer,
    /// #     color_view: vk::ImageView,
    /// #     depth_view: vk::ImageView,
    /// # ) -> Result<(), Box<dyn std::error::Error>> {
    /// let (color_format, depth_format) = (vk::Format::R16G16B16A16_SFLOAT, vk::Format::D32_SFLOAT);
    /// let scene = PreparedScene::new(&Scene::builtin(), &Overrides::default())?;
    /// let mut renderer = Renderer::with_target(gpu, scene, TargetDesc::Host { color_format, depth_format })?;
    /// // Each frame: `cmd` is recording, outside any rendering, and the engine's images are in
    /// // COLOR_ATTACHMENT_OPTIMAL and DEPTH_ATTACHMENT_OPTIMAL (docs/GPU.md).
    /// let (extent, samples) = (vk::Extent2D { width: 1280, height: 720 }, vk::SampleCountFlags::TYPE_1);
    /// let target = HostTarget {
    ///     color: HostAttachment { view: color_view, format: color_format, extent, samples },
    ///     depth: HostAttachment { view: depth_view, format: depth_format, extent, samples },
    ///     resolve: None,
    ///     extent,
    ///     offset: vk::Offset2D::default(),
    ///     sync: HostSync::Attachments,
    ///     load: true,
    /// };
    /// let recorded = renderer.record_frame(cmd, Some(&target))?;
    /// // ... the engine's own passes; it ends `cmd`, submits it and waits on its fence ...
    /// let timings = renderer.read_timings(&recorded)?;
    /// # Ok(()) }
    /// ```
    pub fn record_frame(
        &mut self,
        cmd: vk::CommandBuffer,
        target: Option<&HostTarget>,
    ) -> Result<RecordedFrame, RenderError> {
        if let Some(t) = target {
            crate::render::host::check_target(&self.gpu, self.target, self.options.samples, t)?;
            self.follow_extent(t.extent);
        }
        let plan = self.planner.plan(&self.needs, &self.view());
        self.record_plan(cmd, &plan, target)
    }

    /// Record the exitance that what changed since the last frame calls for, without shading,
    /// into `cmd` (recording, outside any rendering), for a host that shades itself: the passes
    /// `record_frame` would record up to the gather (shadow maps, sky light, splat, gather), and
    /// none after. No submission and no wait; `read_timings` and the lifetime rule are those
    /// of `record_frame`.
    ///
    /// `extent` is the size in pixels the host draws the view at (set with `SceneEdit::Camera`): the
    /// levels of detail follow it, as they follow a `HostTarget`'s extent. `readers` are the
    /// accesses the host will read the output with (`Access::VertexAttributeRead` for a vertex
    /// stream, `ComputeRead`, `FragmentRead`, `TransferRead`, `HostRead`): the call ends with
    /// the barrier from the gather's writes to them, and the next frame's writes wait for them.
    ///
    /// The output is `buffers().exitance`, and `buffers().environment_irradiance` for the sky
    /// light, one `vec4` per vertex of every object in scene order (docs/GPU.md, "The exitance
    /// as an output"). It equals what `record_frame` gathers for the same change and view.
    pub fn record_exitance(
        &mut self,
        cmd: vk::CommandBuffer,
        extent: vk::Extent2D,
        readers: &[Access],
    ) -> Result<RecordedFrame, RenderError> {
        if self.target == TargetDesc::Own {
            return Err(RenderError::ExitanceOnOwnTarget);
        }
        if extent.width == 0 || extent.height == 0 {
            return Err(RenderError::HostTargetEmpty { extent: [extent.width, extent.height] });
        }
        if let Some(&bad) = readers.iter().find(|a| a.writes() || **a == Access::Nothing) {
            return Err(RenderError::ExitanceReader(bad));
        }
        self.follow_extent(extent);
        let mut plan = self.planner.plan(&self.needs, &self.view());
        plan.passes.retain(|(p, _)| !matches!(p, Pass::Shade | Pass::Tonemap));
        // The host reads every vertex, seen or not.
        for o in plan.objects.iter_mut().filter(|o| o.gather) {
            o.receivers = ReceiverScope::Every { why: EveryReason::HostReadsExitance };
        }
        self.host_frames = true;
        let frame = self.record_checked(cmd, &plan, None);
        let uses: Vec<_> = [Resource::Exitance, Resource::EnvironmentIrradiance]
            .iter()
            .flat_map(|&r| readers.iter().map(move |&a| read(r, a)))
            .collect();
        self.hazards.get_mut().before(self.gpu.device(), cmd, &uses);
        Ok(frame)
    }

    /// The levels of detail follow `extent`, the host's: a new extent replans as a camera move
    /// does (as the own image's `resize`).
    fn follow_extent(&mut self, extent: vk::Extent2D) {
        if self.host_extent.is_some_and(|e| e != extent) {
            self.planner.mark(Change::Camera);
        }
        self.host_extent = Some(extent);
    }

    /// Record the passes of `plan` into `cmd` (as `record_frame` does, with a plan of the
    /// caller's), timed in the next slot of the timer ring.
    pub fn record_plan(
        &mut self,
        cmd: vk::CommandBuffer,
        plan: &Plan,
        target: Option<&HostTarget>,
    ) -> Result<RecordedFrame, RenderError> {
        match (self.target, target) {
            (TargetDesc::Own, Some(_)) => return Err(RenderError::UnexpectedHostTarget),
            (TargetDesc::Host { .. }, None) => {
                return Err(RenderError::MissingHostTarget);
            }
            (_, Some(t)) => crate::render::host::check_target(&self.gpu, self.target, self.options.samples, t)?,
            _ => {}
        }
        self.host_frames = true;
        Ok(self.record_checked(cmd, plan, target))
    }

    /// `record_plan` into a command buffer of the renderer's own, which its caller submits and
    /// waits for (`frame`, `frame_isolated`): not a host's frame to wait for at Drop.
    fn record_own(&mut self, cmd: vk::CommandBuffer, plan: &Plan) -> Result<RecordedFrame, RenderError> {
        if let TargetDesc::Host { .. } = self.target {
            return Err(RenderError::MissingHostTarget);
        }
        Ok(self.record_checked(cmd, plan, None))
    }

    /// `record_plan` after its checks: `target` suits this renderer, or `plan` does not shade.
    fn record_checked(&mut self, cmd: vk::CommandBuffer, plan: &Plan, target: Option<&HostTarget>) -> RecordedFrame {
        let plan = &self.planner.stamped(plan);
        let mark_slot = self.marks.slot(self.generation + 1);
        self.undo = Some(Undo {
            hazards: self.hazards.get_mut().clone(),
            planner: self.planner.clone(),
            needs: self.needs.clone(),
            uploads: self.gpu_scene.uploads(),
            slot_frame: self.slot_frames[mark_slot],
        });
        self.generation += 1;
        self.slot_frames[mark_slot] = self.generation;
        let slot = (!self.timers.is_empty()).then_some(mark_slot);
        for o in &plan.objects {
            self.gpu_scene.set_local_channels(o.object, o.local_mask());
        }
        let device = self.gpu.device();
        let uploads: Vec<_> =
            self.gpu_scene.pending_uploads().into_iter().map(|r| write(r, Access::TransferWrite)).collect();
        self.hazards.get_mut().before(device, cmd, &uploads);
        self.gpu_scene.record_uploads(device, cmd);
        // Taken out for the recording, which borrows `self` immutably.
        let mut timers = std::mem::take(&mut self.timers);
        let mut timer = slot.map(|s| &mut timers[s]);
        if let Some(t) = timer.as_deref_mut() {
            t.reset(cmd);
        }
        let recorded = self.record(cmd, plan, timer, target);
        self.marks.record(self.gpu.device(), cmd, self.generation);
        self.timers = timers;
        let baked = self.planner.baked_levels();
        // Only the vertex gather works at a level's vertices; the others reach every vertex.
        self.planner.recorded(
            plan,
            matches!(
                self.scene.scene.file.render.gather,
                GatherMode::Vertex | GatherMode::Hierarchical | GatherMode::Texture
            ),
        );
        // A frame that recomputed the sky light withdraws the levels baked from it.
        if self.planner.baked_levels() != baked {
            self.needs = Self::needs_of(&self.scene, self.target, &self.planner);
        }
        RecordedFrame { passes: recorded, slot, generation: self.generation, renderer: self.id() }
    }

    /// GPU milliseconds of each pass of `frame`, from its timestamps: call after the host's
    /// fence for the submission holding it, and before `frames_in_flight` more frames were
    /// recorded (`RendererOptions`; they reuse its slot). Never blocks: until the frame has run
    /// (its mark, written after everything it recorded, is there: `marks`) it answers
    /// `FrameNotDone`, never an earlier frame's timestamps; after its slot was reused,
    /// `TimingsOverwritten`. Empty on a queue without timestamps.
    pub fn read_timings(&self, frame: &RecordedFrame) -> Result<FrameTimings, RenderError> {
        if frame.renderer != self.id() {
            return Err(RenderError::ForeignFrame);
        }
        let slot = self.marks.slot(frame.generation);
        if self.slot_frames[slot] != frame.generation {
            return Err(RenderError::TimingsOverwritten {
                frame: frame.generation,
                by: self.slot_frames[slot],
                in_flight: self.slot_frames.len(),
            });
        }
        if !self.marks.ran(frame.generation)? {
            return Err(RenderError::FrameNotDone(frame.generation));
        }
        let marks = match frame.slot {
            Some(slot) => self.timers[slot].results_if_done()?.ok_or(RenderError::FrameNotDone(frame.generation))?,
            None => Vec::new(),
        };
        // One mark per recorded pass, in order (`record`).
        Ok(FrameTimings { passes: frame.passes.iter().zip(marks).map(|(&p, (_, ms))| (p, ms)).collect() })
    }

    /// Forget `frame`, the last frame recorded, whose command buffer will never be submitted (a
    /// swapchain went out of date before the host submitted it, say): the renderer goes back
    /// to the state before it was recorded (what the planner thinks is current, the barrier
    /// tracker's states, the uploads it took, its number and timer slot), so the next frame
    /// redoes what it did and takes its number. An earlier
    /// frame cannot be discarded (`DiscardNotLast`): frames recorded after it counted on it.
    /// Submitting a discarded frame's command buffer is the host's error.
    pub fn discard(&mut self, frame: RecordedFrame) -> Result<(), RenderError> {
        if frame.renderer != self.id() {
            return Err(RenderError::ForeignFrame);
        }
        let undo = match self.undo.take() {
            Some(undo) if frame.generation == self.generation => undo,
            other => {
                self.undo = other;
                return Err(RenderError::DiscardNotLast { frame: frame.generation, last: self.generation });
            }
        };
        *self.hazards.get_mut() = undo.hazards;
        self.planner = undo.planner;
        self.needs = undo.needs;
        self.gpu_scene.restore_uploads(undo.uploads);
        // Its slot and number go back too: the frame before it in that slot stays readable.
        self.slot_frames[self.marks.slot(frame.generation)] = undo.slot_frame;
        self.generation -= 1;
        Ok(())
    }

    /// Record the passes of `plan` into `cmd`, each after the barrier its declaration needs and
    /// between the timer's marks when given; returns the passes recorded.
    fn record(
        &self,
        cmd: vk::CommandBuffer,
        plan: &Plan,
        mut timer: Option<&mut GpuTimer>,
        target: Option<&HostTarget>,
    ) -> Vec<Pass> {
        let layers = plan.shadow_light.map(|source| self.scene.shadow_layers_of(source));
        if let Some(t) = target {
            let mut hazards = self.hazards.borrow_mut();
            if t.sync == HostSync::Attachments {
                // The host's contract: it drew into its attachments before this frame.
                hazards.external(Resource::HostColor, Access::ColorAttachmentWrite);
                hazards.external(Resource::HostDepth, Access::DepthAttachmentReadWrite);
            } else {
                // The shading pass records the barriers from and to the declared states itself.
                hazards.forget(Resource::HostColor);
                hazards.forget(Resource::HostDepth);
            }
        }
        let frame = self.inputs(plan, layers.as_deref(), target);
        let mut recorded = Vec::new();
        for &(pass, _) in &plan.passes {
            let Some(recorder) = self.passes.get(pass) else { continue };
            recorded.push(pass);
            if let Some(t) = timer.as_deref_mut() {
                t.begin(cmd, pass.name());
            }
            frame.before(cmd, &recorder.uses(&frame));
            recorder.record(cmd, &frame);
            if let Some(t) = timer.as_deref_mut() {
                t.end(cmd);
            }
        }
        // What the host reads back after the fence: directly, or by a copy of its own.
        let host: Vec<_> =
            HOST_READ.iter().flat_map(|&r| [read(r, Access::HostRead), read(r, Access::TransferRead)]).collect();
        frame.before(cmd, &host);
        recorded
    }

    /// What the passes of `plan` record from: this renderer's data, camera and hazards, the
    /// shadow-map layers to redraw and the host's target.
    pub(super) fn inputs<'a>(
        &'a self,
        plan: &'a Plan,
        shadow_layers: Option<&'a [u32]>,
        target: Option<&'a HostTarget>,
    ) -> FrameInputs<'a> {
        FrameInputs {
            gpu: &self.gpu,
            scene: &self.gpu_scene,
            targets: &self.targets,
            plan,
            shadow_layers,
            view_proj: self.camera.projection * self.camera.view,
            eye: self.camera.eye,
            background: self.clear_color(),
            exposure: self.scene.scene.file.render.exposure,
            target,
            hazards: &self.hazards,
        }
    }

    /// Render one frame: record the passes of `plan` in one submission of its own, wait, and
    /// return their GPU times from timestamp queries (none on a queue that cannot write
    /// timestamps). A thin wrapper over `record_plan`.
    pub fn frame(&mut self, plan: &Plan) -> Result<FrameTimings, RenderError> {
        let gpu = self.gpu.clone();
        let recorded = gpu.one_shot("frame", |cmd| self.record_own(cmd, plan))??;
        let timings = self.read_timings(&recorded)?;
        self.bake_after(plan)?;
        Ok(timings)
    }

    /// Render one frame with every pass in a submission of its own, and return each pass's
    /// time from submission to fence (wall clock, milliseconds): the check on the timestamps
    /// of `frame` (on lavapipe they once disagreed for compute passes; `GpuTimer::begin` says
    /// why and how that was cured).
    pub fn frame_isolated(&mut self, plan: &Plan) -> Result<FrameTimings, RenderError> {
        let gpu = self.gpu.clone();
        let mut passes = Vec::new();
        for (pass, why) in &plan.passes {
            let alone = Plan { passes: vec![(*pass, why.clone())], skipped: Vec::new(), ..plan.clone() };
            let start = std::time::Instant::now();
            gpu.one_shot(pass.name(), |cmd| self.record_own(cmd, &alone))??;
            passes.push((*pass, start.elapsed().as_secs_f64() * 1e3));
        }
        self.bake_after(plan)?;
        Ok(FrameTimings { passes })
    }

    /// After a frame of `plan` has finished: bake levels from the sky light it recomputed.
    fn bake_after(&mut self, plan: &Plan) -> Result<(), RenderError> {
        if plan.runs(Pass::VertexLight) {
            self.bake_static_levels()?;
        }
        Ok(())
    }
}

/// The renderer's state before a frame was recorded, put back by `Renderer::discard`.
pub(super) struct Undo {
    hazards: crate::gpu::Hazards<Resource>,
    planner: crate::render::plan::Planner,
    needs: crate::scene::needs::SceneNeeds,
    uploads: crate::render::gpu_scene::PendingUploads,
    /// The generation its slot held before it.
    slot_frame: u64,
}
