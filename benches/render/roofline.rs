//! The frame's roofline: what the device takes for the same work done the plainest way, timed in
//! the same run as the renderer's frames, so each pass can be read as a ratio to its yardstick.
//!
//! - raster: the shading pass's geometry (the renderer's own vertex and index buffers, each
//!   object at the level the plan draws it, the faces it culls culled) into targets of the same formats and size, with a
//!   one-interpolant vertex stage and a fragment stage that writes the normal
//!   (glsl/bench/raster_trivial.*);
//! - shadow: the shadow casters at their caster levels (the faces the shadow pass culls culled),
//!   depth-only into one map of the scene's
//!   size and format, no bias (glsl/bench/depth_only.vert): what a light frame redraws;
//! - tone map: the HDR image texel by texel into packed RGBA8 with a clamp
//!   (glsl/bench/tonemap_minimal.comp);
//! - submission: an empty command buffer, submitted and waited for.
//!
//! Not part of the roofline, beside it: deferred shading, the same drawn geometry into a G-buffer
//! of the shading pass's four interpolants (glsl/bench/raster_gbuffer.frag), then the shading
//! pass's own arithmetic over its pixels in a compute pass (glsl/bench/shade_compute.comp), which
//! says whether llvmpipe shades cheaper in full SIMD lanes than in fragment blocks.
//!
//! The naive gather (glsl/bench/gather_naive.comp) is the gather's yardstick, measured in
//! render.rs. Each part here is timed by timestamps inside one submission, as the frame is.

use ash::vk;
use std::sync::Arc;
use std::time::Instant;
use translucent::DepthConvention;
use translucent::gpu::{
    Access, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorSet, Gpu, GpuTimer, GraphicsDesc, GraphicsPipeline,
    Image, ImageBarrier, ImageDesc, Named, Sampler, median,
};
use translucent::render::plan::Plan;
use translucent::render::records::Vertex;
use translucent::render::renderer::Renderer;
use translucent::render::cull::culled_faces;
use translucent::render::shade::{HDR_FORMAT, ShadePush};

/// The camera's depth format (`render::targets::CAMERA_DEPTH_FORMAT`).
const CAMERA_DEPTH: vk::Format = vk::Format::D32_SFLOAT;
/// The shadow maps' format (`render::targets::SHADOW_FORMAT`).
const SHADOW_DEPTH: vk::Format = vk::Format::D16_UNORM;

/// Timed parts per submission: raster, shadow, tone map, gather, raster with the shading pass's
/// inputs, the G-buffer and the compute shading over it.
const PARTS: u32 = 7;

/// Median milliseconds of each yardstick part.
#[derive(Clone, Copy, Debug, Default)]
pub struct Yardsticks {
    /// Trivial-shader raster of the drawn geometry.
    pub raster: f64,
    /// Depth-only casters into one shadow map.
    pub shadow: f64,
    /// Minimal tone-map dispatch.
    pub tonemap: f64,
    /// The naive gather over as many vertex-sample pairs as the frame's gather.
    pub gather: f64,
    /// Not part of the roofline: the raster yardstick with the shading pass's own vertex stage
    /// and interpolants (shade.vert, glsl/bench/raster_inputs.frag), which says how much of the
    /// gap is the inputs.
    pub raster_inputs: f64,
    /// An empty submission, wall time from submission to fence.
    pub submit: f64,
    /// Not part of the roofline: deferred shading's G-buffer raster (the shading pass's vertex
    /// stage, its four interpolants written to four RGBA32F targets).
    pub gbuffer: f64,
    /// Not part of the roofline: the shading pass's arithmetic over the G-buffer in compute.
    pub shade_compute: f64,
}

impl Yardsticks {
    /// The camera frame's roofline: raster, tone map, submission.
    pub fn camera(&self) -> f64 {
        self.raster + self.tonemap + self.submit
    }

    /// The light frame's roofline: the camera frame's, one shadow map and the naive gather.
    pub fn light(&self) -> f64 {
        self.camera() + self.shadow + self.gather
    }
}

/// The yardsticks' pipelines and targets, sized after one renderer.
pub struct Roofline {
    gpu: Arc<Gpu>,
    raster: GraphicsPipeline,
    inputs: GraphicsPipeline,
    depth: GraphicsPipeline,
    tonemap: ComputePipeline,
    tonemap_set: DescriptorSet,
    naive: ComputePipeline,
    naive_set: DescriptorSet,
    _naive_out: Buffer,
    colour: Image,
    camera_depth: Image,
    shadow: Image,
    _output: Buffer,
    _sampler: Sampler,
    /// Taken out while a submission records (the recording borrows the rest), put back after.
    timer: Option<GpuTimer>,
    /// Times per part, one entry per `run`.
    times: [Vec<f64>; 8],
    deferred: Deferred,
}

/// Deferred shading's G-buffer, its raster pipeline, and the compute shading over it.
struct Deferred {
    raster: GraphicsPipeline,
    targets: Vec<Image>,
    shade: ComputePipeline,
    set: DescriptorSet,
    out: Image,
    _samplers: [Sampler; 2],
}

fn attachment(view: vk::ImageView, layout: vk::ImageLayout, depth: bool) -> vk::RenderingAttachmentInfo<'static> {
    let clear = if depth {
        vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } }
    } else {
        vk::ClearValue { color: vk::ClearColorValue { float32: [0.0, 0.0, 0.0, 1.0] } }
    };
    vk::RenderingAttachmentInfo::default()
        .image_view(view)
        .image_layout(layout)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(if depth { vk::AttachmentStoreOp::DONT_CARE } else { vk::AttachmentStoreOp::STORE })
        .clear_value(clear)
}

impl Roofline {
    /// Pipelines and targets for `renderer`'s camera image size and shadow-map size.
    pub fn new(gpu: &Arc<Gpu>, renderer: &Renderer) -> Roofline {
        let [width, height] = renderer.scene().scene.file.camera.resolution;
        let map = renderer.scene().scene.file.render.shadow_map_size;
        use vk::ImageUsageFlags as U;
        let image =
            |name, w, h, format, usage| Image::new(gpu, &ImageDesc::new(name, w, h, format, usage)).expect(name);
        let colour = image("roofline colour", width, height, HDR_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED);
        let camera_depth = image("roofline depth", width, height, CAMERA_DEPTH, U::DEPTH_STENCIL_ATTACHMENT);
        // An array view of its one layer, so that the deferred yardstick samples it as the
        // shading pass samples its maps (sampler2DArrayShadow).
        let shadow = Image::new(gpu, &{
            let mut d =
                ImageDesc::new("roofline shadow", map, map, SHADOW_DEPTH, U::DEPTH_STENCIL_ATTACHMENT | U::SAMPLED);
            d.array_view = true;
            d
        })
        .expect("roofline shadow");
        let mut desc = GraphicsDesc::new("bench/raster_trivial.vert", Some("bench/raster_trivial.frag"));
        desc.vertex_bindings = vec![Vertex::binding()];
        desc.vertex_attributes = vec![Vertex::position_attribute(), Vertex::normal_attribute()];
        desc.color_formats = vec![HDR_FORMAT];
        desc.depth_format = Some(CAMERA_DEPTH);
        desc.dynamic_cull = true;
        let raster = GraphicsPipeline::new(gpu, &desc).expect("trivial raster pipeline");
        let inputs = inputs_pipeline(gpu);
        let mut desc = GraphicsDesc::new("bench/depth_only.vert", None);
        desc.vertex_bindings = vec![Vertex::binding()];
        desc.vertex_attributes = vec![Vertex::position_attribute()];
        desc.depth_format = Some(SHADOW_DEPTH);
        desc.dynamic_cull = true;
        let depth = GraphicsPipeline::new(gpu, &desc).expect("depth-only pipeline");
        let tonemap = ComputePipeline::new(gpu, "bench/tonemap_minimal.comp").expect("minimal tone map");
        let pixels = width as u64 * height as u64;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let output = Buffer::new(gpu, &BufferDesc::gpu_only("roofline rgba8", 4 * pixels, usage)).expect("buffer");
        let sampler = Sampler::new(gpu, vk::Filter::NEAREST).expect("sampler");
        let hdr = Binding::Image {
            view: colour.view(),
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            sampler: sampler.raw(),
        };
        let tonemap_set = tonemap
            .descriptor_set(&[
                Named { name: "hdr", binding: hdr },
                Named { name: "Tonemapped", binding: Binding::Buffer(&output) },
            ])
            .expect("tone-map set");
        let (naive, naive_set, naive_out) = naive_gather(gpu, renderer);
        let timer = GpuTimer::new(gpu, PARTS).expect("timer");
        let deferred = Deferred::new(gpu, renderer, &shadow);
        Roofline {
            gpu: gpu.clone(),
            raster,
            inputs,
            depth,
            tonemap,
            tonemap_set,
            naive,
            naive_set,
            _naive_out: naive_out,
            colour,
            camera_depth,
            shadow,
            _output: output,
            _sampler: sampler,
            timer: Some(timer),
            times: Default::default(),
            deferred,
        }
    }

    /// One run of every part for `renderer`'s current camera and `plan`'s levels, into the
    /// medians `yardsticks` returns.
    pub fn run(&mut self, renderer: &Renderer, plan: &Plan) {
        let camera = renderer.camera();
        let camera_matrix = camera.projection * camera.view;
        let view_proj = camera_matrix.to_cols_array_2d();
        let scene = renderer.scene_data();
        // The faces the shading and shadow passes draw: those they cull are culled here too.
        let draws: Vec<_> = (0..scene.levels.len())
            .map(|i| scene.level(i, plan.level(i)))
            .map(|level| (level.draw, culled_faces(plan, &level, camera_matrix, DepthConvention::Standard)))
            .collect();
        let light = scene.light_matrices.first().copied().unwrap_or(view_proj);
        let light_matrix = glam::Mat4::from_cols_array_2d(&light);
        let casters: Vec<_> = scene
            .casters
            .iter()
            .map(|&(o, l)| scene.level(o, l))
            .map(|level| (level.draw, culled_faces(plan, &level, light_matrix, DepthConvention::Standard)))
            .collect();
        let (vertices, indices) = (scene.buffers().vertices().raw(), scene.indices.raw());
        let receivers = frame_receivers(renderer, plan);
        let mut timer = self.timer.take().expect("the timer is put back after each run");
        self.gpu
            .one_shot("roofline", |cmd| {
                timer.reset(cmd);
                timer.begin(cmd, "raster");
                self.record_raster(cmd, (vertices, indices), &draws, &view_proj);
                timer.end(cmd);
                timer.begin(cmd, "shadow");
                self.record_shadow(cmd, (vertices, indices), &casters, &light);
                timer.end(cmd);
                timer.begin(cmd, "tonemap");
                self.record_tonemap(cmd);
                timer.end(cmd);
                timer.begin(cmd, "gather");
                self.record_naive(cmd, &receivers);
                timer.end(cmd);
                timer.begin(cmd, "inputs");
                self.record_inputs(cmd, renderer, &draws, &view_proj);
                timer.end(cmd);
                timer.begin(cmd, "gbuffer");
                self.deferred.record_gbuffer((&self.gpu, cmd, &self.camera_depth), renderer, &draws, &view_proj);
                timer.end(cmd);
                timer.begin(cmd, "shade compute");
                self.deferred.record_shading((&self.gpu, cmd, &self.shadow), renderer, &view_proj);
                timer.end(cmd);
            })
            .expect("roofline submission");
        for (i, (_, ms)) in timer.results().expect("roofline timings").into_iter().enumerate() {
            self.times[if i < 5 { i } else { i + 1 }].push(ms);
        }
        self.timer = Some(timer);
        let start = Instant::now();
        self.gpu.one_shot("empty submission", |_| ()).expect("empty submission");
        self.times[5].push(start.elapsed().as_secs_f64() * 1e3);
    }

    /// The medians of every `run` so far.
    pub fn yardsticks(&self) -> Yardsticks {
        let m = |i: usize| median(&mut self.times[i].clone());
        Yardsticks {
            raster: m(0),
            shadow: m(1),
            tonemap: m(2),
            gather: m(3),
            raster_inputs: m(4),
            submit: m(5),
            gbuffer: m(6),
            shade_compute: m(7),
        }
    }

    fn record_raster(
        &self,
        cmd: vk::CommandBuffer,
        (vertices, indices): (vk::Buffer, vk::Buffer),
        draws: &[(translucent::render::gpu_scene::DrawRange, vk::CullModeFlags)],
        view_proj: &[[f32; 4]; 4],
    ) {
        let draw = |cmd| {
            // SAFETY: inside the rendering `raster_into` began; the buffers outlive the submission.
            unsafe {
                let device = self.gpu.device();
                device.cmd_bind_vertex_buffers(cmd, 0, &[vertices], &[0]);
                device.cmd_bind_index_buffer(cmd, indices, 0, vk::IndexType::UINT32);
            }
            self.raster.bind(cmd, None, view_proj, self.colour.extent());
            for (d, hidden) in draws {
                self.raster.set_cull(cmd, *hidden);
                self.raster.draw_indexed(cmd, d.index_count, d.first_index, d.vertex_offset);
            }
        };
        self.raster_into(cmd, draw);
    }

    /// The shading pass's vertex stage and streams with glsl/bench/raster_inputs.frag.
    fn record_inputs(
        &self,
        cmd: vk::CommandBuffer,
        renderer: &Renderer,
        draws: &[(translucent::render::gpu_scene::DrawRange, vk::CullModeFlags)],
        view_proj: &[[f32; 4]; 4],
    ) {
        let scene = renderer.scene_data();
        let streams = [scene.buffers().vertices().raw(), scene.buffers().exitance().raw(), scene.buffers().environment_irradiance().raw()];
        let push = ShadePush { view_proj: *view_proj, ..bytemuck::Zeroable::zeroed() };
        let draw = |cmd| {
            // SAFETY: as in `record_raster`.
            unsafe {
                let device = self.gpu.device();
                device.cmd_bind_vertex_buffers(cmd, 0, &streams, &[0, 0, 0]);
                device.cmd_bind_index_buffer(cmd, scene.indices.raw(), 0, vk::IndexType::UINT32);
            }
            self.inputs.bind(cmd, None, &push, self.colour.extent());
            for (d, hidden) in draws {
                self.inputs.set_cull(cmd, *hidden);
                self.inputs.draw_indexed(cmd, d.index_count, d.first_index, d.vertex_offset);
            }
        };
        self.raster_into(cmd, draw);
    }

    /// Clear the colour and depth targets, record `draw` into them, and leave the colour image
    /// ready for the tone map.
    fn raster_into(&self, cmd: vk::CommandBuffer, draw: impl FnOnce(vk::CommandBuffer)) {
        let device = self.gpu.device();
        let colour_access = [Access::ComputeSampledRead];
        ImageBarrier::new(
            self.colour.raw(),
            vk::ImageAspectFlags::COLOR,
            &colour_access,
            &[Access::ColorAttachmentWrite],
        )
        .discard(true)
        .record(device, cmd);
        ImageBarrier::new(
            self.camera_depth.raw(),
            vk::ImageAspectFlags::DEPTH,
            &[Access::Nothing],
            &[Access::DepthAttachmentReadWrite],
        )
        .discard(true)
        .record(device, cmd);
        let colours = [attachment(self.colour.view(), vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, false)];
        let depth = attachment(self.camera_depth.view(), vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, true);
        let extent = self.colour.extent();
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&colours)
            .depth_attachment(&depth);
        // SAFETY: `cmd` is recording; the attachments are in the layouts the barriers set.
        unsafe { device.cmd_begin_rendering(cmd, &info) };
        draw(cmd);
        // SAFETY: ends the render begun just above in the same `cmd`; `draw` only records
        // binds and draws inside it.
        unsafe { device.cmd_end_rendering(cmd) };
        ImageBarrier::new(
            self.colour.raw(),
            vk::ImageAspectFlags::COLOR,
            &[Access::ColorAttachmentWrite],
            &[Access::ComputeSampledRead],
        )
        .record(device, cmd);
    }

    fn record_shadow(
        &self,
        cmd: vk::CommandBuffer,
        (vertices, indices): (vk::Buffer, vk::Buffer),
        casters: &[(translucent::render::gpu_scene::DrawRange, vk::CullModeFlags)],
        light: &[[f32; 4]; 4],
    ) {
        let device = self.gpu.device();
        ImageBarrier::new(
            self.shadow.raw(),
            vk::ImageAspectFlags::DEPTH,
            &[Access::Nothing],
            &[Access::DepthAttachmentReadWrite],
        )
        .discard(true)
        .record(device, cmd);
        let depth = attachment(self.shadow.view(), vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, true);
        let extent = self.shadow.extent();
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .depth_attachment(&depth);
        // SAFETY: as in `record_raster`.
        unsafe {
            device.cmd_begin_rendering(cmd, &info);
            device.cmd_bind_vertex_buffers(cmd, 0, &[vertices], &[0]);
            device.cmd_bind_index_buffer(cmd, indices, 0, vk::IndexType::UINT32);
        }
        self.depth.bind(cmd, None, light, extent);
        for (d, hidden) in casters {
            self.depth.set_cull(cmd, *hidden);
            self.depth.draw_indexed(cmd, d.index_count, d.first_index, d.vertex_offset);
        }
        // SAFETY: ends the shadow render begun above in the same `cmd`.
        unsafe { device.cmd_end_rendering(cmd) };
    }

    /// The naive kernel over `receivers` (object, vertex count): the first that many vertices of
    /// each object, as many pairs as the frame's gather at the level it gathers at.
    fn record_naive(&self, cmd: vk::CommandBuffer, receivers: &[(u32, u32)]) {
        for &(object, count) in receivers {
            self.naive.dispatch(cmd, &self.naive_set, &object, [count, 1, 1]);
        }
    }

    fn record_tonemap(&self, cmd: vk::CommandBuffer) {
        let extent = self.colour.extent();
        let size = [extent.width, extent.height];
        self.tonemap.dispatch(cmd, &self.tonemap_set, &size, [extent.width, extent.height, 1]);
    }
}

/// Each translucent object the frame of `plan` gathers, and its receiver count there.
pub fn frame_receivers(renderer: &Renderer, plan: &Plan) -> Vec<(u32, u32)> {
    let scene = renderer.scene_data();
    (0..scene.receivers.len())
        .map(|j| {
            let object = scene.receivers[j].object;
            (object, scene.level(object as usize, plan.level(object as usize)).vertex_count)
        })
        .collect()
}

/// Vertex-sample pairs of the frame of `plan`'s gather, if it were flat.
pub fn frame_pairs(renderer: &Renderer, plan: &Plan) -> f64 {
    let scene = renderer.scene_data();
    frame_receivers(renderer, plan)
        .iter()
        .zip(&scene.receivers)
        .map(|(&(_, count), r)| count as f64 * r.sample_count as f64)
        .sum()
}

/// glsl/bench/gather_naive.comp bound to `renderer`'s buffers, writing into its own.
pub fn naive_gather(gpu: &Arc<Gpu>, renderer: &Renderer) -> (ComputePipeline, DescriptorSet, Buffer) {
    use translucent::render::graph::Resource;
    let naive = ComputePipeline::new(gpu, "bench/gather_naive.comp").expect("naive gather pipeline");
    let b = renderer.scene_data();
    let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
    let size = 16 * b.vertex_count.max(1) as u64;
    let out = Buffer::new(gpu, &BufferDesc::gpu_only("naive exitance", size, usage)).expect("buffer");
    let set = naive
        .descriptor_set(&[
            Resource::Vertices.bind(Binding::Buffer(b.buffers().vertices())),
            Resource::Samples.bind(Binding::Buffer(b.buffers().samples())),
            Resource::Splat.bind(Binding::Buffer(b.buffers().splat())),
            Resource::Objects.bind(Binding::Buffer(b.buffers().objects())),
            Resource::Exitance.bind(Binding::Buffer(&out)),
        ])
        .expect("descriptor set");
    (naive, set, out)
}

/// shade.vert (the shading pass's vertex stage and three streams) with
/// glsl/bench/raster_inputs.frag, into the same targets as the raster yardstick.
fn inputs_pipeline(gpu: &Arc<Gpu>) -> GraphicsPipeline {
    let mut desc = inputs_desc("bench/raster_inputs.frag");
    desc.color_formats = vec![HDR_FORMAT];
    GraphicsPipeline::new(gpu, &desc).expect("inputs raster pipeline")
}

/// shade.vert with its three streams, `fragment` after it, camera depth; colour formats unset.
fn inputs_desc(fragment: &str) -> GraphicsDesc {
    let stream = |binding: u32, location: u32| {
        (
            vk::VertexInputBindingDescription { binding, stride: 16, input_rate: vk::VertexInputRate::VERTEX },
            vk::VertexInputAttributeDescription {
                location,
                binding,
                format: vk::Format::R32G32B32A32_SFLOAT,
                offset: 0,
            },
        )
    };
    let (exitance, environment) = (stream(1, 2), stream(2, 3));
    let mut desc = GraphicsDesc::new("shade.vert", Some(fragment));
    desc.vertex_bindings = vec![Vertex::binding(), exitance.0, environment.0];
    desc.vertex_attributes = vec![Vertex::position_attribute(), Vertex::normal_attribute(), exitance.1, environment.1];
    desc.depth_format = Some(CAMERA_DEPTH);
    desc.dynamic_cull = true;
    desc
}

impl Deferred {
    /// The G-buffer (four RGBA32F targets of the camera's size), its pipeline, and the compute
    /// shading bound to `renderer`'s lights and the roofline's own shadow map (`shadow`).
    fn new(gpu: &Arc<Gpu>, renderer: &Renderer, shadow: &Image) -> Deferred {
        use vk::ImageUsageFlags as U;
        let [width, height] = renderer.scene().scene.file.camera.resolution;
        let format = vk::Format::R32G32B32A32_SFLOAT;
        let targets: Vec<Image> = ["g position", "g normal", "g exitance", "g environment"]
            .iter()
            .map(|name| {
                let desc = ImageDesc::new(name, width, height, format, U::COLOR_ATTACHMENT | U::SAMPLED);
                Image::new(gpu, &desc).expect(name)
            })
            .collect();
        let out = Image::new(gpu, &ImageDesc::new("deferred radiance", width, height, format, U::STORAGE))
            .expect("deferred radiance");
        let mut desc = inputs_desc("bench/raster_gbuffer.frag");
        desc.color_formats = vec![format; 4];
        let raster = GraphicsPipeline::new(gpu, &desc).expect("G-buffer pipeline");
        let shade = ComputePipeline::new(gpu, "bench/shade_compute.comp").expect("compute shading");
        let samplers = [
            Sampler::shadow(gpu, SHADOW_DEPTH).expect("shadow sampler"),
            Sampler::new(gpu, vk::Filter::NEAREST).expect("sampler"),
        ];
        let sampled = |image: &Image, sampler: &Sampler| Binding::Image {
            view: image.view(),
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            sampler: sampler.raw(),
        };
        let names = ["g_position", "g_normal", "g_exitance", "g_environment"];
        let mut bindings = vec![
            Named { name: "Lights", binding: Binding::Buffer(renderer.scene_data().buffers().lights()) },
            Named { name: "shadow_maps", binding: sampled(shadow, &samplers[0]) },
        ];
        bindings.extend(names.iter().zip(&targets).map(|(&name, t)| Named { name, binding: sampled(t, &samplers[1]) }));
        let storage =
            Binding::Image { view: out.view(), layout: vk::ImageLayout::GENERAL, sampler: vk::Sampler::null() };
        bindings.push(Named { name: "radiance_out", binding: storage });
        let set = shade.descriptor_set(&bindings).expect("compute shading set");
        Deferred { raster, targets, shade, set, out, _samplers: samplers }
    }

    /// The drawn geometry through the shading pass's vertex stage into the G-buffer.
    fn record_gbuffer(
        &self,
        (gpu, cmd, depth): (&Gpu, vk::CommandBuffer, &Image),
        renderer: &Renderer,
        draws: &[(translucent::render::gpu_scene::DrawRange, vk::CullModeFlags)],
        view_proj: &[[f32; 4]; 4],
    ) {
        let device = gpu.device();
        ImageBarrier::new(
            depth.raw(),
            vk::ImageAspectFlags::DEPTH,
            &[Access::Nothing],
            &[Access::DepthAttachmentReadWrite],
        )
        .discard(true)
        .record(device, cmd);
        for t in &self.targets {
            ImageBarrier::new(
                t.raw(),
                vk::ImageAspectFlags::COLOR,
                &[Access::Nothing],
                &[Access::ColorAttachmentWrite],
            )
            .discard(true)
            .record(device, cmd);
        }
        // Cleared to zero: a position's w of 0 marks a pixel no surface covers.
        let zero = vk::ClearValue { color: vk::ClearColorValue { float32: [0.0; 4] } };
        let colours: Vec<_> = self
            .targets
            .iter()
            .map(|t| attachment(t.view(), vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, false).clear_value(zero))
            .collect();
        // The depth image is the roofline's; its parts run one after another in one submission.
        let depth = attachment(depth.view(), vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL, true);
        let extent = self.targets[0].extent();
        let scene = renderer.scene_data();
        let streams = [scene.buffers().vertices().raw(), scene.buffers().exitance().raw(), scene.buffers().environment_irradiance().raw()];
        let push = ShadePush { view_proj: *view_proj, ..bytemuck::Zeroable::zeroed() };
        let info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent })
            .layer_count(1)
            .color_attachments(&colours)
            .depth_attachment(&depth);
        // SAFETY: `cmd` is recording; the targets are in the layout the barriers set, and the
        // buffers outlive the submission.
        unsafe {
            device.cmd_begin_rendering(cmd, &info);
            device.cmd_bind_vertex_buffers(cmd, 0, &streams, &[0, 0, 0]);
            device.cmd_bind_index_buffer(cmd, scene.indices.raw(), 0, vk::IndexType::UINT32);
        }
        self.raster.bind(cmd, None, &push, extent);
        for (d, hidden) in draws {
            self.raster.set_cull(cmd, *hidden);
            self.raster.draw_indexed(cmd, d.index_count, d.first_index, d.vertex_offset);
        }
        // SAFETY: ends the render begun above in the same `cmd`.
        unsafe { device.cmd_end_rendering(cmd) };
        for t in &self.targets {
            let (from, to) = ([Access::ColorAttachmentWrite], [Access::ComputeSampledRead]);
            ImageBarrier::new(t.raw(), vk::ImageAspectFlags::COLOR, &from, &to).record(device, cmd);
        }
    }

    /// The shading pass's arithmetic over every pixel of the G-buffer, as the first translucent
    /// object's pipeline shades it, with the shadow map the roofline drew just before.
    fn record_shading(
        &self,
        (gpu, cmd, shadow): (&Gpu, vk::CommandBuffer, &Image),
        renderer: &Renderer,
        view_proj: &[[f32; 4]; 4],
    ) {
        let device = gpu.device();
        let (drawn, read) = ([Access::DepthAttachmentReadWrite], [Access::ComputeSampledRead]);
        ImageBarrier::new(shadow.raw(), vk::ImageAspectFlags::DEPTH, &drawn, &read).record(device, cmd);
        let scene = renderer.scene_data();
        let eye = renderer.camera().eye;
        let object = (0..scene.levels.len())
            .find(|&i| scene.object_record(i).kind == translucent::render::records::MATERIAL_TRANSLUCENT)
            .unwrap_or(0);
        let record = scene.object_record(object);
        let push = ShadePush {
            view_proj: *view_proj,
            eye_object: [eye.x, eye.y, eye.z, object as f32],
            counts: [scene.light_count, scene.key_light_count, record.local_channels, 0],
            albedo_roughness: record.albedo_roughness,
            material: [record.eta, record.norm, 0.0, 0.0],
        };
        ImageBarrier::new(self.out.raw(), vk::ImageAspectFlags::COLOR, &[Access::Nothing], &[Access::ComputeWrite])
            .discard(true)
            .record(device, cmd);
        let extent = self.out.extent();
        self.shade.dispatch(cmd, &self.set, &push, [extent.width, extent.height, 1]);
    }
}
