//! The viewer's one pass of its own: rings over the swapchain image where the lights can be
//! grabbed, while the user picks one (glsl/examples/viewer_present.frag). translucent draws the
//! image itself in display values (`Output::Display`), so there is no tone-map pass here.

use super::host::Host;
use anyhow::Result;
use ash::vk;

/// The most light markers the pass draws (`MAX_MARKERS` in viewer_present.frag).
pub const MAX_MARKERS: usize = 6;

/// `PresentPush` in glsl/examples/viewer_present.frag.
#[repr(C)]
#[derive(Clone, Copy, Default, bytemuck::Pod, bytemuck::Zeroable)]
struct PresentPush {
    markers: u32,
    pad: [u32; 3],
    marker: [[f32; 4]; MAX_MARKERS],
}

/// A ring drawn over the image where a light can be grabbed.
#[derive(Clone, Copy, Debug)]
pub struct Marker {
    /// Centre in pixels.
    pub at: [f32; 2],
    /// Radius in pixels.
    pub radius: f32,
    /// Whether it is the light being dragged (drawn in another colour).
    pub dragged: bool,
}

/// The rings' pipeline.
pub struct Present {
    device: ash::Device,
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
    format: vk::Format,
}

impl Present {
    /// The pass for swapchain images of `format`.
    pub fn new(host: &Host, format: vk::Format) -> Result<Present> {
        let device = &host.device;
        let size = size_of::<PresentPush>() as u32;
        let push = [vk::PushConstantRange { stage_flags: vk::ShaderStageFlags::FRAGMENT, offset: 0, size }];
        // SAFETY: valid create info; destroyed in `drop`.
        let layout = unsafe {
            device.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&push), None)
        }?;
        let mut present = Present { device: device.clone(), layout, pipeline: vk::Pipeline::null(), format };
        present.pipeline = pipeline(device, layout, format)?;
        Ok(present)
    }

    /// The swapchain image format this pass draws.
    pub fn format(&self) -> vk::Format {
        self.format
    }

    /// Draw `markers` (the first `MAX_MARKERS`) over `target` (in COLOR_ATTACHMENT_OPTIMAL,
    /// kept) of `extent`; nothing without markers.
    pub fn record(&self, cmd: vk::CommandBuffer, target: vk::ImageView, extent: vk::Extent2D, markers: &[Marker]) {
        if markers.is_empty() {
            return;
        }
        let mut push = PresentPush { markers: markers.len().min(MAX_MARKERS) as u32, ..Default::default() };
        for (slot, m) in push.marker.iter_mut().zip(markers) {
            *slot = [m.at[0], m.at[1], m.radius, f32::from(u8::from(m.dragged))];
        }
        let colors = [vk::RenderingAttachmentInfo::default()
            .image_view(target)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::LOAD)
            .store_op(vk::AttachmentStoreOp::STORE)];
        let rendering =
            vk::RenderingInfo::default().render_area(extent.into()).layer_count(1).color_attachments(&colors);
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let device = &self.device;
        // SAFETY: `cmd` is recording outside any rendering; the target is a live view.
        unsafe {
            device.cmd_begin_rendering(cmd, &rendering);
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
            device.cmd_push_constants(cmd, self.layout, vk::ShaderStageFlags::FRAGMENT, 0, bytemuck::bytes_of(&push));
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_set_scissor(cmd, 0, &[extent.into()]);
            // translucent leaves the cull mode as its last draw set it (docs/GPU.md).
            device.cmd_set_cull_mode(cmd, vk::CullModeFlags::NONE);
            device.cmd_draw(cmd, 3, 1, 0, 0);
            device.cmd_end_rendering(cmd);
        }
    }
}

impl Drop for Present {
    fn drop(&mut self) {
        // SAFETY: the viewer waits for the device to be idle before dropping the pass.
        unsafe {
            self.device.destroy_pipeline(self.pipeline, None);
            self.device.destroy_pipeline_layout(self.layout, None);
        }
    }
}

/// The graphics pipeline: no vertex input, no depth, dynamic viewport, scissor and cull mode.
fn pipeline(device: &ash::Device, layout: vk::PipelineLayout, format: vk::Format) -> Result<vk::Pipeline> {
    let module = |name: &str| -> Result<vk::ShaderModule> {
        let words = translucent::gpu::shaders::spirv(name)?;
        // SAFETY: SPIR-V compiled by glslang in build.rs; destroyed below.
        Ok(unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }?)
    };
    let (vert, frag) = (module("examples/viewer_present.vert")?, module("examples/viewer_present.frag")?);
    let stages = [
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vert).name(c"main"),
        vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::FRAGMENT).module(frag).name(c"main"),
    ];
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
    let raster =
        vk::PipelineRasterizationStateCreateInfo::default().polygon_mode(vk::PolygonMode::FILL).line_width(1.0);
    let multisample =
        vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let blend_attachments =
        [vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)];
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR, vk::DynamicState::CULL_MODE];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let formats = [format];
    let mut rendering = vk::PipelineRenderingCreateInfo::default().color_attachment_formats(&formats);
    let info = [vk::GraphicsPipelineCreateInfo::default()
        .stages(&stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering)];
    // SAFETY: valid create infos; the modules are destroyed once the pipeline exists.
    let pipeline = unsafe {
        let made = device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None);
        device.destroy_shader_module(vert, None);
        device.destroy_shader_module(frag, None);
        made.map_err(|(_, e)| e)?[0]
    };
    Ok(pipeline)
}
