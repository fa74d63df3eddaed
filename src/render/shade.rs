//! Forward-shading pass (`glsl/shade.vert`, `glsl/shade.frag`): every object rasterised from the
//! camera into a linear HDR target; translucent surfaces turn gathered exitance into radiance
//! through the BSSRDF's outgoing Fresnel lobe, opaque surfaces are Lambertian, and the key
//! (non-environment) lights add a GGX specular lobe to every surface, all shadowed by the
//! shadow maps. The environment reaches diffuse surfaces through the per-vertex cache.
//!
//! Vertex input: binding 0 = `records::Vertex`, binding 1 = exitance, binding 2 = cached
//! environment irradiance (vec4 per vertex each).
//! Bindings: 0 = objects, 1 = lights, 2 = shadow maps. Push: `ShadePush`.

use super::gpu_scene::GpuScene;
use super::pass::{FrameInputs, RenderPass};
use super::records::Vertex;
use super::shadow::ShadowPass;
use crate::gpu::{
    Access, Binding, DescriptorSet, Gpu, GpuResult, GraphicsDesc, GraphicsPipeline, Image, ImageBarrier, ImageDesc,
};
use ash::vk;
use std::sync::Arc;

pub const HDR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Pixel gather only: world position and translucent object of each pixel.
pub const SURFACE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// `ShadePush` in glsl/common/shade_push.glsl.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadePush {
    pub view_proj: [[f32; 4]; 4],
    /// xyz: camera position; w: object index.
    pub eye_object: [f32; 4],
    /// x: light count; y: key (non-environment) lights, which come first in the buffer.
    pub counts: [u32; 4],
}

pub struct ShadePass {
    pipeline: GraphicsPipeline,
    set: DescriptorSet,
    hdr: Image,
    depth: Image,
    /// Pixel gather only (shade_pixel.frag's second attachment).
    surface: Option<Image>,
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

fn attachment(name: &str, [width, height]: [u32; 2], format: vk::Format, usage: vk::ImageUsageFlags) -> ImageDesc {
    ImageDesc::new(name, width, height, format, usage)
}

impl ShadePass {
    pub fn new(
        gpu: &Arc<Gpu>,
        size: [u32; 2],
        scene: &GpuScene,
        shadow: &ShadowPass,
        pixel_gather: bool,
    ) -> GpuResult<ShadePass> {
        let fragment = if pixel_gather { "shade_pixel.frag" } else { "shade.frag" };
        let mut desc = GraphicsDesc::new("shade.vert", Some(fragment));
        let (exitance, environment) = (vec4_stream(1, 2), vec4_stream(2, 3));
        desc.vertex_bindings = vec![Vertex::binding(), exitance.0, environment.0];
        desc.vertex_attributes =
            vec![Vertex::position_attribute(), Vertex::normal_attribute(), exitance.1, environment.1];
        desc.color_formats = if pixel_gather { vec![HDR_FORMAT, SURFACE_FORMAT] } else { vec![HDR_FORMAT] };
        desc.depth_format = Some(DEPTH_FORMAT);
        let pipeline = GraphicsPipeline::new(gpu, &desc)?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(&scene.objects),
            Binding::Buffer(&scene.lights),
            shadow.binding(),
        ])?;
        use vk::ImageUsageFlags as U;
        // STORAGE: the pixel gather adds its exitance in place.
        let hdr = Image::new(
            gpu,
            &attachment("hdr radiance", size, HDR_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED | U::STORAGE),
        )?;
        let surface = pixel_gather
            .then(|| Image::new(gpu, &attachment("surface", size, SURFACE_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED)))
            .transpose()?;
        let depth = Image::new(gpu, &attachment("camera depth", size, DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT))?;
        Ok(ShadePass { pipeline, set, hdr, depth, surface })
    }

    pub fn hdr(&self) -> &Image {
        &self.hdr
    }
    /// The surface image (pixel gather only), readable by compute after the pass.
    pub fn surface(&self) -> Option<&Image> {
        self.surface.as_ref()
    }

    /// The colour images this pass draws: HDR, and the surface in pixel-gather mode.
    fn colors(&self) -> impl Iterator<Item = &Image> {
        std::iter::once(&self.hdr).chain(&self.surface)
    }
}

impl RenderPass for ShadePass {
    /// Clear to the background, draw every object (`scene.draws[i]` is object i), leave the HDR
    /// (and surface) image readable by compute for the tone map (and the pixel gather).
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let device = frame.gpu.device();
        let scene = frame.scene;
        let color = vk::ImageAspectFlags::COLOR;
        let (readers, writes) = ([Access::ComputeSampledRead], [Access::ColorAttachmentWrite]);
        for image in self.colors() {
            ImageBarrier::new(image.raw(), color, &readers, &writes).discard(true).record(device, cmd);
        }
        let depth_access = [Access::DepthAttachmentReadWrite];
        ImageBarrier::new(self.depth.raw(), vk::ImageAspectFlags::DEPTH, &depth_access, &depth_access)
            .discard(true)
            .record(device, cmd);
        let [r, g, b] = frame.background;
        let clears = [[r, g, b, 1.0], [0.0; 4]];
        let colors: Vec<_> = self
            .colors()
            .zip(clears)
            .map(|(image, clear)| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(image.view())
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: clear } })
            })
            .collect();
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view())
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::DONT_CARE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
        let extent = self.hdr.extent();
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth);
        // SAFETY: `cmd` is recording; attachments are in the layouts the barriers above set.
        unsafe {
            device.cmd_begin_rendering(cmd, &info);
            let streams = [scene.vertices.raw(), scene.exitance.raw(), scene.environment_irradiance.raw()];
            device.cmd_bind_vertex_buffers(cmd, 0, &streams, &[0, 0, 0]);
            device.cmd_bind_index_buffer(cmd, scene.indices.raw(), 0, vk::IndexType::UINT32);
        }
        let eye = frame.eye;
        for (i, d) in scene.draws.iter().enumerate() {
            let push = ShadePush {
                view_proj: frame.view_proj.to_cols_array_2d(),
                eye_object: [eye.x, eye.y, eye.z, i as f32],
                counts: [scene.light_count, scene.key_light_count, 0, 0],
            };
            self.pipeline.bind(cmd, Some(&self.set), &push, extent);
            unsafe { device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { device.cmd_end_rendering(cmd) };
        for image in self.colors() {
            ImageBarrier::new(image.raw(), color, &writes, &readers).record(device, cmd);
        }
    }
}
