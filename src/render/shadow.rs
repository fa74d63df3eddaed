//! Shadow-map pass (`glsl/shadow.vert`): depth of the shadow casters from each shadow-casting
//! light into one layer of a D16 array image, which the splat and shade passes sample with a
//! compare sampler (percentage-closer filtering, `glsl/common/lights.glsl`).
//!
//! Vertex input: binding 0 = `records::Vertex`. Push: `ShadowPush`.

use super::graph::{Resource, Use, overwrite, read, write};
use super::error::RenderError;
use super::pass::{FrameInputs, PassContext, Rebuild, RegisteredPass, RenderPass};
use super::records::Vertex;
use super::cull::culled_faces;
use super::target::DepthConvention;
use super::targets::SHADOW_FORMAT;
use crate::gpu::{Access, Gpu, GpuResult, GraphicsDesc, GraphicsPipeline};
use ash::vk;
use std::sync::Arc;

/// Format of the shadow maps (`targets::SHADOW_FORMAT`).
pub const DEPTH_FORMAT: vk::Format = SHADOW_FORMAT;

/// `ShadowPush` in glsl/shadow.vert.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct ShadowPush {
    /// World -> the light's clip space, column-major.
    pub light_matrix: [[f32; 4]; 4],
    /// x: the layer; yzw: unused.
    pub layer: [u32; 4],
}

/// The shadow-map pass: a depth-only graphics pipeline (glsl/shadow.vert) drawing the casters
/// into the frame targets' shadow-map array (`FrameTargets::shadow_maps`), one layer per map.
pub struct ShadowPass {
    pipeline: GraphicsPipeline,
    layers: u32,
}

impl ShadowPass {
    /// The pipeline for `layers` shadow maps.
    pub fn new(gpu: &Arc<Gpu>, layers: u32) -> GpuResult<ShadowPass> {
        let mut desc = GraphicsDesc::new("shadow.vert", None);
        desc.vertex_bindings = vec![Vertex::binding()];
        desc.vertex_attributes = vec![Vertex::position_attribute()];
        desc.depth_format = Some(DEPTH_FORMAT);
        // Slope-scaled bias against acne on surfaces grazing the light.
        desc.depth_bias = Some((1.0, 1.75));
        desc.dynamic_cull = true;
        Ok(ShadowPass { pipeline: GraphicsPipeline::new(gpu, &desc)?, layers })
    }
}

impl RenderPass for ShadowPass {
    /// A full redraw overwrites the maps; redrawing some layers keeps the others.
    fn uses(&self, frame: &FrameInputs) -> Vec<Use> {
        let maps = match frame.shadow_layers {
            None => overwrite(Resource::ShadowMaps, Access::DepthAttachmentReadWrite),
            Some(_) => write(Resource::ShadowMaps, Access::DepthAttachmentReadWrite),
        };
        vec![read(Resource::Vertices, Access::VertexAttributeRead), maps]
    }

    /// Render every layer (`light_matrices[i]` into layer i), or only `frame.shadow_layers` (the
    /// others keep their contents).
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let device = frame.gpu.device();
        let scene = frame.scene;
        let only = frame.shadow_layers;
        let maps = &frame.targets.shadow_maps;
        let extent = maps.extent();
        // One layered render: each light's draws pick its layer with gl_Layer (shadow.vert). A
        // full redraw clears every layer on load; a partial one loads and clears only its layers.
        let attachment = vk::RenderingAttachmentInfo::default()
            .image_view(maps.view())
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
            let light_matrix = glam::Mat4::from_cols_array_2d(matrix);
            self.pipeline.bind(cmd, None, &push, extent);
            // SAFETY: `cmd` is recording inside the render begun above; the scene's vertex and
            // index buffers were made with VERTEX_BUFFER / INDEX_BUFFER usage and `frame` borrows
            // them.
            unsafe {
                device.cmd_bind_vertex_buffers(cmd, 0, &[scene.buffers.vertices.raw()], &[0]);
                device.cmd_bind_index_buffer(cmd, scene.indices.raw(), 0, vk::IndexType::UINT32);
            }
            for &(object, level) in &scene.casters {
                let level = scene.level(object, level);
                // The nearest surface to the light is a face towards it: the map is the same
                // without the hidden ones but for depth ties at the casters' silhouettes.
                let hidden = culled_faces(frame.plan, &level, light_matrix, DepthConvention::Standard);
                self.pipeline.set_cull(cmd, hidden);
                let d = level.draw;
                self.pipeline.draw_indexed(cmd, d.index_count, d.first_index, d.vertex_offset);
            }
        }
        // SAFETY: ends the render begun at the top of this function, in the same `cmd`.
        unsafe { device.cmd_end_rendering(cmd) };
    }
}

impl RegisteredPass for ShadowPass {
    // It binds no scene buffer: its draws take the vertex and index buffers each frame.
    const REBUILT_ON: &'static [Rebuild] = &[];

    fn build(context: &PassContext) -> Result<Option<Self>, RenderError> {
        Ok(Some(ShadowPass::new(context.gpu, context.scene.shadow_layers)?))
    }
}
