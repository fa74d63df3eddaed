//! Forward-shading pass (`glsl/shade.vert`, `glsl/shade.frag`): every object rasterised from the
//! camera into a linear HDR target; translucent surfaces turn gathered exitance into radiance
//! through the BSSRDF's outgoing Fresnel lobe, opaque surfaces are Lambertian, and the key
//! (non-environment) lights add a GGX specular lobe to every surface, all shadowed by the
//! shadow maps. The environment reaches diffuse surfaces through the per-vertex cache.
//!
//! Vertex input: binding 0 = `records::Vertex`, binding 1 = exitance, binding 2 = cached
//! environment irradiance (vec4 per vertex each).
//! Bindings: 0 = lights, 1 = shadow maps. Push: `ShadePush` (with the object's material).

use super::graph::{Resource, Resources, Use, overwrite, read, write};
use super::cull::culled_faces;
use super::target::{DepthTest, TargetDesc};
use super::error::RenderError;
use super::options::RendererOptions;
use super::pass::{FrameInputs, PassContext, Rebuild, RegisteredPass, RenderPass};
use super::records::Vertex;
use crate::gpu::{Access, DescriptorSet, Gpu, GpuResult, GraphicsDesc, GraphicsPipeline};
use ash::vk;
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
    /// Display output (`Output::Display`): the exposure the tone curve is applied at.
    pub display: Option<f32>,
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
                let (display, exposure) = options.display.map_or((0, 1.0f32), |e| (1, e));
                let specialization = vec![translucent, radius, directional, keys, display, exposure.to_bits()];
                let desc = GraphicsDesc { specialization, ..desc.clone() };
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
            let streams = [scene.buffers.vertices.raw(), scene.buffers.exitance.raw(), scene.buffers.environment_irradiance.raw()];
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
        // SAFETY: ends the render begun above in this function, in the same `cmd`.
        unsafe { device.cmd_end_rendering(cmd) };
        if let Some(t) = frame.target {
            super::host::record_exit(device, cmd, t);
        }
    }
}

impl ShadeOptions {
    /// What the shading pass takes of the host's choices, and of the scene its exposure.
    pub fn of(options: &RendererOptions, exposure: f32) -> ShadeOptions {
        let display = (options.output == super::options::Output::Display).then_some(exposure);
        ShadeOptions { depth: options.depth, samples: options.samples, display }
    }
}

impl RegisteredPass for ShadePass {
    // It binds the lights buffer, which new scene data replaces.
    const REBUILT_ON: &'static [Rebuild] = &[Rebuild::SceneData];

    fn build(c: &PassContext) -> Result<Option<Self>, RenderError> {
        let options = ShadeOptions::of(c.options, c.scene.scene.file.render.exposure);
        Ok(Some(ShadePass::new(c.gpu, c.target, &c.resources, c.needs.pixel_gather, options)?))
    }
}
