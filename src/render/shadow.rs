//! Shadow-map pass (`glsl/shadow.vert`): depth of the shadow casters from each shadow-casting
//! light into one layer of a D16 array image, which the splat and shade passes sample with a
//! compare sampler (percentage-closer filtering, `glsl/common/lights.glsl`).
//!
//! Vertex input: binding 0 = `records::Vertex`. Push: `ShadowPush`.

use super::pass::{FrameInputs, RenderPass};
use super::records::Vertex;
use crate::gpu::{
    Access, Binding, Gpu, GpuResult, GraphicsDesc, GraphicsPipeline, Image, ImageBarrier, ImageDesc, Sampler,
};
use ash::vk;
use std::sync::Arc;

/// Format of the shadow maps: 16-bit depth, sampled through a compare sampler.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D16_UNORM;

/// `ShadowPush` in glsl/shadow.vert.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowPush {
    /// World -> the light's clip space, column-major.
    pub light_matrix: [[f32; 4]; 4],
    /// x: the layer; yzw: unused.
    pub layer: [u32; 4],
}

/// Who reads the maps between redraws.
const READERS: [Access; 2] = [Access::FragmentSampledRead, Access::ComputeSampledRead];

/// The shadow-map pass: a depth-only graphics pipeline (glsl/shadow.vert), the D16 array image with
/// one layer per shadow map, and its compare sampler. Between redraws the maps stay in
/// SHADER_READ_ONLY_OPTIMAL, readable by fragment and compute shaders.
pub struct ShadowPass {
    pipeline: GraphicsPipeline,
    maps: Image,
    sampler: Sampler,
    layers: u32,
}

impl ShadowPass {
    /// `layers` shadow maps of `size`^2 texels (at least one layer, so the array can always be
    /// bound even when nothing casts a shadow).
    pub fn new(gpu: &Arc<Gpu>, size: u32, layers: u32) -> GpuResult<ShadowPass> {
        let mut desc = GraphicsDesc::new("shadow.vert", None);
        desc.vertex_bindings = vec![Vertex::binding()];
        desc.vertex_attributes = vec![Vertex::position_attribute()];
        desc.depth_format = Some(DEPTH_FORMAT);
        // Slope-scaled bias against acne on surfaces grazing the light.
        desc.depth_bias = Some((1.0, 1.75));
        let pipeline = GraphicsPipeline::new(gpu, &desc)?;
        let maps = Image::new(
            gpu,
            &ImageDesc::new(
                "shadow maps",
                size,
                size,
                DEPTH_FORMAT,
                vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT
                    | vk::ImageUsageFlags::SAMPLED
                    | vk::ImageUsageFlags::TRANSFER_DST,
            )
            .layers(layers.max(1))
            .array_view(),
        )?;
        let sampler = Sampler::shadow(gpu, DEPTH_FORMAT)?;
        // Start cleared to the far plane (everything lit) and readable, so the passes that sample
        // the maps are valid even when the plan never renders them (no shadow caster).
        let device = gpu.device();
        let depth = vk::ImageAspectFlags::DEPTH;
        gpu.one_shot("shadow map init", |cmd| {
            ImageBarrier::new(maps.raw(), depth, &[Access::Nothing], &[Access::TransferWrite]).record(device, cmd);
            let range = [vk::ImageSubresourceRange::default()
                .aspect_mask(vk::ImageAspectFlags::DEPTH)
                .level_count(1)
                .layer_count(vk::REMAINING_ARRAY_LAYERS)];
            let far = vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 };
            // SAFETY: the image is in TRANSFER_DST_OPTIMAL and has TRANSFER_DST usage.
            unsafe {
                device.cmd_clear_depth_stencil_image(
                    cmd,
                    maps.raw(),
                    vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                    &far,
                    &range,
                )
            };
            ImageBarrier::new(maps.raw(), depth, &[Access::TransferWrite], &READERS).record(device, cmd);
        })?;
        Ok(ShadowPass { pipeline, maps, sampler, layers })
    }

    /// The maps with their compare sampler, as the passes that read them bind them.
    pub fn binding(&self) -> Binding<'_> {
        Binding::Image {
            view: self.maps.view(),
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            sampler: self.sampler.raw(),
        }
    }
}

impl RenderPass for ShadowPass {
    /// Render every layer (`light_matrices[i]` into layer i), or only `frame.shadow_layers` (the
    /// others keep their contents), then leave the maps readable by compute and fragment shaders.
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let device = frame.gpu.device();
        let scene = frame.scene;
        let only = frame.shadow_layers;
        // Redrawing some layers keeps the others: their contents must survive the transition.
        let depth = vk::ImageAspectFlags::DEPTH;
        ImageBarrier::new(self.maps.raw(), depth, &READERS, &[Access::DepthAttachmentReadWrite])
            .discard(only.is_none())
            .record(device, cmd);
        let extent = self.maps.extent();
        // One layered render: each light's draws pick its layer with gl_Layer (shadow.vert). A
        // full redraw clears every layer on load; a partial one loads and clears only its layers.
        let attachment = vk::RenderingAttachmentInfo::default()
            .image_view(self.maps.view())
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(if only.is_some() { vk::AttachmentLoadOp::LOAD } else { vk::AttachmentLoadOp::CLEAR })
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(self.layers.max(1))
            .depth_attachment(&attachment);
        // SAFETY: `cmd` is recording; the array view is a depth attachment in the right layout.
        unsafe { device.cmd_begin_rendering(cmd, &info) };
        if let Some(layers) = only {
            let clear = [vk::ClearAttachment {
                aspect_mask: vk::ImageAspectFlags::DEPTH,
                color_attachment: 0,
                clear_value: vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } },
            }];
            let rects: Vec<_> = layers
                .iter()
                .map(|&l| vk::ClearRect {
                    rect: vk::Rect2D { offset: vk::Offset2D::default(), extent },
                    base_array_layer: l,
                    layer_count: 1,
                })
                .collect();
            // SAFETY: inside the render; every rect lies in the attachment's extent and layers.
            unsafe { device.cmd_clear_attachments(cmd, &clear, &rects) };
        }
        let redraw = |layer: u32| only.is_none_or(|l| l.contains(&layer));
        for (layer, matrix) in scene.light_matrices.iter().enumerate().take(self.layers as usize) {
            if !redraw(layer as u32) {
                continue;
            }
            let push = ShadowPush { light_matrix: *matrix, layer: [layer as u32, 0, 0, 0] };
            self.pipeline.bind(cmd, None, &push, extent);
            unsafe {
                device.cmd_bind_vertex_buffers(cmd, 0, &[scene.vertices.raw()], &[0]);
                device.cmd_bind_index_buffer(cmd, scene.indices.raw(), 0, vk::IndexType::UINT32);
            }
            for &(object, level) in &scene.casters {
                let d = scene.level(object, level).draw;
                self.pipeline.draw_indexed(cmd, d.index_count, d.first_index, d.vertex_offset);
            }
        }
        unsafe { device.cmd_end_rendering(cmd) };
        ImageBarrier::new(self.maps.raw(), depth, &[Access::DepthAttachmentReadWrite], &READERS).record(device, cmd);
    }
}
