//! What a host engine chooses of the renderer's target, at the crate's boundary: where shading
//! draws (`TargetDesc`), which way depth runs and how it is tested (`DepthTest`), the host's
//! attachments for one frame (`HostTarget`) and how it hands them over (`HostSync`). Plain data:
//! the checks on them are `host`'s, the drawing is `shade`'s.

use ash::vk;

/// What the shading pass draws into.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TargetDesc {
    /// Its own linear HDR image (RGBA32F) and depth, tone-mapped by the tone-map pass.
    Own,
    /// A host engine's colour and depth images of these formats, given each frame as a
    /// `HostTarget`. The pass writes linear radiance (alpha 1) and depth-tests against the host's
    /// depth, depth written, as the renderer's `DepthTest` says (`RendererOptions::depth`: 0 near,
    /// 1 far and LESS_OR_EQUAL unless the host chose reversed-Z).
    Host {
        /// Format of the host's colour image.
        color_format: vk::Format,
        /// Format of the host's depth image.
        depth_format: vk::Format,
    },
}

/// Which way depth runs in the target's depth image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DepthConvention {
    /// 0 at the near plane, 1 at the far plane: cleared to 1, nearer is less.
    #[default]
    Standard,
    /// Reversed-Z: 1 at the near plane, 0 at the far plane: cleared to 0, nearer is greater
    /// (float depth's precision then spreads over distance). The camera's projection must map
    /// so too (`CameraView::reversed_depth`).
    Reversed,
}

/// The depth test shading makes against the target's depth (and writes it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthTest {
    /// Which way depth runs: what `load: false` clears to, and which comparisons make sense.
    pub convention: DepthConvention,
    /// The comparison: one that passes nearer fragments under `convention` (LESS or
    /// LESS_OR_EQUAL for standard depth, GREATER or GREATER_OR_EQUAL for reversed), or EQUAL
    /// (after the host's depth pre-pass) or ALWAYS under either; `Renderer::with_options`
    /// refuses the others (`RenderError::DepthCompare`).
    pub compare: vk::CompareOp,
}

impl DepthTest {
    /// 0 near, 1 far, LESS_OR_EQUAL: the default, and the CLI's.
    pub const STANDARD: DepthTest =
        DepthTest { convention: DepthConvention::Standard, compare: vk::CompareOp::LESS_OR_EQUAL };
    /// Reversed-Z: 1 near, 0 far, GREATER_OR_EQUAL.
    pub const REVERSED: DepthTest =
        DepthTest { convention: DepthConvention::Reversed, compare: vk::CompareOp::GREATER_OR_EQUAL };

    /// The far plane's depth, which `load: false` clears to.
    pub fn far(self) -> f32 {
        match self.convention {
            DepthConvention::Standard => 1.0,
            DepthConvention::Reversed => 0.0,
        }
    }

    /// Whether `compare` passes nearer fragments under `convention` (see `compare`).
    pub fn is_consistent(self) -> bool {
        use vk::CompareOp as C;
        match (self.convention, self.compare) {
            (_, C::EQUAL | C::ALWAYS) => true,
            (DepthConvention::Standard, c) => c == C::LESS || c == C::LESS_OR_EQUAL,
            (DepthConvention::Reversed, c) => c == C::GREATER || c == C::GREATER_OR_EQUAL,
        }
    }
}

impl Default for DepthTest {
    fn default() -> Self {
        DepthTest::STANDARD
    }
}

/// A host's attachments for one frame (`TargetDesc::Host`). By default (`HostSync::Attachments`)
/// on entry and on exit the colour image is in COLOR_ATTACHMENT_OPTIMAL and the depth image in
/// DEPTH_ATTACHMENT_OPTIMAL; the pass waits for earlier attachment writes, and its own writes
/// are done at the colour-output and late-fragment-test stages, where the host's next barrier
/// picks them up. With `HostSync::Declared` the pass records the barriers from and to the
/// states the host declares instead.
///
/// Each attachment carries its image's format and size, because a view does not say them and
/// Vulkan cannot be asked: `record_frame` checks them against the `TargetDesc` the pipelines
/// were made for and the render area against both images and the device's framebuffer limits
/// (an area past an image is `VUID-VkRenderingInfo-pNext-06079`, and a crash on some drivers).
#[derive(Clone, Copy, Debug)]
pub struct HostTarget {
    /// The host's colour image.
    pub color: HostAttachment,
    /// The host's depth image.
    pub depth: HostAttachment,
    /// The render area's size, and the viewport's and scissor's: at least 1x1, and within both
    /// images from `offset`. The camera's projection is for this size's aspect ratio, and
    /// levels of detail follow it.
    pub extent: vk::Extent2D,
    /// The render area's top-left corner in both images (`vk::Offset2D::default()`: the
    /// origin): not negative. Pixels outside the area are neither cleared nor drawn.
    pub offset: vk::Offset2D,
    /// With multisampled attachments (`RendererOptions::samples` above 1), the single-sampled
    /// image of the colour format that shading resolves the colour into (averaged), in
    /// COLOR_ATTACHMENT_OPTIMAL on entry and exit like the colour image (`HostSync::Attachments`
    /// only); `None` leaves the resolve to the host.
    pub resolve: Option<HostAttachment>,
    /// How the images are handed over: in the attachment layouts (`HostSync::Attachments`,
    /// the default), or in states the host declares for entry and exit (`HostSync::Declared`).
    pub sync: HostSync,
    /// Keep the host's colour and depth (`true`), or clear them to the scene's background and
    /// the far plane (`false`).
    pub load: bool,
}

/// One of the host's images, as `HostTarget` gives it: a 2D view of mip level 0, one layer.
#[derive(Clone, Copy, Debug)]
pub struct HostAttachment {
    /// The view drawn through.
    pub view: vk::ImageView,
    /// The image's (and view's) format: must be the `TargetDesc::Host` format.
    pub format: vk::Format,
    /// The image's width and height at mip level 0.
    pub extent: vk::Extent2D,
    /// The image's samples per pixel: must be `RendererOptions::samples` for the colour and
    /// depth images, TYPE_1 for a resolve image.
    pub samples: vk::SampleCountFlags,
}

/// How the host hands its attachments to the shading pass and takes them back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum HostSync {
    /// In the attachment layouts on entry and on exit (COLOR_ATTACHMENT_OPTIMAL,
    /// DEPTH_ATTACHMENT_OPTIMAL): the host's earlier attachment writes are waited for, and its
    /// next use needs a barrier of its own from translucent's attachment writes.
    #[default]
    Attachments,
    /// Each image's state on entry and the state the host wants it in on exit
    /// (FidelityFX-style): translucent records the image barriers, layout changes included, from
    /// the entry state to its attachment use and from that to the exit state, and the host
    /// records none around it.
    Declared {
        /// The colour image.
        color: DeclaredImage,
        /// The depth image.
        depth: DeclaredImage,
    },
}

/// One of the host's images with its states on entry and exit (`HostSync::Declared`). The
/// barriers cover mip level 0 and array layer 0, what the attachment's view shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DeclaredImage {
    /// The image the attachment's view is of.
    pub image: vk::Image,
    /// Its layout, and the stages and accesses of the host's last use before the frame
    /// (`ImageState::UNUSED` for a new image). Its layout may be UNDEFINED only when the frame
    /// does not `load` it.
    pub entry: ImageState,
    /// The layout the host wants it in after the frame, and the stages and accesses of its
    /// next use: neither UNDEFINED nor PREINITIALIZED.
    pub exit: ImageState,
}

/// A layout and the pipeline stages and accesses of a use of an image.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageState {
    /// The image's layout during that use.
    pub layout: vk::ImageLayout,
    /// The stages of the use.
    pub stages: vk::PipelineStageFlags2,
    /// Its memory accesses (empty for a read-only use that needs no visibility, as on entry).
    pub access: vk::AccessFlags2,
}

impl ImageState {
    /// A new image: UNDEFINED, no earlier use to wait for.
    pub const UNUSED: ImageState = ImageState {
        layout: vk::ImageLayout::UNDEFINED,
        stages: vk::PipelineStageFlags2::NONE,
        access: vk::AccessFlags2::NONE,
    };
}

