//! `Renderer`: the passes a prepared scene needs, built over its GPU data (`GpuScene`), and the
//! frame loop that records the passes a plan asks for, each timed with the `GpuTimer`. Outputs
//! stay on the GPU between frames, so a frame that skips a pass reuses its last result.

use super::beam_gather::{BeamGatherPass, GatherThenBeams};
use super::edit::SceneEdit;
use super::gather::GatherPass;
use super::gather_pixel::GatherPixelPass;
use super::gather_sparse::GatherSparsePass;
use super::gather_texture::GatherTexturePass;
use super::gather_tree::GatherTreePass;
use super::gpu_scene::GpuScene;
use super::graph::{HOST_READ, Resource, Resources, read, write};
use super::host::HostSync;
use super::local_exitance::LocalExitancePass;
use super::pass::{FrameInputs, RenderPass};
use super::plan::{self, Change, Pass, Plan, Planner};
use super::shade::{DepthConvention, DepthTest, HostTarget, ShadeOptions, ShadePass, TargetDesc};
use super::shadow::ShadowPass;
use super::splat::SplatPass;
use super::targets::{CameraTargets, FrameTargets};
use super::tonemap::TonemapPass;
use super::vertex_light::VertexLightPass;
use crate::gpu::{Access, Gpu, GpuError, GpuTimer, Hazards, ShaderInterface};
use crate::scene::build::PreparedScene;
use crate::scene::needs::SceneNeeds;
use crate::scene::{GatherMode, Light};
use ash::vk;
use glam::{Mat4, Vec3};
use std::cell::RefCell;
use std::sync::Arc;

/// Why a renderer could not be made.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scene asks for more than the device has.
    #[error("{setting} = {value} does not fit this device: its {limit_name} is {limit}")]
    DoesNotFit {
        /// The scene setting that is too large, or the quantity it leads to (e.g. the bytes of the
        /// HDR image at camera.resolution).
        setting: String,
        /// How large it is.
        value: u64,
        /// The device limit it exceeds (a VkPhysicalDeviceLimits name, or the largest device-local
        /// heap).
        limit_name: &'static str,
        /// That limit on this device.
        limit: u64,
    },
    /// A host target's format this device cannot render to as that attachment.
    #[error("the host's {which} format {format:?} is not usable as a {which} attachment on this device")]
    Format {
        /// "colour" or "depth".
        which: &'static str,
        /// The format given.
        format: vk::Format,
    },
    /// The pixel gather was asked of a renderer drawing into a host's target.
    #[error("the pixel gather needs the renderer's own HDR image: use vertex or sparse")]
    PixelGatherOnHostTarget,
    /// A material whose `model` takes single scattering between points, in a scene gathered at
    /// pixels: that model is gathered at the vertices.
    #[error(
        "object {0}: material.model takes single scattering between points, which is gathered at the vertices: \
         use render.gather \"vertex\", \"hierarchical\", \"sparse\" or \"texture\", or material.model = \"dipole\""
    )]
    SingleScatteringOnPixelGather(usize),
    /// `set_material` of an object whose `model` takes single scattering between points: its
    /// kernel tables are built with the scene's GPU data.
    #[error(
        "set_material: object {0}'s material.model takes single scattering between points, whose tables are built \
         once with the scene; load the scene with the new material instead"
    )]
    MaterialWithBeamTables(usize),
    /// `resize` of a renderer drawing into a host's target.
    #[error("resize: a host target's size comes with each frame's HostTarget")]
    ResizeHostTarget,
    /// `record_exitance` of a renderer drawing into its own images: its levels of detail follow
    /// its own image, and `frame` with `exitance` reads its exitance.
    #[error("record_exitance is for a host-target renderer (TargetDesc::Host); this one draws into its own images")]
    ExitanceOnOwnTarget,
    /// `record_exitance` told that the host will write the exitance, or access it not at all.
    #[error("record_exitance: {0:?} is not a read; the host may only read the exitance it is handed")]
    ExitanceReader(Access),
    /// A `HostTarget` given to a renderer that draws into its own images.
    #[error("this renderer draws into its own images: record it without a HostTarget")]
    UnexpectedHostTarget,
    /// A host-target renderer recorded without a `HostTarget`.
    #[error("a host-target renderer needs a HostTarget for every frame")]
    MissingHostTarget,
    /// A `HostTarget` whose render area has no pixel.
    #[error("HostTarget extent {}x{}: the render area needs at least one pixel each way", extent[0], extent[1])]
    HostTargetEmpty {
        /// The extent given.
        extent: [u32; 2],
    },
    /// A `HostTarget` whose render area, from its offset, reaches past one of its images, or
    /// past what the device allows.
    #[error(
        "HostTarget extent {}x{} at offset ({}, {}) is larger than {what} ({}x{})",
        extent[0], extent[1], offset[0], offset[1], limit[0], limit[1]
    )]
    HostTargetTooLarge {
        /// The render area's size.
        extent: [u32; 2],
        /// The render area's offset.
        offset: [i32; 2],
        /// What it exceeds: "the colour image", "the depth image" or the device limit.
        what: &'static str,
        /// Its size.
        limit: [u32; 2],
    },
    /// A `HostTarget` whose declared image states (`HostSync::Declared`) cannot be right.
    #[error("the HostTarget's {which} image: {reason}")]
    HostTargetState {
        /// "colour" or "depth".
        which: &'static str,
        /// What is wrong.
        reason: &'static str,
    },
    /// A `HostTarget` whose render area begins left of or above its images.
    #[error("HostTarget offset ({}, {}): a render area's offset must not be negative", offset[0], offset[1])]
    HostTargetOffset {
        /// The offset given.
        offset: [i32; 2],
    },
    /// `RendererOptions::frames_in_flight` of 0, or past `Renderer::MAX_FRAMES_IN_FLIGHT`.
    #[error("frames_in_flight = {given}: a renderer takes 1 to {max} frames in flight")]
    FramesInFlight {
        /// The count given.
        given: usize,
        /// `Renderer::MAX_FRAMES_IN_FLIGHT`.
        max: usize,
    },
    /// `RendererOptions::samples` this renderer cannot draw at.
    #[error("samples {given:?}: {reason} (this device supports {supported:?})")]
    Samples {
        /// The count given.
        given: vk::SampleCountFlags,
        /// The counts the device supports for colour and depth attachments both.
        supported: vk::SampleCountFlags,
        /// Why it is refused.
        reason: &'static str,
    },
    /// A `HostTarget` attachment of another sample count than the renderer draws at.
    #[error("the HostTarget's {which} image has {given:?} samples, but the renderer draws at {expected:?}")]
    HostTargetSamples {
        /// "colour", "depth" or "resolve".
        which: &'static str,
        /// The attachment's samples.
        given: vk::SampleCountFlags,
        /// What it must have.
        expected: vk::SampleCountFlags,
    },
    /// A `DepthTest` whose comparison does not pass nearer fragments under its convention.
    #[error(
        "depth compare {compare:?} under {convention:?} depth would hide what is nearer: use {expected} (or EQUAL, \
         ALWAYS)"
    )]
    DepthCompare {
        /// The comparison given.
        compare: vk::CompareOp,
        /// The convention given.
        convention: DepthConvention,
        /// The comparisons that suit it.
        expected: &'static str,
    },
    /// A `HostTarget` attachment of another format than the `TargetDesc` the pipelines were
    /// made for.
    #[error(
        "the HostTarget's {which} image is {given:?}, but the renderer was made for {declared:?} (TargetDesc::Host)"
    )]
    HostTargetFormat {
        /// "colour" or "depth".
        which: &'static str,
        /// The attachment's format.
        given: vk::Format,
        /// The `TargetDesc::Host` format.
        declared: vk::Format,
    },
    /// `read_timings` of a frame whose submission has not finished (or was not made): reading
    /// would block until it does.
    #[error("frame {0}'s timings are not written yet: read them after the fence of its submission")]
    FrameNotDone(u64),
    /// `read_timings` of a frame whose timestamp queries a later frame has reused.
    #[error(
        "frame {frame}'s timings were overwritten by frame {by}: read them before {in_flight} more frames are \
         recorded (RendererOptions::frames_in_flight)"
    )]
    TimingsOverwritten {
        /// The frame asked for (`RecordedFrame::generation`).
        frame: u64,
        /// The later frame that reused its queries.
        by: u64,
        /// How many frames may be in flight.
        in_flight: usize,
    },
    /// `read_timings` of a frame another renderer recorded.
    #[error("this frame was recorded by another renderer")]
    ForeignFrame,
    /// `image` or `hdr_image` of a renderer drawing into a host's target.
    #[error("a host target has no image of the renderer's own: the host reads its own")]
    NoOwnImage,
    /// A scene object index past the scene's objects.
    #[error("object {object} does not exist: the scene has {objects} objects")]
    NoSuchObject {
        /// The index given.
        object: usize,
        /// How many objects the scene has.
        objects: usize,
    },
    /// A translucent-only call (`set_material`) on an opaque object.
    #[error("object {0} is opaque: it has no translucent material to replace")]
    OpaqueObject(usize),
    /// `set_material` with coefficients the dipole model refuses.
    #[error("object {object}: invalid material: {reason}")]
    InvalidMaterial {
        /// The object.
        object: usize,
        /// What is wrong with it.
        reason: String,
    },
    /// `set_exitance` with another number of values than the object has vertices.
    #[error("object {object} has {vertices} vertices, but {given} exitance values were given")]
    ExitanceCount {
        /// The object.
        object: usize,
        /// Its vertex count.
        vertices: usize,
        /// Values given.
        given: usize,
    },
    /// `exitance` after a gather that ran at a coarser level of detail than the whole mesh.
    #[error(
        "exitance at every vertex of object {0}: its last gather ran at a coarser level of detail \
         (render.level_of_detail = false, or --full-detail, keeps every vertex current)"
    )]
    ExitanceAtCoarserLevel(usize),
    /// A scene change could not be prepared (the message names the object and step).
    #[error("{0}")]
    Scene(String),
    /// `set_light` was given a light of another kind than scene light `index`, or an index past the
    /// scene's lights.
    #[error("light {0} cannot be replaced by a light of another kind")]
    LightKindChanged(usize),
    /// An error of the GPU core.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// Non-finite values one pass left on one object.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NonFinite {
    /// `Pass::Splat` (at the samples) or `Pass::Gather` (at the vertices).
    pub pass: Pass,
    /// Index of the object in the scene.
    pub object: usize,
    /// Samples (splat) or vertices (gather) with a NaN or infinite value.
    pub count: usize,
}

/// Per-pass GPU milliseconds of one frame, in recording order.
#[derive(Clone, Debug, Default)]
pub struct FrameTimings {
    /// (pass, GPU milliseconds) per recorded pass.
    pub passes: Vec<(Pass, f64)>,
}

impl FrameTimings {
    /// Sum over the passes, in milliseconds.
    pub fn total(&self) -> f64 {
        self.passes.iter().map(|(_, ms)| ms).sum()
    }
    /// Milliseconds of `pass`, if it was recorded.
    pub fn get(&self, pass: Pass) -> Option<f64> {
        self.passes.iter().find(|(p, _)| *p == pass).map(|(_, ms)| *ms)
    }
}

/// Where the camera is: world -> view, view -> clip (Vulkan: depth 0..1, y down), and its
/// position (for the specular lobe).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraView {
    /// World -> view.
    pub view: Mat4,
    /// View -> clip (Vulkan clip space: depth 0..1, y down).
    pub projection: Mat4,
    /// Camera position in world space.
    pub eye: Vec3,
}

impl CameraView {
    /// The scene file's camera, its near and far planes fitted around the scene.
    pub fn of_scene(scene: &PreparedScene) -> CameraView {
        let camera = &scene.scene.file.camera;
        CameraView {
            view: camera.view(),
            projection: camera.projection(scene.bounds.0, scene.bounds.1),
            eye: Vec3::from(camera.eye),
        }
    }

    /// This camera with its depth reversed (reversed-Z, `DepthConvention::Reversed`): clip
    /// depth `z` becomes `w - z`, so that the near plane is at 1 and the far plane at 0; what
    /// is drawn where is unchanged.
    pub fn reversed_depth(self) -> CameraView {
        let reverse = Mat4::from_cols(
            glam::Vec4::X,
            glam::Vec4::Y,
            glam::Vec4::new(0.0, 0.0, -1.0, 0.0),
            glam::Vec4::new(0.0, 0.0, 1.0, 1.0),
        );
        CameraView { projection: reverse * self.projection, ..self }
    }

    /// This camera turned by `degrees` about the vertical axis through `centre` (the world
    /// turning the other way in its view).
    pub fn orbited(self, centre: Vec3, degrees: f32) -> CameraView {
        let turn = Mat4::from_translation(centre)
            * Mat4::from_rotation_y(degrees.to_radians())
            * Mat4::from_translation(-centre);
        CameraView {
            view: self.view * turn.inverse(),
            projection: self.projection,
            eye: turn.transform_point3(self.eye),
        }
    }
}

/// A frame recorded into a command buffer: which passes, and where its timings will be.
#[derive(Clone, Debug)]
pub struct RecordedFrame {
    /// The passes recorded, in order (what the plan ran, counted as recorded).
    pub passes: Vec<Pass>,
    /// Slot of the timer ring that holds its timestamps.
    slot: Option<usize>,
    /// Its number among the frames its renderer recorded, from 1.
    generation: u64,
    /// The renderer that recorded it (`Renderer::id`).
    renderer: usize,
}

impl RecordedFrame {
    /// Its number among the frames its renderer recorded, from 1: `read_timings` refuses a
    /// frame whose timer slot a later generation reused.
    pub fn generation(&self) -> u64 {
        self.generation
    }
}

/// An object's exitance where its last gather computed it (`Renderer::exitance_at_level`).
#[derive(Clone, Debug, PartialEq)]
pub struct LevelExitance {
    /// The level of detail gathered at (0: the whole mesh).
    pub level: usize,
    /// That level's vertices, object-relative, ascending.
    pub vertices: Vec<u32>,
    /// Their RGB exitance, in the same order.
    pub values: Vec<[f32; 3]>,
}

/// What a host chooses of a renderer beyond its target (`Renderer::with_options`); `default()`
/// is what `Renderer::new` and `with_target` take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RendererOptions {
    /// Frames that may be in flight at once, each with its own timestamp queries: a frame's
    /// timings can be read until this many later frames are recorded (`read_timings`).
    /// 1 to `Renderer::MAX_FRAMES_IN_FLIGHT`; `Renderer::FRAMES_IN_FLIGHT` (3) by default.
    pub frames_in_flight: usize,
    /// The depth test shading makes against the target's depth, and what it clears depth to;
    /// standard depth (0 near, LESS_OR_EQUAL) by default. With reversed-Z, give the renderer
    /// reversed projections (`CameraView::reversed_depth`); its first camera is reversed so.
    pub depth: DepthTest,
    /// Samples per pixel of the host's colour and depth images (MSAA): shading rasterises at
    /// that rate and resolves into `HostTarget::resolve` when given. TYPE_1 by default; above it,
    /// a host target only, and a count the device supports for colour and depth attachments
    /// (`framebufferColorSampleCounts`, `framebufferDepthSampleCounts`).
    pub samples: vk::SampleCountFlags,
}

impl Default for RendererOptions {
    fn default() -> Self {
        RendererOptions {
            frames_in_flight: Renderer::FRAMES_IN_FLIGHT,
            depth: DepthTest::STANDARD,
            samples: vk::SampleCountFlags::TYPE_1,
        }
    }
}

impl RendererOptions {
    /// What the shading pass takes of them.
    fn shade(&self) -> ShadeOptions {
        ShadeOptions { depth: self.depth, samples: self.samples }
    }

    /// An error naming what the options get wrong for `target` on `gpu`.
    fn check(&self, gpu: &Gpu, target: TargetDesc) -> Result<(), RenderError> {
        let samples = self.samples;
        let limits = &gpu.properties().limits;
        let supported = limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts;
        let reason = if samples.as_raw().count_ones() != 1 {
            Some("a sample count is one of the SampleCountFlags bits")
        } else if !supported.contains(samples) {
            Some("the device does not support it for both colour and depth attachments")
        } else if samples != vk::SampleCountFlags::TYPE_1 && target == TargetDesc::Own {
            Some("the renderer's own images are single-sampled: multisampling is for a host target")
        } else {
            None
        };
        if let Some(reason) = reason {
            return Err(RenderError::Samples { given: samples, supported, reason });
        }
        let max = Renderer::MAX_FRAMES_IN_FLIGHT;
        if self.frames_in_flight == 0 || self.frames_in_flight > max {
            return Err(RenderError::FramesInFlight { given: self.frames_in_flight, max });
        }
        if !self.depth.is_consistent() {
            let expected = match self.depth.convention {
                DepthConvention::Standard => "LESS or LESS_OR_EQUAL",
                DepthConvention::Reversed => "GREATER or GREATER_OR_EQUAL",
            };
            let DepthTest { compare, convention } = self.depth;
            return Err(RenderError::DepthCompare { compare, convention, expected });
        }
        Ok(())
    }
}

/// Renders one prepared scene: its passes over its GPU data, recording the passes each frame
/// needs into a command buffer (the host's, or its own for `frame`).
///
/// **Lifetime.** Frames recorded with `record_frame` or `record_exitance` into a host's
/// command buffer use the renderer's pipelines, buffers and images until their submission
/// finishes. Dropping the renderer (and `set_transform`, `bake_static_levels`, `resize`, which
/// replace some of them) therefore first waits for the `Gpu`'s queue to go idle
/// (`vkQueueWaitIdle`) unless every frame it recorded was seen finished: by `read_timings`
/// succeeding on the last one (of at least one pass), or by `frame`. So no order of safe calls destroys what a frame in flight uses; a host that does
/// not want the wait reads the last frame's timings after its fence first. A host must submit
/// the command buffers it recorded into before dropping the renderer, or never (a buffer
/// recorded against a dropped renderer is invalid, as after any destroyed object).
pub struct Renderer {
    gpu: Arc<Gpu>,
    scene: PreparedScene,
    needs: SceneNeeds,
    // Passes drop before the data their descriptor sets point into.
    shadow: ShadowPass,
    vertex_light: VertexLightPass,
    splat: SplatPass,
    /// Vertex, sparse or pixel gather (`render.gather`).
    gather: Box<dyn RenderPass>,
    shade: ShadePass,
    /// Own target only: the host tone-maps its own.
    tonemap: Option<TonemapPass>,
    /// One timer per frame that may be in flight (empty without timestamps).
    timers: Vec<GpuTimer>,
    /// The generation of the frame each timer holds.
    slot_frames: Vec<u64>,
    /// Frames recorded so far (the last one's generation).
    generation: u64,
    /// The last generation seen finished (`read_timings`, `frame`); what Drop need not wait for.
    finished: std::cell::Cell<u64>,
    /// The extent of the last `HostTarget`: the planner's levels of detail follow it.
    host_extent: Option<vk::Extent2D>,
    /// Tells its `RecordedFrame`s from another renderer's (`NEXT_RENDERER`).
    id: usize,
    /// The shadow maps and camera images the passes' descriptor sets point into.
    targets: FrameTargets,
    buffers: GpuScene,
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
    pub const FRAMES_IN_FLIGHT: usize = 3;
    /// The most frames in flight a renderer takes: each is a query pool, and a count past
    /// what any swapchain holds is more likely a mistake than a wish.
    pub const MAX_FRAMES_IN_FLIGHT: usize = 16;

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
        let buffers = GpuScene::new(gpu, &scene)?;
        let settings = &scene.scene.file.render;
        let camera = (target == TargetDesc::Own).then_some((scene.scene.file.camera.resolution, needs.pixel_gather));
        let targets = FrameTargets::new(gpu, settings.shadow_map_size, scene.shadow_layers, camera)?;
        let resources = Resources { scene: &buffers, targets: &targets };
        let shade = ShadePass::new(gpu, target, &resources, needs.pixel_gather, options.shade())?;
        let gather = Self::gather_pass(gpu, &resources, settings, needs.pixel_gather)?;
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
            vertex_light: VertexLightPass::new(gpu, &resources)?,
            splat: SplatPass::new(gpu, &resources, scene.scene.file.render.splat_visibility)?,
            tonemap: targets.hdr().is_some().then(|| TonemapPass::new(gpu, &resources)).transpose()?,
            shadow: ShadowPass::new(gpu, scene.shadow_layers)?,
            gather,
            shade,
            slot_frames: vec![0; timers.len()],
            timers,
            generation: 0,
            finished: std::cell::Cell::new(0),
            host_extent: None,
            id: NEXT_RENDERER.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            targets,
            buffers,
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

    /// The gather `render.gather` names (the pixel gather when the scene's needs say so).
    fn gather_pass(
        gpu: &Arc<Gpu>,
        resources: &Resources,
        settings: &crate::scene::RenderSettings,
        pixel: bool,
    ) -> Result<Box<dyn RenderPass>, RenderError> {
        let gather: Box<dyn RenderPass> = match settings.gather {
            _ if pixel => return Ok(Box::new(GatherPixelPass::new(gpu, resources)?)),
            GatherMode::Sparse => Box::new(GatherSparsePass::new(gpu, resources)?),
            GatherMode::Hierarchical => Box::new(GatherTreePass::new(gpu, resources)?),
            GatherMode::Texture => Box::new(GatherTexturePass::new(gpu, resources, settings.texture_samples)?),
            _ => Box::new(GatherPass::new(gpu, resources)?),
        };
        // Channels of single scattering between points overwrite the dipole's after it.
        Ok(match BeamGatherPass::new(gpu, resources)? {
            Some(beams) => Box::new(GatherThenBeams { gather, beams }),
            None => gather,
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
    pub fn buffers(&self) -> &GpuScene {
        &self.buffers
    }

    /// The scene's data on the GPU, to write (a test feeding the gather its own input) with no
    /// frame in flight: the next frame's readers of any of it wait for those writes.
    pub fn buffers_mut(&mut self) -> &mut GpuScene {
        let mut hazards = self.hazards.borrow_mut();
        for r in super::graph::SCENE_BUFFERS {
            hazards.written_outside(r);
        }
        drop(hazards);
        &mut self.buffers
    }

    /// The passes a frame with this change would run, seen from the current camera, and what
    /// each object gets.
    pub fn plan(&self, change: Change) -> Plan {
        self.planner.plan_for(&self.needs, &self.view(), change)
    }

    /// Bake the levels of detail of opaque objects under an environment light from their
    /// per-vertex sky light as the last vertex-light pass left it (read back): the vertices
    /// where it varies by more than `SKY_LOCK_SHARE` of the object's brightest are kept, the
    /// others simplified away like any mesh's (`mesh::Mesh::levels_of_detail_locked`). So a
    /// flat floor keeps its density only around the soft shadows on it. `frame` calls this
    /// after each frame that ran the vertex-light pass; a host recording its own frames calls
    /// it after the fence of such a frame, with no frame in flight (the index buffer is
    /// replaced). From the frame that recomputes the sky light until then, those objects are
    /// drawn whole (the planner withdraws their baked levels, `plan::BakedLevels`). Returns
    /// whether anything was baked.
    pub fn bake_static_levels(&mut self) -> Result<bool, RenderError> {
        if !self.scene.scene.file.render.level_of_detail || self.needs.environment.is_none() {
            return Ok(false);
        }
        self.wait_for_recorded()?;
        let sky: Vec<[f32; 4]> = self.buffers.environment_irradiance.read()?;
        let mut baked = false;
        let mut first = 0;
        for o in &mut self.scene.objects {
            let count = o.mesh.positions().len();
            if matches!(o.material, crate::scene::build::ResolvedMaterial::Opaque { .. }) {
                let values: Vec<[f32; 3]> = sky[first..first + count].iter().map(|e| [e[0], e[1], e[2]]).collect();
                let locked = o.mesh.locks_where_varying(&values, SKY_LOCK_SHARE);
                o.levels = o.mesh.levels_of_detail_locked(&locked);
                baked = true;
            }
            first += count;
        }
        if baked {
            self.buffers.set_levels(&self.gpu, &self.scene)?;
            self.planner.levels_baked();
            self.needs = Self::needs_of(&self.scene, self.target, &self.planner);
        }
        Ok(baked)
    }

    /// After a frame of `plan` has finished: bake levels from the sky light it recomputed.
    fn bake_after(&mut self, plan: &Plan) -> Result<(), RenderError> {
        if plan.runs(Pass::VertexLight) {
            self.bake_static_levels()?;
        }
        Ok(())
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

    /// Apply one edit of the scene (`SceneEdit`), re-preparing only what it reaches; the next
    /// frame's plan redoes what it invalidates. `set_camera`, `resize`, `set_light`,
    /// `set_material` and `set_transform` are its cases.
    pub fn edit(&mut self, edit: SceneEdit) -> Result<(), RenderError> {
        match edit {
            SceneEdit::Camera(camera) => {
                self.set_camera(camera);
                Ok(())
            }
            SceneEdit::Resize { width, height } => self.resize(width, height),
            SceneEdit::Light { index, light } => self.set_light(index, light),
            SceneEdit::Material { object, material } => self.set_material(object, material),
            SceneEdit::Transform { object, transform } => self.set_transform(object, transform),
        }
    }

    /// Move the camera: the next frame re-shades (and, in pixel mode, gathers again); exitance
    /// at the vertices does not depend on the view.
    pub fn set_camera(&mut self, camera: CameraView) {
        self.camera = camera;
        self.planner.mark(Change::Camera);
    }

    /// Change the own target's size (the CLI's image): its images are made anew. The camera's
    /// projection is the caller's (`set_camera`), for the new aspect ratio. A host target takes
    /// its extent from each frame's `HostTarget` instead.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), RenderError> {
        if self.target != TargetDesc::Own {
            return Err(RenderError::ResizeHostTarget);
        }
        self.scene.scene.file.camera.resolution = [width, height];
        check_fits(&self.gpu, &self.scene)?;
        self.wait_for_recorded()?;
        let gpu = self.gpu.clone();
        // The old images' last frame must be done before they go (the caller's contract).
        self.targets.camera = Some(CameraTargets::new(&gpu, [width, height], self.needs.pixel_gather)?);
        let resources = Resources { scene: &self.buffers, targets: &self.targets };
        if self.needs.pixel_gather {
            self.gather = Box::new(GatherPixelPass::new(&gpu, &resources)?);
        }
        self.tonemap = Some(TonemapPass::new(&gpu, &resources)?);
        self.targets.track_camera(self.hazards.get_mut());
        self.planner.mark(Change::Camera);
        Ok(())
    }

    fn pass(&self, pass: Pass) -> Option<&dyn RenderPass> {
        Some(match pass {
            Pass::Shadow => &self.shadow,
            Pass::VertexLight => &self.vertex_light,
            Pass::Splat => &self.splat,
            Pass::Gather => self.gather.as_ref(),
            Pass::Shade => &self.shade,
            Pass::Tonemap => self.tonemap.as_ref()?,
        })
    }

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
            super::host::check_target(&self.gpu, self.target, self.options.samples, t)?;
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
    /// `extent` is the size in pixels the host draws the view at (set with `set_camera`): the
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
            (_, Some(t)) => super::host::check_target(&self.gpu, self.target, self.options.samples, t)?,
            _ => {}
        }
        Ok(self.record_checked(cmd, plan, target))
    }

    /// `record_plan` after its checks: `target` suits this renderer, or `plan` does not shade.
    fn record_checked(&mut self, cmd: vk::CommandBuffer, plan: &Plan, target: Option<&HostTarget>) -> RecordedFrame {
        self.generation += 1;
        let slot = (!self.timers.is_empty()).then(|| {
            let slot = (self.generation - 1) as usize % self.timers.len();
            self.slot_frames[slot] = self.generation;
            slot
        });
        for o in &plan.objects {
            self.buffers.set_local_channels(o.object, o.local_mask());
        }
        let device = self.gpu.device();
        let uploads: Vec<_> =
            self.buffers.pending_uploads().into_iter().map(|r| write(r, Access::TransferWrite)).collect();
        self.hazards.get_mut().before(device, cmd, &uploads);
        self.buffers.record_uploads(device, cmd);
        // Taken out for the recording, which borrows `self` immutably.
        let mut timers = std::mem::take(&mut self.timers);
        let mut timer = slot.map(|s| &mut timers[s]);
        if let Some(t) = timer.as_deref_mut() {
            t.reset(cmd);
        }
        let recorded = self.record(cmd, plan, timer, target);
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

    /// Identifies this renderer's frames: a number no other renderer of this process has.
    fn id(&self) -> usize {
        self.id
    }

    /// GPU milliseconds of each pass of `frame`, from its timestamps: call after the host's
    /// fence for the submission holding it, and before `frames_in_flight` more frames were
    /// recorded (`RendererOptions`; they reuse its queries). Never blocks: before the submission
    /// has finished it answers `FrameNotDone`, after its queries were reused
    /// `TimingsOverwritten`. Empty on a queue without timestamps, and for a frame of no pass
    /// (then nothing tells whether the frame finished). Before the fence, `FrameNotDone` is
    /// certain only for a slot's first frame: until the GPU begins a later one, the slot's
    /// queries still hold the results of the frame `frames_in_flight` before it (docs/GPU.md,
    /// "Timestamps").
    pub fn read_timings(&self, frame: &RecordedFrame) -> Result<FrameTimings, RenderError> {
        if frame.renderer != self.id() {
            return Err(RenderError::ForeignFrame);
        }
        let marks = match frame.slot {
            Some(slot) if self.slot_frames[slot] != frame.generation => {
                return Err(RenderError::TimingsOverwritten {
                    frame: frame.generation,
                    by: self.slot_frames[slot],
                    in_flight: self.timers.len(),
                });
            }
            Some(slot) => self.timers[slot].results_if_done()?.ok_or(RenderError::FrameNotDone(frame.generation))?,
            None => Vec::new(),
        };
        // A frame of no pass wrote no query, so its answer says nothing of its submission.
        if frame.slot.is_some() && !frame.passes.is_empty() {
            // Frames finish in the order they were recorded (the host's contract).
            self.finished.set(self.finished.get().max(frame.generation));
        }
        // One mark per recorded pass, in order (`record`).
        Ok(FrameTimings { passes: frame.passes.iter().zip(marks).map(|(&p, (_, ms))| (p, ms)).collect() })
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
            let Some(recorder) = self.pass(pass) else { continue };
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
    fn inputs<'a>(
        &'a self,
        plan: &'a Plan,
        shadow_layers: Option<&'a [u32]>,
        target: Option<&'a HostTarget>,
    ) -> FrameInputs<'a> {
        FrameInputs {
            gpu: &self.gpu,
            scene: &self.buffers,
            targets: &self.targets,
            plan,
            shadow_layers,
            view_proj: self.camera.projection * self.camera.view,
            eye: self.camera.eye,
            background: self.background,
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
        let recorded = gpu.one_shot("frame", |cmd| self.record_plan(cmd, plan, None))??;
        self.finished.set(recorded.generation);
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
            let recorded = gpu.one_shot(pass.name(), |cmd| self.record_plan(cmd, &alone, None))??;
            self.finished.set(recorded.generation);
            passes.push((*pass, start.elapsed().as_secs_f64() * 1e3));
        }
        self.bake_after(plan)?;
        Ok(FrameTimings { passes })
    }

    /// The last tone-mapped image (RGBA8, rows top to bottom) and how many of its HDR pixels
    /// were non-finite (they are drawn black).
    pub fn image(&self) -> Result<(Vec<u8>, u32), RenderError> {
        let tonemap = self.tonemap.as_ref().ok_or(RenderError::NoOwnImage)?;
        Ok(tonemap.read()?)
    }

    /// The last linear HDR image, RGBA f32, rows top to bottom.
    pub fn hdr_image(&self) -> Result<Vec<f32>, RenderError> {
        let hdr = self.targets.hdr().ok_or(RenderError::NoOwnImage)?;
        let mut hazards = self.hazards.borrow_mut();
        let bytes = hdr.read(hazards.last_access(Resource::Hdr))?;
        // The copy waited for the fence and left the image in TRANSFER_SRC.
        hazards.image(Resource::Hdr, hdr.raw(), vk::ImageAspectFlags::COLOR, Access::TransferRead);
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    }

    /// Radiant exitance (RGB, W/m^2 for the scene's light units) at every vertex of object
    /// `object`, from the last vertex gather (zero in pixel-gather mode).
    pub fn exitance(&self, object: usize) -> Result<Vec<[f32; 3]>, RenderError> {
        self.check_object(object)?;
        if self.planner.gathered_coarser(object) {
            return Err(RenderError::ExitanceAtCoarserLevel(object));
        }
        self.exitance_all(object)
    }

    /// Object `object`'s exitance as shading draws it, at every vertex: the gathered channels as
    /// [`Renderer::exitance`] reads them, and the channels the last recorded frame computed
    /// locally as `M = R_d,total E_t` at the vertex, with that frame's shadow maps and filter
    /// (`local_exitance` pass, recorded in a submission of its own and waited for). Call after a
    /// frame, with none in flight.
    pub fn exitance_drawn(&self, object: usize) -> Result<Vec<[f32; 3]>, RenderError> {
        let mut exitance = self.exitance(object)?;
        let mask = self.buffers.local_channels(object);
        if mask == 0 {
            return Ok(exitance);
        }
        let resources = Resources { scene: &self.buffers, targets: &self.targets };
        let pass = LocalExitancePass::new(&self.gpu, &resources, object)?;
        let plan = self.planner.plan_for(&self.needs, &self.view(), Change::Camera);
        self.gpu.one_shot("local exitance", |cmd| {
            let frame = self.inputs(&plan, None, None);
            frame.before(cmd, &pass.uses(&frame));
            pass.record(cmd, &frame);
            let r = Resource::LocalExitance;
            frame.before(cmd, &[read(r, Access::HostRead), read(r, Access::TransferRead)]);
        })?;
        let local: Vec<[f32; 4]> = self.buffers.local_exitance.read()?;
        let first = self.buffers.object_range(object).first_vertex as usize;
        for (e, l) in exitance.iter_mut().zip(&local[first..]) {
            for c in (0..3).filter(|c| mask & (1 << c) != 0) {
                e[c] = l[c];
            }
        }
        Ok(exitance)
    }

    /// Object `object`'s exitance where the last gather computed it: the level of detail it
    /// gathered at, that level's vertices (object-relative, ascending) and their RGB exitance.
    /// Unlike [`Renderer::exitance`], it answers after a gather at a coarser level too.
    pub fn exitance_at_level(&self, object: usize) -> Result<LevelExitance, RenderError> {
        self.check_object(object)?;
        let level = self.planner.gathered_level(object).unwrap_or(0);
        let all = self.exitance_all(object)?;
        let vertices = match self.scene.objects[object].levels.get(level) {
            Some(l) if level > 0 => l.vertices.clone(),
            _ => (0..all.len() as u32).collect(),
        };
        let values = vertices.iter().map(|&v| all[v as usize]).collect();
        Ok(LevelExitance { level, vertices, values })
    }

    /// Object `object`'s exitance buffer as it stands, every vertex.
    fn exitance_all(&self, object: usize) -> Result<Vec<[f32; 3]>, RenderError> {
        let all: Vec<[f32; 4]> = self.buffers.exitance.read()?;
        let first = self.buffers.object_range(object).first_vertex as usize;
        let count = self.scene.objects[object].mesh.positions().len();
        Ok(all[first..first + count].iter().map(|e| [e[0], e[1], e[2]]).collect())
    }

    /// Replace object `object`'s per-vertex exitance (RGB per vertex, its vertex order) before
    /// a frame that shades without gathering (`Change::Camera` in vertex mode): how the study
    /// draws the image of the exact exitance. The next gather overwrites it. Call with no
    /// frame in flight.
    pub fn set_exitance(&mut self, object: usize, exitance: &[[f32; 3]]) -> Result<(), RenderError> {
        self.check_object(object)?;
        let vertices = self.scene.objects[object].mesh.positions().len();
        if vertices != exitance.len() {
            return Err(RenderError::ExitanceCount { object, vertices, given: exitance.len() });
        }
        let first = u64::from(self.buffers.object_range(object).first_vertex);
        let values: Vec<[f32; 4]> = exitance.iter().map(|e| [e[0], e[1], e[2], 1.0]).collect();
        self.buffers.exitance.write(first * 16, &values)?;
        self.hazards.get_mut().written_outside(Resource::Exitance);
        self.planner.exitance_written(object);
        Ok(())
    }

    /// Splat output of every sample, in scene order: (irradiance RGB, area).
    pub fn splat_irradiance(&self) -> Result<Vec<([f32; 3], f32)>, RenderError> {
        // A scene without samples still has a buffer, of 16 bytes: less than one record.
        if self.scene.sample_count() == 0 {
            return Ok(Vec::new());
        }
        let all: Vec<super::records::SplatRecord> = self.buffers.splat.read()?;
        Ok(all
            .iter()
            .map(|s| ([s.irradiance_area[0], s.irradiance_area[1], s.irradiance_area[2]], s.irradiance_area[3]))
            .collect())
    }

    /// Replace scene light `index` by `light` of the same kind (moved, re-aimed or re-coloured),
    /// and upload the lights' records and shadow matrices. Render the next frame with
    /// `Change::Light(index)`.
    pub fn set_light(&mut self, index: usize, light: Light) -> Result<(), RenderError> {
        let lights = &mut self.scene.scene.file.lights;
        match lights.get_mut(index) {
            Some(old) if std::mem::discriminant(old) == std::mem::discriminant(&light) => *old = light,
            _ => return Err(RenderError::LightKindChanged(index)),
        }
        self.scene.reprepare_lights();
        self.buffers.set_lights(&self.scene);
        self.planner.mark(Change::Light(index));
        Ok(())
    }

    /// Replace object `object`'s translucent material (new coefficients, same samples): its
    /// record is re-packed and uploaded by the next frame, which reruns its splat and gather
    /// (`Change::Material`). Errors when the object is opaque or the index is out of range.
    pub fn set_material(&mut self, object: usize, material: crate::optics::Material) -> Result<(), RenderError> {
        self.check_object(object)?;
        if self.buffers.beams[object].is_some() {
            return Err(RenderError::MaterialWithBeamTables(object));
        }
        let o = &mut self.scene.objects[object];
        let crate::scene::build::ResolvedMaterial::Translucent { material: m, dipoles, mm_per_unit, .. } =
            &mut o.material
        else {
            return Err(RenderError::OpaqueObject(object));
        };
        *dipoles = material
            .dipoles(*mm_per_unit)
            .map_err(|e| RenderError::InvalidMaterial { object, reason: e.to_string() })?;
        // The scene file says so too, so that a later resampling (`set_transform`) keeps it.
        if let crate::scene::MaterialSpec::Translucent { preset, sigma_a, sigma_s_prime, eta, .. } =
            &mut self.scene.scene.file.objects[object].material
        {
            (*preset, *sigma_a, *sigma_s_prime, *eta) =
                (None, Some(material.sigma_a), Some(material.sigma_s_prime), Some(material.eta));
        }
        *m = material;
        self.buffers.set_material(&self.scene, object);
        self.needs = Self::needs_of(&self.scene, self.target, &self.planner);
        self.planner.mark(Change::Material(object));
        Ok(())
    }

    /// Move object `object`: `transform` replaces its transform in the scene. That object alone
    /// is placed again and resampled (same method, count and seed), and the scene's GPU data
    /// and the passes that bind it are made anew (the hierarchy and its lists depend on the
    /// geometry); the frame targets, timers, camera and shadow pass stay. The next frame redraws
    /// every shadow and gathers every object (`Change::Geometry`). Call with no frame of this
    /// renderer in flight: its scene buffers are replaced. On an error nothing changed.
    pub fn set_transform(&mut self, object: usize, transform: crate::scene::Transform) -> Result<(), RenderError> {
        self.check_object(object)?;
        self.wait_for_recorded()?;
        let mut scene = self.scene.clone();
        scene.set_transform(object, transform).map_err(|e| RenderError::Scene(e.to_string()))?;
        check_fits(&self.gpu, &scene)?;
        let old = std::mem::replace(&mut self.scene, scene);
        if let Err(e) = self.rebuild_scene_data() {
            self.scene = old;
            return Err(e);
        }
        // Every buffer is new: nothing is gathered yet, and the change covers what was pending.
        let pending = self.planner.pending().map_or(Change::Geometry(object), |p| p.and(Change::Geometry(object)));
        self.planner = Planner::new(self.scene.objects.len(), pending);
        self.needs = Self::needs_of(&self.scene, self.target, &self.planner);
        Ok(())
    }

    /// The scene's GPU data made anew from `self.scene`, and the passes that bind it; the
    /// shadow pass, the tone map, the frame targets, timers and camera stay. No frame may be
    /// in flight (the old buffers go).
    fn rebuild_scene_data(&mut self) -> Result<(), RenderError> {
        let gpu = self.gpu.clone();
        let buffers = GpuScene::new(&gpu, &self.scene)?;
        let resources = Resources { scene: &buffers, targets: &self.targets };
        let settings = &self.scene.scene.file.render;
        // Built first, then swapped in: an error leaves the renderer as it was.
        let gather = Self::gather_pass(&gpu, &resources, settings, self.needs.pixel_gather)?;
        let (vertex_light, splat) =
            (VertexLightPass::new(&gpu, &resources)?, SplatPass::new(&gpu, &resources, settings.splat_visibility)?);
        let shade = ShadePass::new(&gpu, self.target, &resources, self.needs.pixel_gather, self.options.shade())?;
        (self.gather, self.vertex_light, self.splat, self.shade) = (gather, vertex_light, splat, shade);
        self.buffers = buffers;
        let hazards = self.hazards.get_mut();
        for r in super::graph::SCENE_BUFFERS {
            hazards.forget(r);
        }
        Ok(())
    }

    /// What the planner weighs for `scene` drawn into `target`, with the baked levels as
    /// `planner` has them (`plan::needs`).
    fn needs_of(scene: &PreparedScene, target: TargetDesc, planner: &Planner) -> SceneNeeds {
        plan::needs(scene, target != TargetDesc::Own, planner.baked_levels())
    }

    /// Where the last frame's non-finite values are, pass by pass and object by object (the
    /// splat's irradiance at the samples, the gather's exitance at the vertices), so a NaN is
    /// reported with its cause instead of drawn black. Empty when both are finite: then a
    /// non-finite pixel comes from shading.
    pub fn find_non_finite(&self) -> Result<Vec<NonFinite>, RenderError> {
        let splat = self.splat_irradiance()?;
        let exitance: Vec<[f32; 4]> = self.buffers.exitance.read()?;
        let mut found = Vec::new();
        let mut first_sample = 0;
        for (object, o) in self.scene.objects.iter().enumerate() {
            let samples = &splat[first_sample..first_sample + o.samples.len()];
            first_sample += o.samples.len();
            let bad = samples.iter().filter(|(e, a)| !(e.iter().all(|v| v.is_finite()) && a.is_finite())).count();
            if bad > 0 {
                found.push(NonFinite { pass: Pass::Splat, object, count: bad });
            }
            let first = self.buffers.object_range(object).first_vertex as usize;
            let vertices = &exitance[first..first + o.mesh.positions().len()];
            let bad = vertices.iter().filter(|e| !e.iter().all(|v| v.is_finite())).count();
            if bad > 0 {
                found.push(NonFinite { pass: Pass::Gather, object, count: bad });
            }
        }
        Ok(found)
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

    /// Before destroying what recorded frames use: wait for the queue unless every frame
    /// recorded was seen finished (the lifetime rule on `Renderer`).
    fn wait_for_recorded(&self) -> Result<(), RenderError> {
        if self.finished.get() < self.generation {
            self.gpu.wait_queue_idle()?;
            self.finished.set(self.generation);
        }
        Ok(())
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

/// An error naming the scene setting when the scene needs more than the device allows, before
/// any GPU work: dispatch sizes, image sizes and layers, storage-buffer ranges, and memory (the
/// largest single allocation against `maxMemoryAllocationSize`, the total against the largest
/// device-local heap).
fn check_fits(gpu: &Gpu, scene: &PreparedScene) -> Result<(), RenderError> {
    let mut checks = dispatch_checks(gpu, scene)?;
    checks.extend(memory_checks(gpu, scene));
    for (setting, value, limit_name, limit) in checks {
        if value > limit {
            return Err(RenderError::DoesNotFit { setting, value, limit_name, limit });
        }
    }
    Ok(())
}

/// (scene setting, its value, the device limit's name, the limit).
type Check = (String, u64, &'static str, u64);

/// Dispatch sizes, image sides and layers, and storage ranges against the device's limits.
fn dispatch_checks(gpu: &Gpu, scene: &PreparedScene) -> Result<Vec<Check>, RenderError> {
    let limits = &gpu.properties().limits;
    // Vertex- and sample-wide passes dispatch along x only.
    let dispatchable = |shader: &str| -> Result<u64, RenderError> {
        Ok(limits.max_compute_work_group_count[0] as u64 * ShaderInterface::of(shader)?.local_size[0] as u64)
    };
    let dispatch = "maxComputeWorkGroupCount x local size";
    let image_side = limits.max_image_dimension2_d as u64;
    let file = &scene.scene.file;
    let [width, height] = file.camera.resolution.map(u64::from);
    let range = limits.max_storage_buffer_range as u64;
    // With epsilon 0 the hierarchical gather lists every sample for every group of receivers.
    let flat_lists: u64 = if file.render.gather == GatherMode::Hierarchical && file.render.gather_epsilon == 0.0 {
        let group = crate::sampling::RECEIVER_GROUP_SIZE as u64;
        let per_object = |o: &crate::scene::build::PreparedObject| {
            (o.mesh.positions().len() as u64).div_ceil(group) * o.samples.len() as u64 * 4
        };
        scene.objects.iter().map(per_object).sum()
    } else {
        0
    };
    Ok(vec![
        (
            "bytes of the hierarchical gather's item lists at render.gather_epsilon 0 (every sample for every \
             group of 8 vertices)"
                .to_string(),
            flat_lists,
            "maxStorageBufferRange",
            range,
        ),
        ("the meshes' vertex count".into(), scene.vertex_count() as u64, dispatch, dispatchable("vertex_light.comp")?),
        (
            "sampling.count x translucent objects".into(),
            scene.sample_count() as u64,
            dispatch,
            dispatchable("splat.comp")?,
        ),
        ("camera.resolution (largest side)".into(), width.max(height), "maxImageDimension2D", image_side),
        (
            "camera.resolution (width x height x 4 bytes of tone-mapped output)".into(),
            4 * width * height,
            "maxStorageBufferRange",
            range,
        ),
        ("render.shadow_map_size".into(), file.render.shadow_map_size as u64, "maxImageDimension2D", image_side),
        (
            "shadow maps (one per shadow-casting light, environment directions included)".into(),
            scene.shadow_layers as u64,
            "maxImageArrayLayers",
            limits.max_image_array_layers as u64,
        ),
    ])
}

/// The large allocations against `maxMemoryAllocationSize`, and the whole scene against the
/// largest device-local heap.
fn memory_checks(gpu: &Gpu, scene: &PreparedScene) -> Vec<Check> {
    let file = &scene.scene.file;
    let [width, height] = file.camera.resolution.map(u64::from);
    let pixels = width * height;
    let (map, layers) = (file.render.shadow_map_size as u64, scene.shadow_layers.max(1) as u64);
    let (max_allocation, heap) = memory_limits(gpu);
    // The HDR image (and the surface image of the pixel gather), 16 bytes a pixel, and the
    // shadow-map array, 2 bytes a texel, are the large allocations; the rest is counted whole.
    let hdr_bytes = 16 * pixels;
    let shadow_bytes = 2 * map * map * layers;
    let vertex_bytes = 56 * scene.vertex_count() as u64 + 64 * scene.sample_count() as u64;
    let surface = if file.render.gather == GatherMode::Pixel { hdr_bytes } else { 0 };
    // HDR, surface, depth (4), tone-mapped output (4) and the EXR readback (16) per pixel.
    let total = hdr_bytes + surface + 24 * pixels + shadow_bytes + vertex_bytes;
    vec![
        (
            format!("bytes of the HDR image at camera.resolution {width}x{height}"),
            hdr_bytes,
            "maxMemoryAllocationSize",
            max_allocation,
        ),
        (
            format!("bytes of {layers} shadow maps of render.shadow_map_size {map}"),
            shadow_bytes,
            "maxMemoryAllocationSize",
            max_allocation,
        ),
        (
            format!(
                "bytes of device memory the scene needs (images at camera.resolution {width}x{height}, {layers} \
                 shadow maps of {map}^2, meshes and samples)"
            ),
            total,
            "largest device-local memory heap",
            heap,
        ),
    ]
}

/// A host target's formats must be renderable: colour attachment (optimal tiling) for the colour
/// format, depth-stencil attachment with a depth aspect for the depth format.
fn check_host_formats(gpu: &Gpu, color: vk::Format, depth: vk::Format) -> Result<(), RenderError> {
    let features = |format| {
        // SAFETY: a plain query on the device in use.
        unsafe { gpu.instance().get_physical_device_format_properties(gpu.physical_device(), format) }
            .optimal_tiling_features
    };
    if !features(color).contains(vk::FormatFeatureFlags::COLOR_ATTACHMENT) {
        return Err(RenderError::Format { which: "colour", format: color });
    }
    let has_depth = crate::gpu::aspect_of(depth).contains(vk::ImageAspectFlags::DEPTH);
    if !has_depth || !features(depth).contains(vk::FormatFeatureFlags::DEPTH_STENCIL_ATTACHMENT) {
        return Err(RenderError::Format { which: "depth", format: depth });
    }
    Ok(())
}

/// `maxMemoryAllocationSize` and the size of the largest device-local heap.
fn memory_limits(gpu: &Gpu) -> (u64, u64) {
    let mut maintenance3 = ash::vk::PhysicalDeviceMaintenance3Properties::default();
    let mut properties = ash::vk::PhysicalDeviceProperties2::default().push_next(&mut maintenance3);
    // SAFETY: plain queries on the device in use (Vulkan 1.1 core).
    let memory = unsafe {
        gpu.instance().get_physical_device_properties2(gpu.physical_device(), &mut properties);
        gpu.instance().get_physical_device_memory_properties(gpu.physical_device())
    };
    let heaps = &memory.memory_heaps[..memory.memory_heap_count as usize];
    let local = heaps.iter().filter(|h| h.flags.contains(ash::vk::MemoryHeapFlags::DEVICE_LOCAL));
    (maintenance3.max_memory_allocation_size, local.map(|h| h.size).max().unwrap_or(u64::MAX))
}
