//! The GPU core on lavapipe with validation on: compute round-trip, timer, graphics path.

mod common;

use ash::vk;
use common::with_gpu;
use std::sync::Arc;
use translucent::gpu::{
    Access, Binding, Buffer, ComputePipeline, DescriptorSet, Gpu, GpuTimer, GraphicsDesc, GraphicsPipeline, Image,
    ImageBarrier, ImageDesc, Named, shaders,
};
use translucent::render::smoke;

#[test]
fn compute_round_trip_is_exact() {
    with_gpu(|gpu| {
        // Not a multiple of the workgroup size, so the bounds check in the shader matters.
        let input: Vec<f32> = (0..10_001).map(|i| (i as f32) * 0.25 - 1000.0).collect();
        let result = smoke::run(gpu, &input).expect("smoke dispatch");
        assert_eq!(result.output, smoke::expected(&input));
    });
}

#[test]
fn gpu_timer_is_positive_and_finite() {
    with_gpu(|gpu| {
        let input = vec![1.0f32; 1 << 18];
        let result = smoke::run(gpu, &input).expect("smoke dispatch");
        assert!(result.gpu_ms.is_finite() && result.gpu_ms > 0.0, "GPU time {} ms", result.gpu_ms);
        // A dispatch over 2^18 elements on any device takes far less than ten seconds.
        assert!(result.gpu_ms < 10_000.0, "GPU time {} ms", result.gpu_ms);
    });
}

#[test]
fn timer_orders_passes_and_names_them() {
    with_gpu(|gpu| {
        let mut timer = GpuTimer::new(gpu, 2).unwrap();
        gpu.one_shot("timer test", |cmd| {
            timer.reset(cmd);
            timer.begin(cmd, "first");
            timer.end(cmd);
            timer.begin(cmd, "second");
            timer.end(cmd);
        })
        .unwrap();
        let results = timer.results().unwrap();
        let names: Vec<_> = results.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["first", "second"]);
        assert!(results.iter().all(|(_, ms)| ms.is_finite() && *ms >= 0.0));
    });
}

#[test]
fn every_embedded_shader_is_spirv() {
    let names: Vec<_> = shaders::names().collect();
    assert!(names.contains(&"smoke.comp"), "embedded shaders: {names:?}");
    for name in names {
        let words = shaders::spirv(name).unwrap();
        assert_eq!(words[0], 0x0723_0203, "{name} does not start with the SPIR-V magic number");
    }
    assert!(shaders::spirv("no-such.comp").is_err());
}

/// One vertex of the test triangle, laid out as test/triangle.vert reads it.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Vertex {
    position: [f32; 2],
    color: [f32; 3],
}

/// The triangle's pipeline: its own vertex layout (position then colour, one binding) and the
/// target's formats, so that the draw exercises vertex input, a push constant and a depth
/// attachment at once.
fn triangle_pipeline(gpu: &Arc<Gpu>, format: vk::Format, depth_format: vk::Format) -> GraphicsPipeline {
    let mut desc = GraphicsDesc::new("test/triangle.vert", Some("test/triangle.frag"));
    desc.vertex_bindings = vec![vk::VertexInputBindingDescription {
        binding: 0,
        stride: std::mem::size_of::<Vertex>() as u32,
        input_rate: vk::VertexInputRate::VERTEX,
    }];
    desc.vertex_attributes = vec![
        vk::VertexInputAttributeDescription { location: 0, binding: 0, format: vk::Format::R32G32_SFLOAT, offset: 0 },
        vk::VertexInputAttributeDescription {
            location: 1,
            binding: 0,
            format: vk::Format::R32G32B32_SFLOAT,
            offset: 8,
        },
    ];
    desc.color_formats = vec![format];
    desc.depth_format = Some(depth_format);
    GraphicsPipeline::new(gpu, &desc).unwrap()
}

/// Records the draw into `cmd`: both attachments to their attachment layouts, the colour
/// cleared to blue (what the corners must keep), then the triangle with a tint of 0.5.
fn record_triangle(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    (color, depth): (&Image, &Image),
    (pipeline, set): (&GraphicsPipeline, &DescriptorSet),
    vertices: &Buffer,
) {
    ImageBarrier::new(color.raw(), vk::ImageAspectFlags::COLOR, &[Access::Nothing], &[Access::ColorAttachmentWrite])
        .record(device, cmd);
    ImageBarrier::new(
        depth.raw(),
        vk::ImageAspectFlags::DEPTH,
        &[Access::Nothing],
        &[Access::DepthAttachmentReadWrite],
    )
    .record(device, cmd);
    let colors = [vk::RenderingAttachmentInfo::default()
        .image_view(color.view())
        .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::STORE)
        .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0, 0.0, 1.0, 1.0] } })];
    let depth_attachment = vk::RenderingAttachmentInfo::default()
        .image_view(depth.view())
        .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
        .load_op(vk::AttachmentLoadOp::CLEAR)
        .store_op(vk::AttachmentStoreOp::DONT_CARE)
        .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 } });
    let rendering = vk::RenderingInfo::default()
        .render_area(vk::Rect2D { offset: vk::Offset2D::default(), extent: color.extent() })
        .layer_count(1)
        .color_attachments(&colors)
        .depth_attachment(&depth_attachment);
    // SAFETY: `cmd` is recording (inside `one_shot`); the barriers above put both attachments in
    // the layouts named here, and the images, pipeline, set and vertex buffer outlive the
    // submission (the caller holds them until `one_shot` returns); the render is ended here.
    unsafe {
        device.cmd_begin_rendering(cmd, &rendering);
        pipeline.bind(cmd, Some(set), &0.5f32, color.extent());
        device.cmd_bind_vertex_buffers(cmd, 0, &[vertices.raw()], &[0]);
        device.cmd_draw(cmd, 3, 1, 0, 0);
        device.cmd_end_rendering(cmd);
    }
}

#[test]
fn graphics_pipeline_draws_a_triangle() {
    const SIZE: u32 = 64;
    with_gpu(|gpu| {
        // Counter-clockwise in framebuffer space (y down), covering the centre.
        let vertices = [
            Vertex { position: [-0.8, -0.8], color: [1.0, 1.0, 0.0] },
            Vertex { position: [-0.8, 0.8], color: [1.0, 1.0, 0.0] },
            Vertex { position: [0.8, 0.0], color: [1.0, 1.0, 0.0] },
        ];
        let vbuf = Buffer::from_slice(gpu, "triangle", &vertices, vk::BufferUsageFlags::VERTEX_BUFFER).unwrap();
        let tint =
            Buffer::from_slice(gpu, "tint", &[1.0f32, 0.5, 0.5, 1.0], vk::BufferUsageFlags::STORAGE_BUFFER).unwrap();
        let format = vk::Format::R8G8B8A8_UNORM;
        let color =
            Image::new(gpu, &ImageDesc::new("target", SIZE, SIZE, format, vk::ImageUsageFlags::COLOR_ATTACHMENT))
                .unwrap();
        let depth_format = vk::Format::D32_SFLOAT;
        let depth = Image::new(
            gpu,
            &ImageDesc::new("depth", SIZE, SIZE, depth_format, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT),
        )
        .unwrap();
        let pipeline = triangle_pipeline(gpu, format, depth_format);
        let set = pipeline.descriptor_set(&[Named { name: "Tint", binding: Binding::Buffer(&tint) }]).unwrap();
        let device = gpu.device();
        gpu.one_shot("draw", |cmd| record_triangle(device, cmd, (&color, &depth), (&pipeline, &set), &vbuf)).unwrap();
        let pixels = color.read(Access::ColorAttachmentWrite).unwrap();
        let at = |x: u32, y: u32| {
            let i = 4 * (y * SIZE + x) as usize;
            [pixels[i], pixels[i + 1], pixels[i + 2], pixels[i + 3]]
        };
        assert_eq!(at(SIZE / 2, SIZE / 2), [255, 128, 0, 255], "centre is the tinted triangle");
        assert_eq!(at(1, 1), [0, 0, 255, 255], "corner keeps the clear colour");
        assert_eq!(at(SIZE - 2, 2), [0, 0, 255, 255], "right top corner keeps the clear colour");
    });
}

#[test]
fn device_info_names_the_device() {
    with_gpu(|gpu| {
        let info = gpu.info();
        assert!(!info.name.is_empty());
        assert!(info.api_version.starts_with("1."), "{}", info.api_version);
        let (period, bits) = gpu.timestamp_info();
        assert!(period > 0.0 && bits > 0);
    });
}

#[test]
fn validation_counts_a_leaked_object() {
    // The machinery every other test relies on: a VkBuffer left alive when the device is
    // destroyed must be reported and counted.
    let gpu = translucent::gpu::Gpu::new(&common::validated_options())
        .expect("a Vulkan device with validation layers (run `bash scripts/setup`)");
    let counters = gpu.validation();
    let info = vk::BufferCreateInfo::default().size(256).usage(vk::BufferUsageFlags::STORAGE_BUFFER);
    // SAFETY: a valid buffer, deliberately never destroyed.
    let _leaked = unsafe { gpu.device().create_buffer(&info, None) }.unwrap();
    assert_eq!(counters.total(), 0);
    drop(gpu);
    assert!(counters.errors() > 0, "the leaked VkBuffer was not reported");
    assert!(counters.messages().iter().any(|m| m.contains("VkBuffer")), "{:?}", counters.messages());
}

#[test]
fn a_saved_pipeline_cache_seeds_a_new_gpu_and_data_from_elsewhere_is_refused() {
    let data = with_gpu(|gpu| {
        ComputePipeline::new(gpu, "splat.comp").unwrap();
        gpu.pipeline_cache_data().unwrap()
    });
    // At least the header; lavapipe (Mesa 22.3) keeps nothing past it (32 bytes), a GPU's
    // driver keeps the compiled pipeline.
    assert!(data.len() >= 32, "a cache with its header: {} bytes", data.len());
    with_gpu(|gpu| {
        gpu.seed_pipeline_cache(&data).unwrap();
        ComputePipeline::new(gpu, "splat.comp").unwrap();
        assert!(gpu.pipeline_cache_data().unwrap().len() >= 32);
        // Another driver build (its pipelineCacheUUID), and bytes that are no cache at all.
        let mut foreign = data.clone();
        foreign[20] ^= 0xff;
        let message = gpu.seed_pipeline_cache(&foreign).unwrap_err().to_string();
        assert!(message.contains("pipelineCacheUUID"), "{message}");
        let message = gpu.seed_pipeline_cache(&[1, 2, 3]).unwrap_err().to_string();
        assert!(message.contains("shorter than its 32-byte header"), "{message}");
        let mut other_device = data.clone();
        other_device[12] ^= 0x01;
        let message = gpu.seed_pipeline_cache(&other_device).unwrap_err().to_string();
        assert!(message.contains("device"), "{message}");
    });
}
