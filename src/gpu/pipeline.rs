//! Compute and graphics pipelines built from embedded SPIR-V, each with one descriptor set
//! (set 0) and an optional push-constant block visible to every stage. Bindings, push-block size
//! and workgroup size are reflected from the SPIR-V (`shaders::ShaderInterface`).

use super::context::Gpu;
use super::descriptor::{BindingKind, DescriptorSet, Named, SetInterface, create_set_layout};
use super::error::{GpuError, GpuResult, VkContext};
use super::shaders::{self, ShaderInterface};
use ash::vk;
use std::sync::Arc;

/// Set layout + pipeline layout, shared by both pipeline kinds.
struct Layout {
    gpu: Arc<Gpu>,
    set_layout: vk::DescriptorSetLayout,
    pipeline_layout: vk::PipelineLayout,
    kinds: Vec<Option<BindingKind>>,
    /// Each binding's GLSL name, as reflected (`ShaderInterface::names`).
    names: Vec<Option<String>>,
    /// The shader(s), for messages: "gather.comp", "shade.vert + shade.frag".
    shader: String,
    stages: vk::ShaderStageFlags,
    push_bytes: u32,
}

impl Layout {
    fn new(
        gpu: &Arc<Gpu>,
        shader: &str,
        interface: &ShaderInterface,
        stages: vk::ShaderStageFlags,
    ) -> GpuResult<Layout> {
        let (kinds, push_bytes) = (&interface.bindings, interface.push_bytes);
        let limit = gpu.properties().limits.max_push_constants_size;
        if !push_bytes.is_multiple_of(4) || push_bytes > limit {
            return Err(GpuError::PushConstants { bytes: push_bytes, limit });
        }
        let set_layout = create_set_layout(gpu, kinds, stages)?;
        let mut layout = Layout {
            gpu: gpu.clone(),
            set_layout,
            pipeline_layout: vk::PipelineLayout::null(),
            kinds: kinds.to_vec(),
            names: interface.names.clone(),
            shader: shader.to_string(),
            stages,
            push_bytes,
        };
        let ranges = [vk::PushConstantRange { stage_flags: stages, offset: 0, size: push_bytes }];
        let set_layouts = [set_layout];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_bytes > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        // SAFETY: valid create info; Drop destroys it.
        layout.pipeline_layout =
            unsafe { gpu.device().create_pipeline_layout(&info, None) }.vk("vkCreatePipelineLayout")?;
        Ok(layout)
    }

    /// A descriptor set for set 0, each entry checked against the reflected kind and name.
    fn descriptor_set(&self, bindings: &[Named<'_>]) -> GpuResult<DescriptorSet> {
        let interface = SetInterface { shader: &self.shader, kinds: &self.kinds, names: &self.names };
        DescriptorSet::new(&self.gpu, self.set_layout, &interface, bindings)
    }

    fn bind(&self, cmd: vk::CommandBuffer, point: vk::PipelineBindPoint, set: Option<&DescriptorSet>, push: &[u8]) {
        let device = self.gpu.device();
        // SAFETY: `cmd` is recording; set and push block match this layout (push length checked).
        unsafe {
            if let Some(set) = set {
                device.cmd_bind_descriptor_sets(cmd, point, self.pipeline_layout, 0, &[set.raw()], &[]);
            }
            if !push.is_empty() {
                device.cmd_push_constants(cmd, self.pipeline_layout, self.stages, 0, push);
            }
        }
    }

    /// The push bytes to record: the shader's block must have the Rust struct's size (a
    /// block the optimiser removed as unused takes nothing).
    fn check_push<'p>(&self, push: &'p [u8]) -> &'p [u8] {
        if self.push_bytes == 0 {
            return &[];
        }
        assert_eq!(push.len() as u32, self.push_bytes, "push-constant block size differs from the shader's");
        push
    }
}

impl Drop for Layout {
    fn drop(&mut self) {
        // SAFETY: pipelines using this layout are destroyed first (field order in their structs).
        unsafe {
            self.gpu.device().destroy_pipeline_layout(self.pipeline_layout, None);
            self.gpu.device().destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// A shader module that lives only while pipelines are created from it.
struct Module<'a> {
    gpu: &'a Gpu,
    raw: vk::ShaderModule,
}

impl<'a> Module<'a> {
    fn new(gpu: &'a Gpu, name: &str) -> GpuResult<Module<'a>> {
        let words = shaders::spirv(name)?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: `words` is SPIR-V compiled by glslang for Vulkan 1.2.
        let raw = unsafe { gpu.device().create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
        Ok(Module { gpu, raw })
    }
}

impl Drop for Module<'_> {
    fn drop(&mut self) {
        // SAFETY: a module may be destroyed once pipelines using it are created.
        unsafe { self.gpu.device().destroy_shader_module(self.raw, None) };
    }
}

/// A compute pipeline from one embedded shader, its set-0 layout, push-constant range and workgroup
/// size reflected from the SPIR-V. The pipeline is destroyed on Drop, before its layout (field
/// order); no pending submission may use it then.
pub struct ComputePipeline {
    pipeline: vk::Pipeline,
    layout: Layout,
    name: String,
    local_size: [u32; 3],
}

impl ComputePipeline {
    /// `shader` is a path under `glsl/` ("smoke.comp"); its interface is reflected.
    pub fn new(gpu: &Arc<Gpu>, shader: &str) -> GpuResult<ComputePipeline> {
        Self::specialized(gpu, shader, &[])
    }

    /// [`ComputePipeline::new`] with specialization constants: `constant_id` i takes
    /// `constants[i]` (a bool is 0 or 1), so a choice fixed for the pipeline's life is no branch
    /// at run time.
    pub fn specialized(gpu: &Arc<Gpu>, shader: &str, constants: &[u32]) -> GpuResult<ComputePipeline> {
        let interface = ShaderInterface::of(shader)?;
        let layout = Layout::new(gpu, shader, &interface, vk::ShaderStageFlags::COMPUTE)?;
        let module = Module::new(gpu, shader)?;
        let entries: Vec<_> = (0..constants.len() as u32)
            .map(|i| vk::SpecializationMapEntry { constant_id: i, offset: 4 * i, size: 4 })
            .collect();
        let specialization =
            vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(constants));
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.raw)
            .name(c"main")
            .specialization_info(&specialization);
        let info = [vk::ComputePipelineCreateInfo::default().stage(stage).layout(layout.pipeline_layout)];
        let cache = gpu.pipeline_cache.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: valid create info referencing live module and layout; the cache is locked.
        let pipeline = unsafe { gpu.device().create_compute_pipelines(*cache, &info, None) }
            .map_err(|(_, result)| GpuError::Vk { what: "vkCreateComputePipelines", result })?[0];
        Ok(ComputePipeline { pipeline, layout, name: shader.to_string(), local_size: interface.local_size })
    }

    /// Workgroups that cover `threads` invocations in each dimension.
    pub fn groups(&self, threads: [u32; 3]) -> [u32; 3] {
        [0, 1, 2].map(|i| threads[i].div_ceil(self.local_size[i]))
    }

    /// An error naming `what` when `threads` needs more workgroups than the device dispatches.
    pub fn check_threads(&self, threads: [u32; 3], what: &str) -> GpuResult<()> {
        let max = self.layout.gpu.properties().limits.max_compute_work_group_count;
        let groups = self.groups(threads);
        match (0..3).find(|&i| groups[i] > max[i]) {
            Some(i) => Err(GpuError::Limit {
                what: what.to_string(),
                value: threads[i] as u64,
                limit: max[i] as u64 * self.local_size[i] as u64,
                name: "maxComputeWorkGroupCount x local size",
            }),
            None => Ok(()),
        }
    }

    /// A descriptor set for this pipeline's set 0, binding i being `bindings[i]`, whose name must
    /// be the GLSL's at binding i (`GpuError::BindingMismatch`).
    pub fn descriptor_set(&self, bindings: &[Named<'_>]) -> GpuResult<DescriptorSet> {
        self.layout.descriptor_set(bindings)
    }

    /// Record a dispatch of enough workgroups for `threads` invocations, with push block `push`.
    pub fn dispatch<P: bytemuck::Pod>(&self, cmd: vk::CommandBuffer, set: &DescriptorSet, push: &P, threads: [u32; 3]) {
        if threads.contains(&0) {
            return;
        }
        let push = self.layout.check_push(bytemuck::bytes_of(push));
        let device = self.layout.gpu.device();
        let groups = self.groups(threads);
        // SAFETY: `cmd` is recording, outside a render pass.
        unsafe { device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::COMPUTE, self.pipeline) };
        self.layout.bind(cmd, vk::PipelineBindPoint::COMPUTE, Some(set), push);
        // SAFETY: `cmd` is recording outside a render pass, with this compute pipeline, its set
        // and its push block bound just above; every group count is at least 1.
        unsafe { device.cmd_dispatch(cmd, groups[0], groups[1], groups[2]) };
        self.layout.gpu.count_recorded(&self.name);
    }

    /// The shader path it was built from, e.g. "splat.comp".
    pub fn name(&self) -> &str {
        &self.name
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses it (every submission is waited on).
        unsafe { self.layout.gpu.device().destroy_pipeline(self.pipeline, None) };
    }
}

/// What a graphics pipeline draws into and how (dynamic rendering, no render-pass objects).
#[derive(Clone, Debug)]
pub struct GraphicsDesc {
    /// Vertex shader path under `glsl/`.
    pub vertex: String,
    /// `None` for depth-only passes (shadow maps).
    pub fragment: Option<String>,
    /// Vertex buffer bindings: binding number, stride and input rate.
    pub vertex_bindings: Vec<vk::VertexInputBindingDescription>,
    /// Vertex shader inputs: location, binding, format and offset of each.
    pub vertex_attributes: Vec<vk::VertexInputAttributeDescription>,
    /// Formats of the colour attachments, in attachment order; empty for depth-only passes.
    pub color_formats: Vec<vk::Format>,
    /// Format of the depth attachment; with one, depth test (`depth_compare`) and depth writes
    /// are on.
    pub depth_format: Option<vk::Format>,
    /// The depth test's comparison, with a depth attachment: LESS_OR_EQUAL unless set (0 near,
    /// 1 far); a reversed-Z target's is GREATER_OR_EQUAL.
    pub depth_compare: vk::CompareOp,
    /// Samples per pixel of the attachments (rasterizationSamples); TYPE_1 unless set.
    pub samples: vk::SampleCountFlags,
    /// Faces to cull (counter-clockwise is front); NONE unless set. With `dynamic_cull`, the
    /// faces culled until `GraphicsPipeline::set_cull` says otherwise.
    pub cull: vk::CullModeFlags,
    /// The faces culled are dynamic state (Vulkan 1.3 core, no feature to enable):
    /// `GraphicsPipeline::set_cull` picks them per draw, so that one pipeline serves draws that
    /// cull differently.
    pub dynamic_cull: bool,
    /// Constant and slope depth bias, for shadow maps.
    pub depth_bias: Option<(f32, f32)>,
    /// Specialization constants of both stages: `constant_id` i takes value i (a bool is 0 or
    /// 1). The driver folds them before compiling, so a branch on one costs nothing, where a
    /// branch on a push constant is taken lane by lane on a CPU driver (both sides run).
    pub specialization: Vec<u32>,
}

impl GraphicsDesc {
    /// The two shaders and nothing else: no vertex input, no attachments, no culling, no depth
    /// bias.
    pub fn new(vertex: &str, fragment: Option<&str>) -> Self {
        Self {
            vertex: vertex.into(),
            fragment: fragment.map(Into::into),
            vertex_bindings: Vec::new(),
            vertex_attributes: Vec::new(),
            color_formats: Vec::new(),
            depth_format: None,
            depth_compare: vk::CompareOp::LESS_OR_EQUAL,
            samples: vk::SampleCountFlags::TYPE_1,
            cull: vk::CullModeFlags::NONE,
            dynamic_cull: false,
            depth_bias: None,
            specialization: Vec::new(),
        }
    }
}

/// A graphics pipeline for dynamic rendering (no render-pass objects): triangle lists, dynamic
/// viewport and scissor, one descriptor set and one push-constant block shared by the vertex and
/// fragment stages, reflected from their SPIR-V. Destroyed on Drop before its layout; no pending
/// submission may use it then.
pub struct GraphicsPipeline {
    pipeline: vk::Pipeline,
    layout: Layout,
    /// The vertex shader's path, which names its draws in `Gpu::recorded`.
    name: String,
    /// With a dynamic cull mode (`GraphicsDesc::dynamic_cull`), the faces `bind_area` culls.
    cull: Option<vk::CullModeFlags>,
}

impl GraphicsPipeline {
    /// Build the pipeline `desc` describes; the layout is the union of both stages' reflected
    /// interfaces (`ShaderInterface::merge`).
    pub fn new(gpu: &Arc<Gpu>, desc: &GraphicsDesc) -> GpuResult<GraphicsPipeline> {
        let stages_flags = vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT;
        let mut interfaces = vec![ShaderInterface::of(&desc.vertex)?];
        if let Some(f) = &desc.fragment {
            interfaces.push(ShaderInterface::of(f)?);
        }
        let shader = match &desc.fragment {
            Some(f) => format!("{} + {f}", desc.vertex),
            None => desc.vertex.clone(),
        };
        let layout = Layout::new(gpu, &shader, &ShaderInterface::merge(&interfaces)?, stages_flags)?;
        let vertex = Module::new(gpu, &desc.vertex)?;
        let fragment = desc.fragment.as_deref().map(|f| Module::new(gpu, f)).transpose()?;
        let entries: Vec<_> = (0..desc.specialization.len() as u32)
            .map(|i| vk::SpecializationMapEntry { constant_id: i, offset: 4 * i, size: 4 })
            .collect();
        let specialization =
            vk::SpecializationInfo::default().map_entries(&entries).data(bytemuck::cast_slice(&desc.specialization));
        let stage = |flags, module| {
            vk::PipelineShaderStageCreateInfo::default()
                .stage(flags)
                .module(module)
                .name(c"main")
                .specialization_info(&specialization)
        };
        let mut stages = vec![stage(vk::ShaderStageFlags::VERTEX, vertex.raw)];
        if let Some(f) = &fragment {
            stages.push(stage(vk::ShaderStageFlags::FRAGMENT, f.raw));
        }
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&desc.vertex_bindings)
            .vertex_attribute_descriptions(&desc.vertex_attributes);
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let mut raster = vk::PipelineRasterizationStateCreateInfo::default()
            .polygon_mode(vk::PolygonMode::FILL)
            .cull_mode(desc.cull)
            .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
            .line_width(1.0);
        if let Some((constant, slope)) = desc.depth_bias {
            raster = raster.depth_bias_enable(true).depth_bias_constant_factor(constant).depth_bias_slope_factor(slope);
        }
        let multisample = vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(desc.samples);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(desc.depth_format.is_some())
            .depth_write_enable(desc.depth_format.is_some())
            .depth_compare_op(desc.depth_compare);
        let attachments: Vec<_> = desc
            .color_formats
            .iter()
            .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
            .collect();
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
        let mut dynamic_states = vec![vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        if desc.dynamic_cull {
            dynamic_states.push(vk::DynamicState::CULL_MODE);
        }
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&desc.color_formats)
            .depth_attachment_format(desc.depth_format.unwrap_or(vk::Format::UNDEFINED));
        let info = [vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout.pipeline_layout)
            .push_next(&mut rendering)];
        let cache = gpu.pipeline_cache.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: every pointer refers to locals alive for the call; dynamic rendering is enabled.
        let pipeline = unsafe { gpu.device().create_graphics_pipelines(*cache, &info, None) }
            .map_err(|(_, result)| GpuError::Vk { what: "vkCreateGraphicsPipelines", result })?[0];
        let cull = desc.dynamic_cull.then_some(desc.cull);
        Ok(GraphicsPipeline { pipeline, layout, name: desc.vertex.clone(), cull })
    }

    /// A descriptor set for this pipeline's set 0, binding i being `bindings[i]`, whose name must
    /// be the GLSL's at binding i (`GpuError::BindingMismatch`).
    pub fn descriptor_set(&self, bindings: &[Named<'_>]) -> GpuResult<DescriptorSet> {
        self.layout.descriptor_set(bindings)
    }

    /// Bind the pipeline, its set and push block, and set a full-extent viewport and scissor.
    /// Call inside `cmd_begin_rendering`.
    pub fn bind<P: bytemuck::Pod>(
        &self,
        cmd: vk::CommandBuffer,
        set: Option<&DescriptorSet>,
        push: &P,
        extent: vk::Extent2D,
    ) {
        self.bind_area(cmd, set, push, vk::Rect2D { offset: vk::Offset2D::default(), extent });
    }

    /// As `bind`, with the viewport and scissor over `area` (a sub-rectangle of the attachments,
    /// the render area).
    pub fn bind_area<P: bytemuck::Pod>(
        &self,
        cmd: vk::CommandBuffer,
        set: Option<&DescriptorSet>,
        push: &P,
        area: vk::Rect2D,
    ) {
        let push = self.layout.check_push(bytemuck::bytes_of(push));
        let device = self.layout.gpu.device();
        let viewport = vk::Viewport {
            x: area.offset.x as f32,
            y: area.offset.y as f32,
            width: area.extent.width as f32,
            height: area.extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: `cmd` is recording inside dynamic rendering with matching attachment formats.
        unsafe {
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.pipeline);
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_set_scissor(cmd, 0, &[area]);
            if let Some(cull) = self.cull {
                device.cmd_set_cull_mode(cmd, cull);
            }
        }
        self.layout.bind(cmd, vk::PipelineBindPoint::GRAPHICS, set, push);
    }

    /// Cull `faces` in the draws that follow, with this pipeline bound (`bind_area`). Returns
    /// false, and records nothing, for a pipeline made without `GraphicsDesc::dynamic_cull`,
    /// whose faces are fixed.
    pub fn set_cull(&self, cmd: vk::CommandBuffer, faces: vk::CullModeFlags) -> bool {
        if self.cull.is_none() {
            return false;
        }
        // SAFETY: `cmd` is recording with this pipeline bound; its cull mode is dynamic state.
        unsafe { self.layout.gpu.device().cmd_set_cull_mode(cmd, faces) };
        true
    }

    /// Record an indexed draw with this pipeline bound (`bind`), counted in `Gpu::recorded`.
    pub fn draw_indexed(&self, cmd: vk::CommandBuffer, index_count: u32, first_index: u32, vertex_offset: i32) {
        // SAFETY: `cmd` is recording inside dynamic rendering with this pipeline and its vertex
        // and index buffers bound.
        unsafe { self.layout.gpu.device().cmd_draw_indexed(cmd, index_count, 1, first_index, vertex_offset, 0) };
        self.layout.gpu.count_recorded(&self.name);
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        // SAFETY: as for ComputePipeline.
        unsafe { self.layout.gpu.device().destroy_pipeline(self.pipeline, None) };
    }
}
