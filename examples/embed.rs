//! A small engine in raw ash that embeds translucent: it creates its own instance and device
//! (with translucent's required features chained in), an offscreen colour and depth target, and
//! its own geometry (a ground quad). Each frame it records, in one command buffer of its own:
//! its clear and its quad, translucent's passes (`Renderer::record_frame` into the same colour
//! and depth images, depth-tested against the quad), and its own post pass (a blit of the linear
//! image into an 8-bit one, and copies to host memory). It moves the camera between frames,
//! submits, waits on its fence, reads translucent's pass timings, and writes PNGs.
//!
//! `cargo run --release --example embed [OUT_DIR]`; `tests/embed.rs` runs it on lavapipe with
//! validation on.

use ash::vk;
use glam::Mat4;
use std::ffi::{CStr, c_void};
use std::path::Path;
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};
use translucent::SceneEdit;
use translucent::gpu::{EnabledFeatures, Gpu, GpuOptions, HostVulkan, required_features};
use translucent::render::camera::CameraView;
use translucent::render::options::RendererOptions;
use translucent::render::plan::Pass;
use translucent::render::renderer::Renderer;
use translucent::render::target::HostSync;
use translucent::render::target::{DepthConvention, DepthTest, HostAttachment, HostTarget, TargetDesc};
use translucent::scene::Scene;
use translucent::scene::build::{Overrides, PreparedScene};

/// Image size of the example's target.
pub const SIZE: u32 = 128;
/// The host's linear colour format, and its depth format.
pub const COLOR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;
/// The ground quad's linear colour (translucent's marble is never this green).
pub const GROUND: [f32; 4] = [0.05, 0.4, 0.05, 1.0];

/// A marble sphere 2 cm across at the origin, lit from the upper right; the camera looks at it
/// from the front and a little above.
pub const SPHERE_SCENE: &str = r#"
[camera]
eye = [0.0, 0.02, 0.08]
target = [0.0, 0.0, 0.0]
fov_y = 30.0
resolution = [128, 128]

[[object]]
shape = { type = "sphere", radius = 0.01, divisions = 24 }
material = { type = "translucent", preset = "marble", mm_per_unit = 1000.0 }

[[light]]
type = "directional"
direction = [0.6, 0.7, 0.4]
irradiance = [2.0, 2.0, 2.0]

[sampling]
method = "turk"
count = 200

[render]
background = [0.0, 0.0, 0.0]
"#;

/// A ketchup sphere to the right, for a second renderer on the same device.
pub const SECOND_SCENE: &str = r#"
[camera]
eye = [0.0, 0.02, 0.08]
target = [0.0, 0.0, 0.0]
resolution = [128, 128]

[[object]]
shape = { type = "sphere", radius = 0.006, divisions = 16 }
transform = { translate = [0.017, 0.0, 0.0] }
material = { type = "translucent", preset = "ketchup", mm_per_unit = 1000.0 }

[[light]]
type = "directional"
direction = [0.6, 0.7, 0.4]
irradiance = [2.0, 2.0, 2.0]

[sampling]
count = 100
"#;

/// How the host sets itself up (the tests vary it to check translucent's contract).
#[derive(Clone, Debug)]
pub struct Options {
    /// `apiVersion` of the host's instance.
    pub api_version: u32,
    /// Chain translucent's `shaderOutputLayer` into the device (and declare it).
    pub shader_output_layer: bool,
    /// Draw the second renderer's scene into the same command buffer.
    pub second_renderer: bool,
    /// Frames to render; the camera turns 10 degrees about the sphere between frames.
    pub frames: usize,
    /// Height of the ground quad (it hides what of the sphere is below it).
    pub ground_y: f32,
    /// The engine's depth test, translucent's too: standard, or reversed-Z (cleared to 0,
    /// GREATER_OR_EQUAL, projections reversed).
    pub depth: DepthTest,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            api_version: vk::API_VERSION_1_3,
            shader_output_layer: true,
            second_renderer: false,
            frames: 3,
            ground_y: -0.005,
            depth: DepthTest::STANDARD,
        }
    }
}

/// What one frame produced.
pub struct Frame {
    /// The host's linear colour target, RGBA f32, rows top to bottom.
    pub linear: Vec<f32>,
    /// After the host's post pass (blit to RGBA8).
    pub rgba8: Vec<u8>,
    /// The passes translucent recorded.
    pub passes: Vec<Pass>,
    /// translucent's per-pass GPU milliseconds, read after the fence.
    pub timings: Vec<(String, f64)>,
}

/// Everything the run produced.
pub struct Run {
    pub frames: Vec<Frame>,
    /// The host's quad drawn again after the renderers were dropped (the device still works).
    pub after_drop: Vec<f32>,
    /// Validation messages the host's own messenger counted (leaks at device destruction too).
    pub validation_messages: usize,
}

static MESSAGES: AtomicUsize = AtomicUsize::new(0);

/// Validation messages counted since the last `run` began (one run at a time per process).
pub fn validation_messages() -> usize {
    MESSAGES.load(Ordering::SeqCst)
}

unsafe extern "system" fn count_message(
    _severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    MESSAGES.fetch_add(1, Ordering::SeqCst);
    // SAFETY: the layer passes a valid callback data pointer with a NUL-terminated message.
    let message = unsafe { (*data).message_as_c_str() }.map(CStr::to_string_lossy).unwrap_or_default();
    eprintln!("[host validation] {message}");
    vk::FALSE
}

/// One image with its memory and view, the host's way.
struct HostImage {
    image: vk::Image,
    memory: vk::DeviceMemory,
    view: vk::ImageView,
}

fn memory_type(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
    bits: u32,
    flags: vk::MemoryPropertyFlags,
) -> u32 {
    // SAFETY: plain query.
    let props = unsafe { instance.get_physical_device_memory_properties(physical) };
    (0..props.memory_type_count)
        .find(|&i| bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(flags))
        .expect("a memory type")
}

/// A host-visible buffer, mapped for as long as it lives (freeing its memory unmaps it).
struct Mapped {
    buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    ptr: *mut c_void,
}

/// The host's engine: its Vulkan objects, created and destroyed by itself.
struct Host {
    entry: ash::Entry,
    instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    physical: vk::PhysicalDevice,
    device: ash::Device,
    queue: vk::Queue,
    family: u32,
}

impl Host {
    fn new(options: &Options) -> Result<Host, String> {
        // SAFETY: loading the system's Vulkan loader.
        let entry = unsafe { ash::Entry::load() }.map_err(|e| format!("no Vulkan loader: {e}"))?;
        let validation = std::env::var("TRANSLUCENT_VALIDATION").is_ok_and(|v| v == "1");
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        let extensions = [ash::ext::debug_utils::NAME.as_ptr()];
        let app = vk::ApplicationInfo::default().api_version(options.api_version);
        let mut info = vk::InstanceCreateInfo::default().application_info(&app);
        if validation {
            info = info.enabled_layer_names(&layers).enabled_extension_names(&extensions);
        }
        // SAFETY: valid create info.
        let instance = unsafe { entry.create_instance(&info, None) }.map_err(|e| format!("vkCreateInstance: {e}"))?;
        let debug = validation.then(|| {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(count_message));
            // SAFETY: valid create info; destroyed in `destroy`.
            let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }.expect("messenger");
            (loader, messenger)
        });
        // SAFETY: plain queries.
        let physicals = unsafe { instance.enumerate_physical_devices() }.map_err(|e| e.to_string())?;
        let wanted = std::env::var("TRANSLUCENT_DEVICE").ok();
        let physical = physicals
            .iter()
            .copied()
            .find(|&p| {
                // SAFETY: plain query.
                let props = unsafe { instance.get_physical_device_properties(p) };
                let name = props.device_name_as_c_str().unwrap_or_default().to_string_lossy().to_lowercase();
                wanted.as_ref().is_none_or(|w| name.contains(&w.to_lowercase()))
            })
            .ok_or("no Vulkan device")?;
        // SAFETY: plain query.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
            .ok_or("no graphics+compute queue")? as u32;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
        let mut features = required_features();
        features.vulkan12.shader_output_layer = options.shader_output_layer as vk::Bool32;
        let mut info = vk::DeviceCreateInfo::default().queue_create_infos(&queues).push_next(&mut features.vulkan12);
        // Vulkan 1.3 features exist only for a 1.3 instance.
        if options.api_version >= vk::API_VERSION_1_3 {
            info = info.push_next(&mut features.vulkan13);
        }
        // SAFETY: valid create info; destroyed in `destroy`.
        let device =
            unsafe { instance.create_device(physical, &info, None) }.map_err(|e| format!("vkCreateDevice: {e}"))?;
        // SAFETY: queue 0 of `family` was requested.
        let queue = unsafe { device.get_device_queue(family, 0) };
        Ok(Host { entry, instance, debug, physical, device, queue, family })
    }

    fn image(&self, format: vk::Format, usage: vk::ImageUsageFlags, aspect: vk::ImageAspectFlags) -> HostImage {
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: SIZE, height: SIZE, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .usage(usage);
        // SAFETY: valid create infos; everything is destroyed in `destroy_image`.
        unsafe {
            let image = self.device.create_image(&info, None).unwrap();
            let req = self.device.get_image_memory_requirements(image);
            let kind =
                memory_type(&self.instance, self.physical, req.memory_type_bits, vk::MemoryPropertyFlags::DEVICE_LOCAL);
            let memory = self
                .device
                .allocate_memory(
                    &vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(kind),
                    None,
                )
                .unwrap();
            self.device.bind_image_memory(image, memory, 0).unwrap();
            let range = vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1);
            let view = self
                .device
                .create_image_view(
                    &vk::ImageViewCreateInfo::default()
                        .image(image)
                        .view_type(vk::ImageViewType::TYPE_2D)
                        .format(format)
                        .subresource_range(range),
                    None,
                )
                .unwrap();
            HostImage { image, memory, view }
        }
    }

    fn destroy_image(&self, image: &HostImage) {
        // SAFETY: the device is idle.
        unsafe {
            self.device.destroy_image_view(image.view, None);
            self.device.destroy_image(image.image, None);
            self.device.free_memory(image.memory, None);
        }
    }

    /// A host-visible buffer of `size` bytes, mapped.
    fn readback(&self, size: u64) -> Mapped {
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(vk::BufferUsageFlags::TRANSFER_DST | vk::BufferUsageFlags::VERTEX_BUFFER);
        // SAFETY: valid create info; destroyed by the caller.
        unsafe {
            let buffer = self.device.create_buffer(&info, None).unwrap();
            let req = self.device.get_buffer_memory_requirements(buffer);
            let flags = vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT;
            let kind = memory_type(&self.instance, self.physical, req.memory_type_bits, flags);
            let memory = self
                .device
                .allocate_memory(
                    &vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(kind),
                    None,
                )
                .unwrap();
            self.device.bind_buffer_memory(buffer, memory, 0).unwrap();
            let ptr = self.device.map_memory(memory, 0, size, vk::MemoryMapFlags::empty()).unwrap();
            Mapped { buffer, memory, ptr }
        }
    }

    fn destroy(self) {
        // SAFETY: everything made from the device is gone; the device is idle.
        unsafe {
            self.device.destroy_device(None);
            if let Some((loader, messenger)) = &self.debug {
                loader.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

/// The host's quad pipeline (its own shaders, compiled by translucent's build.rs from
/// glsl/examples/ for convenience; an engine would bring its own SPIR-V).
struct Ground {
    layout: vk::PipelineLayout,
    pipeline: vk::Pipeline,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GroundPush {
    view_proj: [[f32; 4]; 4],
    color: [f32; 4],
}

impl Ground {
    fn new(device: &ash::Device, compare: vk::CompareOp) -> Ground {
        let module = |name: &str| {
            let words = translucent::gpu::shaders::spirv(name).unwrap();
            // SAFETY: SPIR-V compiled by glslang; destroyed below once the pipeline exists.
            unsafe { device.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(&words), None) }.unwrap()
        };
        let (vert, frag) = (module("examples/ground.vert"), module("examples/ground.frag"));
        let ranges = [vk::PushConstantRange {
            stage_flags: vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            offset: 0,
            size: size_of::<GroundPush>() as u32,
        }];
        // SAFETY: valid create infos.
        let layout = unsafe {
            device.create_pipeline_layout(&vk::PipelineLayoutCreateInfo::default().push_constant_ranges(&ranges), None)
        }
        .unwrap();
        let stages = [
            vk::PipelineShaderStageCreateInfo::default().stage(vk::ShaderStageFlags::VERTEX).module(vert).name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(frag)
                .name(c"main"),
        ];
        let bindings =
            [vk::VertexInputBindingDescription { binding: 0, stride: 12, input_rate: vk::VertexInputRate::VERTEX }];
        let attributes = [vk::VertexInputAttributeDescription {
            location: 0,
            binding: 0,
            format: vk::Format::R32G32B32_SFLOAT,
            offset: 0,
        }];
        let vertex_input = vk::PipelineVertexInputStateCreateInfo::default()
            .vertex_binding_descriptions(&bindings)
            .vertex_attribute_descriptions(&attributes);
        let assembly =
            vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_STRIP);
        let viewport = vk::PipelineViewportStateCreateInfo::default().viewport_count(1).scissor_count(1);
        let raster =
            vk::PipelineRasterizationStateCreateInfo::default().polygon_mode(vk::PolygonMode::FILL).line_width(1.0);
        let multisample =
            vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
        let depth = vk::PipelineDepthStencilStateCreateInfo::default()
            .depth_test_enable(true)
            .depth_write_enable(true)
            .depth_compare_op(compare);
        let blend_attachments =
            [vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA)];
        let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
        let formats = [COLOR_FORMAT];
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&formats)
            .depth_attachment_format(DEPTH_FORMAT);
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
            .layout(layout)
            .push_next(&mut rendering)];
        // SAFETY: every pointer refers to locals alive for the call.
        let pipeline = unsafe { device.create_graphics_pipelines(vk::PipelineCache::null(), &info, None) }.unwrap()[0];
        // SAFETY: the pipeline is created; the modules are no longer needed.
        unsafe {
            device.destroy_shader_module(vert, None);
            device.destroy_shader_module(frag, None);
        }
        Ground { layout, pipeline }
    }
}

fn barrier(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    image: vk::Image,
    aspect: vk::ImageAspectFlags,
    layouts: (vk::ImageLayout, vk::ImageLayout),
    src: (vk::PipelineStageFlags2, vk::AccessFlags2),
    dst: (vk::PipelineStageFlags2, vk::AccessFlags2),
) {
    let b = [vk::ImageMemoryBarrier2::default()
        .image(image)
        .old_layout(layouts.0)
        .new_layout(layouts.1)
        .src_stage_mask(src.0)
        .src_access_mask(src.1)
        .dst_stage_mask(dst.0)
        .dst_access_mask(dst.1)
        .subresource_range(vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1))];
    // SAFETY: `cmd` is recording.
    unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&b)) };
}

/// The camera of frame `i`: the scene's, turned 10 degrees a frame about the vertical axis,
/// its depth reversed for a reversed-Z engine.
fn camera_of(prepared: &PreparedScene, i: usize, depth: DepthTest) -> CameraView {
    let camera = CameraView::of_scene(prepared).orbited(glam::Vec3::ZERO, 10.0 * i as f32);
    match depth.convention {
        DepthConvention::Standard => camera,
        DepthConvention::Reversed => camera.reversed_depth(),
    }
}

/// Run the engine. An error is translucent's or the host's setup failing, as text.
pub fn run(options: &Options) -> Result<Run, String> {
    MESSAGES.store(0, Ordering::SeqCst);
    let host = Host::new(options)?;
    let result = run_on(&host, options);
    // SAFETY: plain wait before the host destroys its objects.
    unsafe { host.device.device_wait_idle() }.unwrap();
    host.destroy();
    let mut run = result?;
    run.validation_messages = MESSAGES.load(Ordering::SeqCst);
    Ok(run)
}

fn run_on(host: &Host, options: &Options) -> Result<Run, String> {
    let gpu = host_gpu(host, options)?;
    let engine = Engine::new(host, options);
    let result = render_frames(&engine, gpu, options);
    engine.destroy();
    result
}

/// translucent on the host's device, drawing into the host's images; it checks the host's
/// setup before the host has made anything of its own.
fn host_gpu(host: &Host, options: &Options) -> Result<Arc<Gpu>, String> {
    // SAFETY: the host's objects outlive the Gpu (dropped before they are destroyed).
    unsafe {
        Gpu::from_host(
            HostVulkan {
                entry: host.entry.clone(),
                instance: host.instance.clone(),
                physical_device: host.physical,
                device: host.device.clone(),
                queue: host.queue,
                queue_family: host.family,
                enabled_features: EnabledFeatures {
                    shader_output_layer: options.shader_output_layer,
                    ..EnabledFeatures::ALL
                },
            },
            &GpuOptions::default(),
        )
    }
    .map_err(|e| e.to_string())
}

/// The host's own objects for one run, made once translucent has accepted the device and
/// destroyed by the host (`destroy`) after translucent is gone.
struct Engine<'a> {
    host: &'a Host,
    /// The linear colour target and the depth target, shared with translucent.
    color: HostImage,
    depth: HostImage,
    /// The post pass's 8-bit image.
    ldr: HostImage,
    /// Host copies of `color` and of `ldr`.
    linear_readback: Mapped,
    ldr_readback: Mapped,
    /// The ground quad's vertices.
    quad: Mapped,
    ground: Ground,
    /// The far plane's depth, which the engine clears its depth to (`Options::depth`).
    far: f32,
    pool: vk::CommandPool,
    /// The one command buffer every frame is recorded into, and its fence.
    cmd: vk::CommandBuffer,
    fence: vk::Fence,
}

/// Stages and accesses on one side of a barrier.
type Scope = (vk::PipelineStageFlags2, vk::AccessFlags2);

/// Before a frame, nothing is known of an image's last use: wait on everything.
fn anything() -> Scope {
    (vk::PipelineStageFlags2::ALL_COMMANDS, vk::AccessFlags2::MEMORY_READ | vk::AccessFlags2::MEMORY_WRITE)
}

/// The colour target drawn to (by the host's quad and by translucent).
fn color_attachment() -> Scope {
    (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE)
}

/// The post pass reading an image (the blit, the copies to host memory).
fn transfer_read() -> Scope {
    (vk::PipelineStageFlags2::BLIT | vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ)
}

/// The blit writing the 8-bit image.
fn blit_write() -> Scope {
    (vk::PipelineStageFlags2::BLIT, vk::AccessFlags2::TRANSFER_WRITE)
}

/// The whole of a colour image's one mip level and layer, for blits and copies.
fn color_layers() -> vk::ImageSubresourceLayers {
    vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1)
}

impl<'a> Engine<'a> {
    fn new(host: &'a Host, options: &Options) -> Engine<'a> {
        let device = &host.device;
        let color = host.image(
            COLOR_FORMAT,
            vk::ImageUsageFlags::COLOR_ATTACHMENT | vk::ImageUsageFlags::TRANSFER_SRC,
            vk::ImageAspectFlags::COLOR,
        );
        let depth =
            host.image(DEPTH_FORMAT, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT, vk::ImageAspectFlags::DEPTH);
        let ldr = host.image(
            vk::Format::R8G8B8A8_UNORM,
            // SAMPLED only so that it may have a view like the others; the post pass blits.
            vk::ImageUsageFlags::TRANSFER_DST | vk::ImageUsageFlags::TRANSFER_SRC | vk::ImageUsageFlags::SAMPLED,
            vk::ImageAspectFlags::COLOR,
        );
        let pixels = (SIZE * SIZE) as u64;
        let linear_readback = host.readback(16 * pixels);
        let ldr_readback = host.readback(4 * pixels);
        let r = 0.05f32;
        let y = options.ground_y;
        let vertices = [[-r, y, -r], [-r, y, r], [r, y, -r], [r, y, r]];
        let quad = host.readback(size_of_val(&vertices) as u64);
        // SAFETY: the mapping is 48 bytes long.
        unsafe {
            std::ptr::copy_nonoverlapping(vertices.as_ptr().cast::<u8>(), quad.ptr.cast::<u8>(), size_of_val(&vertices))
        };
        let ground = Ground::new(device, options.depth.compare);
        // SAFETY: valid create infos; destroyed in `destroy`.
        let pool = unsafe {
            device.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(host.family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }
        .unwrap();
        // SAFETY: `pool` was just created on this device and only this `Engine` uses it; the
        // buffer is freed with the pool in `destroy`.
        let cmd = unsafe {
            device.allocate_command_buffers(
                &vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1),
            )
        }
        .unwrap()[0];
        // SAFETY: default create info on the live device; destroyed in `destroy`.
        let fence = unsafe { device.create_fence(&vk::FenceCreateInfo::default(), None) }.unwrap();
        let far = options.depth.far();
        Engine { host, color, depth, ldr, linear_readback, ldr_readback, quad, ground, far, pool, cmd, fence }
    }

    /// One frame of the host: clear, its quad, then whatever `between` records, then its post
    /// pass, submitted and waited on. Returns the linear image and the 8-bit one.
    fn frame(&self, view_proj: Mat4, between: &mut dyn FnMut(vk::CommandBuffer)) -> (Vec<f32>, Vec<u8>) {
        self.begin();
        self.draw_ground(view_proj);
        between(self.cmd);
        // The host's post pass: the linear image to 8 bits by a blit, both copied to host memory.
        self.blit_to_ldr();
        self.copy_to_host();
        self.submit_and_wait();
        self.read_back()
    }

    /// Starts the command buffer and moves both targets into their attachment layouts (their
    /// contents are cleared, so the old layout is left undefined).
    fn begin(&self) {
        let (device, cmd) = (&self.host.device, self.cmd);
        // SAFETY: the command buffer is idle (the previous submission was waited on).
        unsafe {
            device.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()).unwrap();
            device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
        }
        let depth_attach = (
            vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
            vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
        );
        barrier(
            device,
            cmd,
            self.color.image,
            vk::ImageAspectFlags::COLOR,
            (vk::ImageLayout::UNDEFINED, vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL),
            anything(),
            color_attachment(),
        );
        barrier(
            device,
            cmd,
            self.depth.image,
            vk::ImageAspectFlags::DEPTH,
            (vk::ImageLayout::UNDEFINED, vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL),
            anything(),
            depth_attach,
        );
    }

    /// The host's own geometry: both targets cleared, then the ground quad, depth-tested and
    /// depth-written so that translucent's passes test against it.
    fn draw_ground(&self, view_proj: Mat4) {
        let (device, cmd) = (&self.host.device, self.cmd);
        let extent = vk::Extent2D { width: SIZE, height: SIZE };
        let colors = [vk::RenderingAttachmentInfo::default()
            .image_view(self.color.view)
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: [0.0, 0.0, 0.0, 1.0] } })];
        let depth_info = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view)
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth: self.far, stencil: 0 } });
        let rendering = vk::RenderingInfo::default()
            .render_area(extent.into())
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth_info);
        let push = GroundPush { view_proj: view_proj.to_cols_array_2d(), color: GROUND };
        // SAFETY: `cmd` is recording; the attachments are in the layouts `begin` set.
        unsafe {
            device.cmd_begin_rendering(cmd, &rendering);
            device.cmd_bind_pipeline(cmd, vk::PipelineBindPoint::GRAPHICS, self.ground.pipeline);
            let viewport = vk::Viewport {
                x: 0.0,
                y: 0.0,
                width: SIZE as f32,
                height: SIZE as f32,
                min_depth: 0.0,
                max_depth: 1.0,
            };
            device.cmd_set_viewport(cmd, 0, &[viewport]);
            device.cmd_set_scissor(cmd, 0, &[extent.into()]);
            device.cmd_push_constants(
                cmd,
                self.ground.layout,
                vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
                0,
                bytemuck::bytes_of(&push),
            );
            device.cmd_bind_vertex_buffers(cmd, 0, &[self.quad.buffer], &[0]);
            device.cmd_draw(cmd, 4, 1, 0, 0);
            device.cmd_end_rendering(cmd);
        }
    }

    /// The post pass's first half: the linear image (after translucent's writes) blitted into
    /// the 8-bit one, which is made a transfer destination for it.
    fn blit_to_ldr(&self) {
        let (device, cmd) = (&self.host.device, self.cmd);
        barrier(
            device,
            cmd,
            self.color.image,
            vk::ImageAspectFlags::COLOR,
            (vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
            color_attachment(),
            transfer_read(),
        );
        barrier(
            device,
            cmd,
            self.ldr.image,
            vk::ImageAspectFlags::COLOR,
            (vk::ImageLayout::UNDEFINED, vk::ImageLayout::TRANSFER_DST_OPTIMAL),
            anything(),
            blit_write(),
        );
        let layers = color_layers();
        let corners = [vk::Offset3D::default(), vk::Offset3D { x: SIZE as i32, y: SIZE as i32, z: 1 }];
        let blit = [vk::ImageBlit::default()
            .src_subresource(layers)
            .src_offsets(corners)
            .dst_subresource(layers)
            .dst_offsets(corners)];
        // SAFETY: layouts as the barriers set.
        unsafe {
            device.cmd_blit_image(
                cmd,
                self.color.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.ldr.image,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                &blit,
                vk::Filter::NEAREST,
            );
        }
    }

    /// The post pass's second half: both images copied into their mapped buffers, and those
    /// writes made visible to the host's reads after the fence.
    fn copy_to_host(&self) {
        let (device, cmd) = (&self.host.device, self.cmd);
        let region = [vk::BufferImageCopy::default().image_subresource(color_layers()).image_extent(vk::Extent3D {
            width: SIZE,
            height: SIZE,
            depth: 1,
        })];
        // SAFETY: the linear image is a transfer source (`blit_to_ldr`); the buffers hold one
        // tightly packed image each.
        unsafe {
            device.cmd_copy_image_to_buffer(
                cmd,
                self.color.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.linear_readback.buffer,
                &region,
            );
        }
        barrier(
            device,
            cmd,
            self.ldr.image,
            vk::ImageAspectFlags::COLOR,
            (vk::ImageLayout::TRANSFER_DST_OPTIMAL, vk::ImageLayout::TRANSFER_SRC_OPTIMAL),
            blit_write(),
            transfer_read(),
        );
        let host_read = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        // SAFETY: as above.
        unsafe {
            device.cmd_copy_image_to_buffer(
                cmd,
                self.ldr.image,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                self.ldr_readback.buffer,
                &region,
            );
            device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&host_read));
        }
    }

    /// Ends the frame's recording, submits it and waits on the fence, leaving the command
    /// buffer idle and the fence unsignalled for the next frame.
    fn submit_and_wait(&self) {
        let (device, cmd, fence) = (&self.host.device, self.cmd, self.fence);
        // SAFETY: `cmd` is recording; the fence is unsignalled.
        unsafe {
            device.end_command_buffer(cmd).unwrap();
            let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
            let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
            device.queue_submit2(self.host.queue, &submit, fence).unwrap();
            device.wait_for_fences(&[fence], true, u64::MAX).unwrap();
            device.reset_fences(&[fence]).unwrap();
        }
    }

    /// The linear image and the 8-bit one, from the mapped buffers.
    fn read_back(&self) -> (Vec<f32>, Vec<u8>) {
        let pixels = (SIZE * SIZE) as usize;
        // SAFETY: the mappings hold the copies, finished at the fence.
        unsafe {
            (
                std::slice::from_raw_parts(self.linear_readback.ptr.cast::<f32>(), 4 * pixels).to_vec(),
                std::slice::from_raw_parts(self.ldr_readback.ptr.cast::<u8>(), 4 * pixels).to_vec(),
            )
        }
    }

    fn destroy(self) {
        let device = &self.host.device;
        // SAFETY: the device is idle (every submission was waited on); the host destroys its own.
        unsafe {
            device.device_wait_idle().unwrap();
            device.destroy_fence(self.fence, None);
            device.destroy_command_pool(self.pool, None);
            device.destroy_pipeline(self.ground.pipeline, None);
            device.destroy_pipeline_layout(self.ground.layout, None);
            for mapped in [&self.linear_readback, &self.ldr_readback, &self.quad] {
                device.destroy_buffer(mapped.buffer, None);
                device.free_memory(mapped.memory, None);
            }
        }
        for image in [&self.color, &self.depth, &self.ldr] {
            self.host.destroy_image(image);
        }
    }
}

/// translucent's part of the run: its renderers on the host's device, recorded into the host's
/// frames, then the host's quad drawn once more after translucent is gone. It takes the Gpu so
/// that it is dropped here, on an error too, before the host destroys its own objects.
fn render_frames(engine: &Engine, gpu: Arc<Gpu>, options: &Options) -> Result<Run, String> {
    let target = TargetDesc::Host { color_format: COLOR_FORMAT, depth_format: DEPTH_FORMAT };
    let renderer_options = RendererOptions { depth: options.depth, ..RendererOptions::default() };
    let prepare = |text: &str| {
        let scene = Scene::parse(text, "embedded scene", None).map_err(|e| e.to_string())?;
        let mut prepared = PreparedScene::new(&scene, &Overrides::default()).map_err(|e| e.to_string())?;
        // The transport kernels `model = "auto"` chose, walked once and cached as the CLI's are.
        let dir = translucent::reference::truth::default_cache_dir();
        let settings = translucent::reference::rte_mesh::KernelSettings::default();
        translucent::reference::transport_cache::attach(&mut prepared.objects, &settings, &dir, &|_, _, _| {})
            .map_err(|e| e.to_string())?;
        Ok::<_, String>(prepared)
    };
    let prepared = prepare(SPHERE_SCENE)?;
    let renderer_for = |scene| Renderer::with_options(&gpu, scene, target, renderer_options).map_err(|e| e.to_string());
    let mut renderer = renderer_for(prepared.clone())?;
    let mut second = if options.second_renderer { Some(renderer_for(prepare(SECOND_SCENE)?)?) } else { None };
    let extent = vk::Extent2D { width: SIZE, height: SIZE };
    const SINGLE: vk::SampleCountFlags = vk::SampleCountFlags::TYPE_1;
    // Each image with its format and size, which translucent checks against its pipelines.
    let host_target = HostTarget {
        color: HostAttachment { view: engine.color.view, format: COLOR_FORMAT, extent, samples: SINGLE },
        depth: HostAttachment { view: engine.depth.view, format: DEPTH_FORMAT, extent, samples: SINGLE },
        resolve: None,
        extent,
        offset: vk::Offset2D::default(),
        sync: HostSync::Attachments,
        load: true,
    };
    let mut frames = Vec::new();
    for i in 0..options.frames {
        let camera = camera_of(&prepared, i, options.depth);
        if i > 0 {
            renderer.edit(SceneEdit::Camera(camera)).map_err(|e| e.to_string())?;
            if let Some(s) = second.as_mut() {
                s.edit(SceneEdit::Camera(camera)).map_err(|e| e.to_string())?;
            }
        }
        frames.push(embedded_frame(engine, &mut renderer, second.as_mut(), &host_target, camera)?);
    }
    drop(second);
    drop(renderer);
    drop(gpu);
    // The host's device after translucent is gone: it still draws the quad.
    let camera = camera_of(&prepared, 0, options.depth);
    let (after_drop, _) = engine.frame(camera.projection * camera.view, &mut |_| {});
    Ok(Run { frames, after_drop, validation_messages: 0 })
}

/// One host frame with every renderer recorded between the host's quad and its post pass, and
/// the first renderer's timings read after the host's fence.
fn embedded_frame(
    engine: &Engine,
    renderer: &mut Renderer,
    mut second: Option<&mut Renderer>,
    host_target: &HostTarget,
    camera: CameraView,
) -> Result<Frame, String> {
    let mut recorded = Vec::new();
    let mut error = None;
    let (linear, rgba8) = engine.frame(camera.projection * camera.view, &mut |cmd| {
        for r in std::iter::once(&mut *renderer).chain(second.as_deref_mut()) {
            match r.record_frame(cmd, Some(host_target)) {
                Ok(frame) => recorded.push(frame),
                Err(e) => error = Some(e.to_string()),
            }
        }
    });
    if let Some(e) = error {
        return Err(e);
    }
    let timings = renderer.read_timings(&recorded[0]).map_err(|e| e.to_string())?.passes;
    let timings = timings.into_iter().map(|(p, ms)| (p.name().to_string(), ms)).collect();
    Ok(Frame { linear, rgba8, passes: recorded[0].passes.clone(), timings })
}

/// Write frame `i`'s post-processed image as a PNG.
pub fn write_png(path: &Path, frame: &Frame) -> Result<(), String> {
    image::RgbaImage::from_raw(SIZE, SIZE, frame.rgba8.clone())
        .ok_or("image size")?
        .save(path)
        .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

#[allow(dead_code)] // tests/embed.rs includes this file for `run`
fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| ".".into());
    let run = match run(&Options { second_renderer: true, ..Options::default() }) {
        Ok(run) => run,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
    };
    for (i, frame) in run.frames.iter().enumerate() {
        let path = Path::new(&out).join(format!("embed-{i}.png"));
        if let Err(e) = write_png(&path, frame) {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
        let passes: Vec<&str> = frame.passes.iter().map(|p| p.name()).collect();
        let ms: f64 = frame.timings.iter().map(|(_, ms)| ms).sum();
        println!("wrote {} (translucent recorded {}; {ms:.2} ms of GPU time)", path.display(), passes.join(", "));
    }
}
