//! `RenderError`: why a renderer could not be made, or refused a call. Every variant is a case
//! a host can match on; errors of the floors below are carried whole (`source()`).

use super::target::DepthConvention;
use crate::gpu::{Access, GpuError};
use crate::optics::OpticsError;
use crate::scene::SceneError;
use ash::vk;

/// Why a renderer could not be made.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scene asks for more than the device has.
    #[error("{setting} = {value} does not fit this device: its {limit_name} is {limit}")]
    DoesNotFit {
        /// The scene setting that is too large, or the quantity it leads to (e.g. the bytes of the
        /// HDR image at camera.resolution).
        setting: Quantity,
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
    /// `SceneEdit::Material` of an object whose `model` takes single scattering between points
    /// before or after the edit: its kernel tables are built with the scene's GPU data.
    #[error(
        "set_material: object {0}'s material.model takes single scattering between points, before or after the \
         edit, whose tables are built once with the scene; load the scene with the new material instead, or give \
         it model = \"dipole\""
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
    /// `Output::Display` asked of a renderer that draws into its own image (which its own tone
    /// map already turns into display values).
    #[error("RendererOptions::output = Display is for a host target; the renderer's own image is tone-mapped already")]
    DisplayOnOwnTarget,
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
    /// `read_timings` or `discard` of a frame another renderer recorded.
    #[error("this frame was recorded by another renderer")]
    ForeignFrame,
    /// `discard` of a frame after which another was recorded (which counted on it).
    #[error("discard: frame {frame} is not the last recorded ({last} is); discard a frame before recording the next")]
    DiscardNotLast {
        /// The frame given.
        frame: u64,
        /// The last frame recorded.
        last: u64,
    },
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
    /// A translucent-only edit (`SceneEdit::Material`) on an opaque object.
    #[error("object {0} is opaque: it has no translucent material to replace")]
    OpaqueObject(usize),
    /// `SceneEdit::Material` with coefficients the dipole model refuses.
    #[error("object {object}: invalid material: {source}")]
    InvalidMaterial {
        /// The object.
        object: usize,
        /// What is wrong with it.
        source: OpticsError,
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
    /// A scene change could not be prepared (the error names the object and step).
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// `SceneEdit::Light` was given a light of another kind than scene light `index`, or an index past the
    /// scene's lights.
    #[error("light {0} cannot be replaced by a light of another kind")]
    LightKindChanged(usize),
    /// An error of the GPU core.
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// What of a scene a device limit is checked against, named by the scene setting it follows
/// from (`RenderError::DoesNotFit`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// The hierarchical gather's item lists at epsilon 0, in bytes.
    FlatGatherLists,
    /// Vertices of every mesh together.
    Vertices,
    /// Samples of every translucent object together.
    Samples,
    /// The image's larger side.
    ResolutionSide,
    /// The tone-mapped output, in bytes.
    ToneMapped,
    /// `render.shadow_map_size`.
    ShadowMapSize,
    /// Shadow-map layers.
    ShadowLayers,
    /// The HDR image at this resolution, in bytes.
    HdrBytes([u64; 2]),
    /// This many shadow maps of this size, in bytes.
    ShadowBytes {
        /// Layers.
        layers: u64,
        /// Texels per side.
        size: u64,
    },
    /// Everything the scene needs on the device, in bytes.
    SceneBytes {
        /// `camera.resolution`.
        resolution: [u64; 2],
        /// Shadow-map layers.
        layers: u64,
        /// Texels per side of each.
        size: u64,
    },
}

impl std::fmt::Display for Quantity {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Quantity::FlatGatherLists => write!(
                f,
                "bytes of the hierarchical gather's item lists at render.gather_epsilon 0 (every sample for every \
                 group of 8 vertices)"
            ),
            Quantity::Vertices => write!(f, "the meshes' vertex count"),
            Quantity::Samples => write!(f, "sampling.count x translucent objects"),
            Quantity::ResolutionSide => write!(f, "camera.resolution (largest side)"),
            Quantity::ToneMapped => write!(f, "camera.resolution (width x height x 4 bytes of tone-mapped output)"),
            Quantity::ShadowMapSize => write!(f, "render.shadow_map_size"),
            Quantity::ShadowLayers => {
                write!(f, "shadow maps (one per shadow-casting light, environment directions included)")
            }
            Quantity::HdrBytes([w, h]) => write!(f, "bytes of the HDR image at camera.resolution {w}x{h}"),
            Quantity::ShadowBytes { layers, size } => {
                write!(f, "bytes of {layers} shadow maps of render.shadow_map_size {size}")
            }
            Quantity::SceneBytes { resolution: [w, h], layers, size } => write!(
                f,
                "bytes of device memory the scene needs (images at camera.resolution {w}x{h}, {layers} shadow maps \
                 of {size}^2, meshes and samples)"
            ),
        }
    }
}
