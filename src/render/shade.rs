//! Forward-shading pass (`glsl/shade.vert`, `glsl/shade.frag`): every object rasterised from the
//! camera into a linear HDR target; translucent surfaces turn gathered exitance into radiance
//! through the BSSRDF's outgoing Fresnel lobe, opaque surfaces are Lambertian, and the key
//! (non-environment) lights add a GGX specular lobe to every surface, all shadowed by the
//! shadow maps. The environment reaches diffuse surfaces through the per-vertex cache.
//!
//! Vertex input: binding 0 = `records::Vertex`, binding 1 = exitance, binding 2 = cached
//! environment irradiance (vec4 per vertex each).
//! Bindings: 0 = lights, 1 = shadow maps. Push: `ShadePush` (with the object's material).

use super::gpu_scene::LevelRange;
use super::graph::{Resource, Resources, Use, overwrite, read, write};
use super::host::HostSync;
use super::pass::{FrameInputs, RenderPass};
use super::plan::Plan;
use super::records::Vertex;
use crate::gpu::{Access, DescriptorSet, Gpu, GpuResult, GraphicsDesc, GraphicsPipeline};
use crate::mesh::Enclosure;
use ash::vk;
use glam::{Mat4, Vec3};
use std::sync::Arc;

use super::targets::CAMERA_DEPTH_FORMAT;
pub use super::targets::{HDR_FORMAT, SURFACE_FORMAT};

/// `Plan::skip_terms` bit: key lights' shadow lookups (every light counts as visible).
pub const TERM_SHADOW: u32 = 1;
/// `Plan::skip_terms` bit: the GGX specular lobe.
pub const TERM_SPECULAR: u32 = 2;
/// `Plan::skip_terms` bit: the Fresnel transmittances of translucent surfaces (taken as 1).
pub const TERM_FRESNEL: u32 = 4;
/// `Plan::skip_terms` bit: everything but the interpolated inputs (exitance plus sky light):
/// what rasterising and interpolating alone cost.
pub const TERM_ALL: u32 = 8;

/// `ShadePush` in glsl/common/shade_push.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadePush {
    /// World -> clip of the camera, column-major.
    pub view_proj: [[f32; 4]; 4],
    /// xyz: camera position; w: object index.
    pub eye_object: [f32; 4],
    /// x: light count; y: key (non-environment) lights, which come first in the buffer; z: the
    /// object's locally computed channels (`ObjectRecord::local_channels`); w: terms left out.
    pub counts: [u32; 4],
    /// The object's `ObjectRecord::albedo_roughness`.
    pub albedo_roughness: [f32; 4],
    /// x: the object's `ObjectRecord::eta`; y: its `norm`; zw: 0. In the push block, not read
    /// from the record: llvmpipe loads a storage buffer lane by lane in a fragment shader.
    pub material: [f32; 4],
}

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

/// The faces of a level of detail (its `enclosure`, its vertices' `bounds`) that no ray from
/// the eye reaches through `view_proj` (world -> clip, depth running as `convention` says), to
/// cull: the inner side of a surface that encloses a volume, when the whole of it lies beyond
/// the near plane (one the near plane cuts shows its inside); NONE for an open surface. On
/// screen a face is front (counter-clockwise, with the viewport's positive height) when its
/// winding's normal points towards the eye in clip space, which the sign of det(view_proj) (the
/// sign of the map's Jacobian wherever w > 0) and the depth's direction decide.
pub fn hidden_faces(
    enclosure: Enclosure,
    bounds: (Vec3, Vec3),
    view_proj: Mat4,
    convention: DepthConvention,
) -> vk::CullModeFlags {
    let outward = match enclosure {
        Enclosure::Open => return vk::CullModeFlags::NONE,
        Enclosure::Outward => true,
        Enclosure::Inward => false,
    };
    let (lo, hi) = bounds;
    let beyond_near = (0..8).all(|k| {
        let corner = Vec3::new(
            if k & 1 == 0 { lo.x } else { hi.x },
            if k & 2 == 0 { lo.y } else { hi.y },
            if k & 4 == 0 { lo.z } else { hi.z },
        );
        let clip = view_proj * corner.extend(1.0);
        // Vulkan's clip volume runs 0 <= z <= w; the near plane is z = 0, or z = w reversed.
        clip.w > 0.0
            && match convention {
                DepthConvention::Standard => clip.z > 0.0,
                DepthConvention::Reversed => clip.z < clip.w,
            }
    });
    let det = view_proj.determinant();
    if !beyond_near || !det.is_finite() || det == 0.0 {
        return vk::CullModeFlags::NONE;
    }
    let front_visible = (det > 0.0) == (convention == DepthConvention::Standard);
    if front_visible == outward { vk::CullModeFlags::BACK } else { vk::CullModeFlags::FRONT }
}

/// The faces to cull when drawing `level` through `view_proj`: its `hidden_faces` where `plan`
/// culls them (`Plan::cull_hidden_faces`), else none.
pub fn culled_faces(
    plan: &Plan,
    level: &LevelRange,
    view_proj: Mat4,
    convention: DepthConvention,
) -> vk::CullModeFlags {
    if plan.cull_hidden_faces {
        hidden_faces(level.enclosure, level.bounds, view_proj, convention)
    } else {
        vk::CullModeFlags::NONE
    }
}

/// Key lights up to this many are a specialization constant of the shading and splat pipelines.
pub const MAX_UNROLLED_KEY_LIGHTS: u32 = 4;

/// The shading and splat pipelines' key-light count (SHADE_KEY_LIGHTS in glsl/common/shade.glsl,
/// SPLAT_KEY_LIGHTS in glsl/splat.comp) for a scene of `key_lights`: the count itself up to
/// `MAX_UNROLLED_KEY_LIGHTS`, so that the loop over them is unrolled and each light's record read
/// at a constant index, once for every lane (a CPU driver loads a storage buffer at a varying
/// index lane by lane: about 4 of the default scene's 17 ms of shading on lavapipe, measured
/// under load); 0 above it, and the loop runs to the push block's count.
pub fn unrolled_key_lights(key_lights: u32) -> u32 {
    if key_lights <= MAX_UNROLLED_KEY_LIGHTS { key_lights } else { 0 }
}

/// glsl/common/shade.glsl's bindings, in binding order.
const BINDINGS: [Resource; 2] = [Resource::Lights, Resource::ShadowMaps];

/// The forward-shading pass: a graphics pipeline (shade.vert with shade.frag, or shade_pixel.frag
/// for the pixel gather) and its descriptor set, drawing into the frame targets' camera images
/// (`FrameTargets::camera`) or a host's. One indexed draw per object.
pub struct ShadePass {
    /// Per `[translucent][shadow radius][key lights all directional]` (glsl/common/shade.glsl's
    /// specialization constants; the fourth, the scene's key-light count, `unrolled_key_lights`,
    /// is the same for all): a pipeline and its set.
    variants: [[[(GraphicsPipeline, DescriptorSet); 2]; 2]; 2],
    /// Whether it draws the surface image too (shade_pixel.frag's second attachment).
    pixel_gather: bool,
    /// The depth test: what the attachment is cleared to when not loaded (the far plane), and
    /// which way depth runs (`hidden_faces`).
    depth: DepthTest,
}

/// How the shading pass draws: its depth test and its samples per pixel
/// (`RendererOptions`).
#[derive(Clone, Copy, Debug)]
pub struct ShadeOptions {
    /// The depth test and convention.
    pub depth: DepthTest,
    /// Samples per pixel of the attachments.
    pub samples: vk::SampleCountFlags,
}

/// A per-vertex vec4 stream (exitance, cached irradiance) at `binding`, read at `location`.
fn vec4_stream(
    binding: u32,
    location: u32,
) -> (vk::VertexInputBindingDescription, vk::VertexInputAttributeDescription) {
    (
        vk::VertexInputBindingDescription { binding, stride: 16, input_rate: vk::VertexInputRate::VERTEX },
        vk::VertexInputAttributeDescription { location, binding, format: vk::Format::R32G32B32A32_SFLOAT, offset: 0 },
    )
}

impl ShadePass {
    /// The pipeline for `target`'s formats and `depth`'s test, and one descriptor set over
    /// `BINDINGS`.
    pub fn new(
        gpu: &Arc<Gpu>,
        target: TargetDesc,
        resources: &Resources,
        pixel_gather: bool,
        options: ShadeOptions,
    ) -> GpuResult<ShadePass> {
        let fragment = if pixel_gather { "shade_pixel.frag" } else { "shade.frag" };
        let mut desc = GraphicsDesc::new("shade.vert", Some(fragment));
        let (exitance, environment) = (vec4_stream(1, 2), vec4_stream(2, 3));
        desc.vertex_bindings = vec![Vertex::binding(), exitance.0, environment.0];
        desc.vertex_attributes =
            vec![Vertex::position_attribute(), Vertex::normal_attribute(), exitance.1, environment.1];
        let (color, depth_format) = match target {
            TargetDesc::Own => (HDR_FORMAT, CAMERA_DEPTH_FORMAT),
            TargetDesc::Host { color_format, depth_format } => (color_format, depth_format),
        };
        desc.color_formats = if pixel_gather { vec![color, SURFACE_FORMAT] } else { vec![color] };
        desc.depth_format = Some(depth_format);
        desc.depth_compare = options.depth.compare;
        desc.samples = options.samples;
        desc.dynamic_cull = true;
        let bindings = resources.bind_all(&BINDINGS)?;
        let keys = unrolled_key_lights(resources.scene.key_light_count);
        let variant =
            |translucent: u32, radius: u32, directional: u32| -> GpuResult<(GraphicsPipeline, DescriptorSet)> {
                let desc =
                    GraphicsDesc { specialization: vec![translucent, radius, directional, keys], ..desc.clone() };
                let pipeline = GraphicsPipeline::new(gpu, &desc)?;
                let set = pipeline.descriptor_set(&bindings)?;
                Ok((pipeline, set))
            };
        let by_lights =
            |t, r| -> GpuResult<[(GraphicsPipeline, DescriptorSet); 2]> { Ok([variant(t, r, 0)?, variant(t, r, 1)?]) };
        let variants = [[by_lights(0, 0)?, by_lights(0, 1)?], [by_lights(1, 0)?, by_lights(1, 1)?]];
        Ok(ShadePass { variants, pixel_gather, depth: options.depth })
    }

    /// Object `i`'s pipeline variant, its set and its push block.
    fn object_draw(&self, frame: &FrameInputs, i: usize) -> (&GraphicsPipeline, &DescriptorSet, ShadePush) {
        let scene = frame.scene;
        let eye = frame.eye;
        let record = scene.object_record(i);
        let push = ShadePush {
            view_proj: frame.view_proj.to_cols_array_2d(),
            eye_object: [eye.x, eye.y, eye.z, i as f32],
            counts: [scene.light_count, scene.key_light_count, record.local_channels, frame.plan.skip_terms],
            albedo_roughness: record.albedo_roughness,
            material: [record.eta, record.norm, 0.0, 0.0],
        };
        let translucent = record.kind == super::records::MATERIAL_TRANSLUCENT;
        let filter = usize::from(!frame.plan.one_tap_shadows);
        let (pipeline, set) =
            &self.variants[usize::from(translucent)][filter][usize::from(scene.key_lights_directional)];
        (pipeline, set, push)
    }

    /// Views, depth view, render area and whether to load: the frame targets' camera images, or
    /// the host's attachments.
    fn attachments(&self, frame: &FrameInputs) -> (Vec<vk::ImageView>, vk::ImageView, vk::Rect2D, bool) {
        match (frame.target, &frame.targets.camera) {
            (Some(t), _) => {
                (vec![t.color.view], t.depth.view, vk::Rect2D { offset: t.offset, extent: t.extent }, t.load)
            }
            (None, Some(c)) => {
                let colors = std::iter::once(&c.hdr).chain(c.surface.as_ref().filter(|_| self.pixel_gather));
                let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: c.hdr.extent() };
                (colors.map(|i| i.view()).collect(), c.depth.view(), area, false)
            }
            (None, None) => unreachable!("Renderer checks that a host target is given"),
        }
    }
}

impl RenderPass for ShadePass {
    /// The vertex streams and shading inputs read; the camera images overwritten (cleared), or
    /// the host's attachments written after the host's own drawing.
    fn uses(&self, frame: &FrameInputs) -> Vec<Use> {
        let mut uses = vec![
            read(Resource::Vertices, Access::VertexAttributeRead),
            read(Resource::Exitance, Access::VertexAttributeRead),
            read(Resource::EnvironmentIrradiance, Access::VertexAttributeRead),
            read(Resource::Lights, Access::FragmentRead),
            read(Resource::ShadowMaps, Access::FragmentSampledRead),
        ];
        if frame.target.is_some() {
            uses.push(write(Resource::HostColor, Access::ColorAttachmentWrite));
            uses.push(write(Resource::HostDepth, Access::DepthAttachmentReadWrite));
        } else {
            uses.push(overwrite(Resource::Hdr, Access::ColorAttachmentWrite));
            uses.push(overwrite(Resource::CameraDepth, Access::DepthAttachmentReadWrite));
            if self.pixel_gather {
                uses.push(overwrite(Resource::Surface, Access::ColorAttachmentWrite));
            }
        }
        uses
    }

    /// Clear to the background (or load the host's contents) and draw every object at the
    /// plan's level of detail.
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let device = frame.gpu.device();
        let scene = frame.scene;
        let (views, depth_view, area, load) = self.attachments(frame);
        let load_op = if load { vk::AttachmentLoadOp::LOAD } else { vk::AttachmentLoadOp::CLEAR };
        let [r, g, b] = frame.background;
        let clears = [[r, g, b, 1.0], [0.0; 4]];
        let mut colors: Vec<_> = views
            .iter()
            .zip(clears)
            .map(|(view, clear)| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(*view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(load_op)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: clear } })
            })
            .collect();
        if let Some(resolve) = frame.target.and_then(|t| t.resolve) {
            // A host target has one colour attachment; its samples are averaged into `resolve`.
            colors[0] = colors[0]
                .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                .resolve_image_view(resolve.view)
                .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL);
        }
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(depth_view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(load_op)
            // The host may test against its depth again after us; our own is not read.
            .store_op(if frame.target.is_some() {
                vk::AttachmentStoreOp::STORE
            } else {
                vk::AttachmentStoreOp::DONT_CARE
            })
            .clear_value(vk::ClearValue {
                depth_stencil: vk::ClearDepthStencilValue { depth: self.depth.far(), stencil: 0 },
            });
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth);
        if let Some(t) = frame.target {
            super::host::record_entry(device, cmd, t);
        }
        // SAFETY: `cmd` is recording; attachments are in the layouts the barriers above set.
        unsafe {
            device.cmd_begin_rendering(cmd, &info);
            let streams = [scene.vertices.raw(), scene.exitance.raw(), scene.environment_irradiance.raw()];
            device.cmd_bind_vertex_buffers(cmd, 0, &streams, &[0, 0, 0]);
            device.cmd_bind_index_buffer(cmd, scene.indices.raw(), 0, vk::IndexType::UINT32);
        }
        for i in 0..scene.levels.len() {
            let (pipeline, set, push) = self.object_draw(frame, i);
            let level = scene.level(i, frame.plan.level(i));
            // ALWAYS draws the last face over the others: culling would change which that is.
            let hidden = match self.depth.compare {
                vk::CompareOp::ALWAYS => vk::CullModeFlags::NONE,
                _ => culled_faces(frame.plan, &level, frame.view_proj, self.depth.convention),
            };
            pipeline.bind_area(cmd, Some(set), &push, area);
            pipeline.set_cull(cmd, hidden);
            pipeline.draw_indexed(cmd, level.draw.index_count, level.draw.first_index, level.draw.vertex_offset);
        }
        unsafe { device.cmd_end_rendering(cmd) };
        if let Some(t) = frame.target {
            super::host::record_exit(device, cmd, t);
        }
    }
}
