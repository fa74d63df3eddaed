//! Forward-shading pass (`glsl/shade.vert`, `glsl/shade.frag`): every object rasterised from the
//! camera into a linear HDR target; translucent surfaces turn gathered exitance into radiance
//! through the BSSRDF's outgoing Fresnel lobe, every surface gets a GGX specular lobe per light,
//! opaque surfaces Lambert, all shadowed by the shadow maps.
//!
//! Vertex input: binding 0 = `records::Vertex`, binding 1 = exitance, binding 2 = cached
//! environment irradiance (vec4 per vertex each).
//! Bindings: 0 = objects, 1 = lights, 2 = shadow maps. Push: `ShadePush`.

use super::records::Vertex;
use super::shadow::DrawRange;
use super::shadow::ShadowPass;
use crate::gpu::{
    Binding, BindingKind, Buffer, DescriptorSet, Gpu, GpuResult, GraphicsDesc, GraphicsPipeline, Image, ImageDesc,
    image_barrier,
};
use ash::vk;
use std::sync::Arc;

pub const HDR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Pixel gather only: world position and translucent object of each pixel.
pub const SURFACE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The push block of shade.vert/shade.frag.
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

impl ShadePass {
    pub fn new(
        gpu: &Arc<Gpu>,
        width: u32,
        height: u32,
        objects: &Buffer,
        lights: &Buffer,
        shadow: &ShadowPass,
        pixel_gather: bool,
    ) -> GpuResult<ShadePass> {
        let fragment = if pixel_gather { "shade_pixel.frag" } else { "shade.frag" };
        let mut desc = GraphicsDesc::new("shade.vert", Some(fragment));
        desc.bindings = vec![BindingKind::StorageBuffer, BindingKind::StorageBuffer, BindingKind::CombinedImageSampler];
        desc.push_bytes = std::mem::size_of::<ShadePush>() as u32;
        desc.vertex_bindings = vec![
            Vertex::binding(),
            vk::VertexInputBindingDescription { binding: 1, stride: 16, input_rate: vk::VertexInputRate::VERTEX },
            vk::VertexInputBindingDescription { binding: 2, stride: 16, input_rate: vk::VertexInputRate::VERTEX },
        ];
        desc.vertex_attributes = vec![
            Vertex::position_attribute(),
            Vertex::normal_attribute(),
            vk::VertexInputAttributeDescription {
                location: 2,
                binding: 1,
                format: vk::Format::R32G32B32A32_SFLOAT,
                offset: 0,
            },
            vk::VertexInputAttributeDescription {
                location: 3,
                binding: 2,
                format: vk::Format::R32G32B32A32_SFLOAT,
                offset: 0,
            },
        ];
        desc.color_formats = if pixel_gather { vec![HDR_FORMAT, SURFACE_FORMAT] } else { vec![HDR_FORMAT] };
        desc.depth_format = Some(DEPTH_FORMAT);
        let pipeline = GraphicsPipeline::new(gpu, &desc)?;
        let set = pipeline.descriptor_set(&[Binding::Buffer(objects), Binding::Buffer(lights), shadow.binding()])?;
        let hdr = Image::new(
            gpu,
            &ImageDesc::new(
                "hdr radiance",
                width,
                height,
                HDR_FORMAT,
                // STORAGE: the pixel gather adds its exitance in place.
                vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED | vk::ImageUsageFlags::STORAGE,
            ),
        )?;
        let surface = pixel_gather
            .then(|| {
                Image::new(
                    gpu,
                    &ImageDesc::new(
                        "surface",
                        width,
                        height,
                        SURFACE_FORMAT,
                        vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::SAMPLED,
                    ),
                )
            })
            .transpose()?;
        let depth = Image::new(
            gpu,
            &ImageDesc::new("camera depth", width, height, DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )?;
        Ok(ShadePass { pipeline, set, hdr, depth, surface })
    }

    pub fn hdr(&self) -> &Image {
        &self.hdr
    }
    /// The surface image (pixel gather only), SHADER_READ_ONLY_OPTIMAL after the pass.
    pub fn surface(&self) -> Option<&Image> {
        self.surface.as_ref()
    }

    /// Record: clear to `background`, draw every object (`draws[i]` is object i), leave the HDR
    /// image in SHADER_READ_ONLY_OPTIMAL for the tone map.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        gpu: &Gpu,
        cmd: vk::CommandBuffer,
        vertices: &Buffer,
        exitance: &Buffer,
        environment_irradiance: &Buffer,
        indices: &Buffer,
        draws: &[DrawRange],
        push: ShadePush,
        background: [f32; 3],
    ) {
        let device = gpu.device();
        image_barrier(
            device,
            cmd,
            self.hdr.raw(),
            vk::ImageAspectFlags::COLOR,
            (vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL),
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_SAMPLED_READ),
            (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE),
        );
        image_barrier(
            device,
            cmd,
            self.depth.raw(),
            vk::ImageAspectFlags::DEPTH,
            (vk::ImageLayout::UNDEFINED, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL),
            (vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS, vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE),
            (
                vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
                vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
            ),
        );
        if let Some(surface) = &self.surface {
            image_barrier(
                device,
                cmd,
                surface.raw(),
                vk::ImageAspectFlags::COLOR,
                (vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL),
                (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_SAMPLED_READ),
                (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE),
            );
        }
        let mut colors = vec![
            vk::RenderingAttachmentInfo::default()
                .image_view(self.hdr.view())
                .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::STORE)
                .clear_value(vk::ClearValue {
                    color: vk::ClearColorValue { float32: [background[0], background[1], background[2], 1.0] },
                }),
        ];
        if let Some(surface) = &self.surface {
            colors.push(
                vk::RenderingAttachmentInfo::default()
                    .image_view(surface.view())
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(vk::AttachmentLoadOp::CLEAR)
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } }),
            );
        }
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
            device.cmd_bind_vertex_buffers(
                cmd,
                0,
                &[vertices.raw(), exitance.raw(), environment_irradiance.raw()],
                &[0, 0, 0],
            );
            device.cmd_bind_index_buffer(cmd, indices.raw(), 0, vk::IndexType::UINT32);
        }
        for (i, d) in draws.iter().enumerate() {
            let mut p = push;
            p.eye_object[3] = i as f32;
            self.pipeline.bind(cmd, Some(&self.set), bytemuck::bytes_of(&p), extent);
            unsafe { device.cmd_draw_indexed(cmd, d.index_count, 1, d.first_index, d.vertex_offset, 0) };
        }
        unsafe { device.cmd_end_rendering(cmd) };
        image_barrier(
            device,
            cmd,
            self.hdr.raw(),
            vk::ImageAspectFlags::COLOR,
            (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
            (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE),
            (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_SAMPLED_READ),
        );
        if let Some(surface) = &self.surface {
            image_barrier(
                device,
                cmd,
                surface.raw(),
                vk::ImageAspectFlags::COLOR,
                (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
                (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE),
                (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_SAMPLED_READ),
            );
        }
    }
}
