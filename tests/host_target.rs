//! The embedding API's boundary, in safe calls only, validation on: what a host gets wrong is
//! an error naming it, or is made correct; nothing crashes or raises a validation message
//! (issue 28's tables). The host here is tests/common/host.rs on the tests' own `Gpu`.

mod common;
#[path = "../examples/embed.rs"]
#[allow(dead_code)]
mod embed;

use ash::vk;
use common::host::{self, HostCommands, HostImages};
use std::sync::Arc;
use translucent::SceneEdit;
use translucent::gpu::ImageBarrier;
use translucent::gpu::{
    Access, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorSet, EnabledFeatures, Gpu, GpuOptions, HostVulkan,
    Named, memory_barrier,
};
use translucent::render::plan::Pass;
use translucent::{
    CameraView, Change, DeclaredImage, DepthConvention, DepthTest, HostSync, HostTarget, ImageState, Overrides,
    PreparedScene, RenderError, Renderer, RendererOptions, Scene, TargetDesc,
};

/// The embed example's sphere scene.
fn sphere() -> PreparedScene {
    PreparedScene::new(&Scene::parse(embed::SPHERE_SCENE, "sphere", None).unwrap(), &Overrides::default()).unwrap()
}

fn host_renderer(gpu: &Arc<Gpu>) -> Renderer {
    Renderer::with_target(gpu, sphere(), host::desc()).unwrap()
}

fn extent(width: u32, height: u32) -> vk::Extent2D {
    vk::Extent2D { width, height }
}

/// `record_frame` into a submission of its own, waited for.
fn record(
    gpu: &Arc<Gpu>,
    renderer: &mut Renderer,
    images: &HostImages,
    target: &translucent::HostTarget,
) -> Result<translucent::RecordedFrame, RenderError> {
    gpu.one_shot("host frame", |cmd| {
        images.to_attachments(gpu, cmd);
        renderer.record_frame(cmd, Some(target))
    })
    .unwrap()
}

#[test]
fn a_host_target_larger_than_its_images_or_empty_is_refused_naming_the_sizes() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 64, 64, host::COLOR);
        let error = record(gpu, &mut renderer, &images, &images.target(extent(128, 64))).unwrap_err();
        assert!(matches!(error, RenderError::HostTargetTooLarge { what: "the colour image", .. }), "{error}");
        assert!(error.to_string().contains("128x64") && error.to_string().contains("64x64"), "{error}");
        let mut target = images.whole();
        target.depth.extent = extent(32, 32);
        let error = record(gpu, &mut renderer, &images, &target).unwrap_err();
        assert!(error.to_string().contains("the depth image (32x32)"), "{error}");
        let error = record(gpu, &mut renderer, &images, &images.target(extent(0, 0))).unwrap_err();
        assert!(matches!(error, RenderError::HostTargetEmpty { extent: [0, 0] }), "{error}");
        // Nothing was recorded by the refused calls: the first frame still runs everything.
        let frame = record(gpu, &mut renderer, &images, &images.whole()).unwrap();
        assert!(frame.passes.contains(&Pass::Gather), "{:?}", frame.passes);
    });
}

#[test]
fn a_host_image_of_another_format_than_its_target_desc_is_refused() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 32, 32, vk::Format::R8G8B8A8_UNORM);
        let error = record(gpu, &mut renderer, &images, &images.whole()).unwrap_err();
        assert!(
            matches!(error, RenderError::HostTargetFormat { which: "colour", given: vk::Format::R8G8B8A8_UNORM, .. }),
            "{error}"
        );
        assert!(error.to_string().contains("R16G16B16A16_SFLOAT"), "{error}");
    });
}

#[test]
fn dropping_the_renderer_before_the_hosts_fence_waits_for_its_frame() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 64, 64, host::COLOR);
        let commands = HostCommands::begin(gpu);
        images.to_attachments(gpu, commands.cmd);
        renderer.record_frame(commands.cmd, Some(&images.whole())).unwrap();
        commands.submit();
        drop(renderer);
        // Drop waited: the frame (a first one, every pass) is done, and nothing was destroyed
        // under it (with_gpu fails on any validation message).
        assert!(commands.finished(), "the renderer was destroyed while its frame was in flight");
    });
}

#[test]
fn read_timings_before_the_fence_is_an_error_not_a_wait() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 64, 64, host::COLOR);
        let commands = HostCommands::begin(gpu);
        images.to_attachments(gpu, commands.cmd);
        let frame = renderer.record_frame(commands.cmd, Some(&images.whole())).unwrap();
        // Recorded, not yet submitted: before any fence. (A submission held back on the GPU
        // cannot be staged on lavapipe, which runs a waiting command buffer to its end.)
        let early = renderer.read_timings(&frame);
        assert!(matches!(early, Err(RenderError::FrameNotDone(1))), "{early:?}");
        commands.submit();
        commands.wait();
        let timings = renderer.read_timings(&frame).unwrap();
        assert_eq!(timings.passes.len(), frame.passes.len(), "every pass timed after the fence");
    });
}

#[test]
fn read_timings_of_a_frame_whose_queries_were_reused_is_refused() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 32, 32, host::COLOR);
        let frames: Vec<_> = (0..=Renderer::FRAMES_IN_FLIGHT)
            .map(|_| record(gpu, &mut renderer, &images, &images.whole()).unwrap())
            .collect();
        let error = renderer.read_timings(&frames[0]).unwrap_err();
        let by = Renderer::FRAMES_IN_FLIGHT as u64 + 1;
        assert!(matches!(error, RenderError::TimingsOverwritten { frame: 1, by: b, .. } if b == by), "{error}");
        assert!(!renderer.read_timings(frames.last().unwrap()).unwrap().passes.is_empty());
        // A frame of another renderer is not read from this one's queries.
        let other = host_renderer(gpu);
        assert!(matches!(other.read_timings(&frames[1]), Err(RenderError::ForeignFrame)));
    });
}

#[test]
fn two_frames_recorded_into_one_command_buffer_draw_what_two_submissions_draw() {
    common::with_gpu(|gpu| {
        let prepared = sphere();
        let turned = CameraView::of_scene(&prepared).orbited(glam::Vec3::ZERO, 25.0);
        let (a, b) = (HostImages::new(gpu, 64, 64, host::COLOR), HostImages::new(gpu, 64, 64, host::COLOR));
        let mut one = host_renderer(gpu);
        gpu.one_shot("two frames", |cmd| {
            a.to_attachments(gpu, cmd);
            b.to_attachments(gpu, cmd);
            one.record_frame(cmd, Some(&a.whole())).unwrap();
            one.edit(SceneEdit::Camera(turned)).unwrap();
            one.record_frame(cmd, Some(&b.whole())).unwrap()
        })
        .unwrap();
        let (first, second) = (a.read_color(), b.read_color());
        let mut apart = host_renderer(gpu);
        let c = HostImages::new(gpu, 64, 64, host::COLOR);
        record(gpu, &mut apart, &c, &c.whole()).unwrap();
        assert_eq!(first, c.read_color(), "the first frame differs from the same frame submitted alone");
        apart.edit(SceneEdit::Camera(turned)).unwrap();
        record(gpu, &mut apart, &c, &c.whole()).unwrap();
        assert_eq!(second, c.read_color(), "the second frame differs from the same frame submitted alone");
        assert_ne!(first, second, "the camera turned between them");
    });
}

#[test]
fn levels_of_detail_follow_the_host_targets_extent_not_the_scene_resolution() {
    common::with_gpu(|gpu| {
        let levels = |resolution: u32, target: u32| {
            let overrides = Overrides { resolution: Some([resolution; 2]), samples: Some(50), ..Overrides::default() };
            let prepared = PreparedScene::new(&Scene::builtin(), &overrides).unwrap();
            let mut renderer = Renderer::with_target(gpu, prepared, host::desc()).unwrap();
            let images = HostImages::new(gpu, target, target, host::COLOR);
            record(gpu, &mut renderer, &images, &images.whole()).unwrap();
            renderer.plan(Change::Camera).objects.iter().map(|o| o.level).collect::<Vec<_>>()
        };
        let (small_scene, large_scene) = (levels(64, 128), levels(512, 128));
        let tiny = levels(512, 16);
        eprintln!(
            "levels: scene 64 / 512 at a 128x128 target {small_scene:?} / {large_scene:?}; 16x16 target {tiny:?}"
        );
        assert_eq!(small_scene, large_scene, "the same 128x128 target, scene resolution 64 and 512");
        assert!(
            tiny.iter().zip(&large_scene).all(|(t, l)| t >= l) && tiny != large_scene,
            "a 16x16 target should draw coarser levels than a 128x128 one: {tiny:?} against {large_scene:?}"
        );
    });
}

/// The error `Gpu::from_host` gives for `gpu`'s own handles declared with `queue_family` and
/// `enabled_features` (which the test makes wrong).
fn refused_host(gpu: &Arc<Gpu>, queue_family: u32, enabled_features: EnabledFeatures) -> String {
    let host = HostVulkan {
        entry: gpu.entry().clone(),
        instance: gpu.instance().clone(),
        physical_device: gpu.physical_device(),
        device: gpu.device().clone(),
        queue: *gpu.queue(),
        queue_family,
        enabled_features,
    };
    // SAFETY: the handles are the live `gpu`'s; the call fails before it makes anything.
    unsafe { Gpu::from_host(host, &GpuOptions::default()) }.err().expect("refused").to_string()
}

#[test]
fn a_host_device_lacking_several_features_gets_all_of_them_named() {
    common::with_gpu(|gpu| {
        let features = EnabledFeatures { synchronization2: false, shader_output_layer: false, ..EnabledFeatures::ALL };
        let error = refused_host(gpu, gpu.queue_family(), features);
        assert!(error.contains("synchronization2, shaderOutputLayer features"), "{error}");
    });
}

/// Issue 47, defect 5: a queue family past the device's is named as not existing, with the
/// families there are, not as one that "does not do graphics and compute".
#[test]
fn a_host_queue_family_that_does_not_exist_is_named_with_the_families_there_are() {
    common::with_gpu(|gpu| {
        let error = refused_host(gpu, 7, EnabledFeatures::ALL);
        assert!(error.contains("queue family 7 does not exist (the device has"), "{error}");
    });
}

/// The messages of a validated `Gpu` with synchronisation validation on, after `f` and the
/// device are done.
fn sync_messages(f: impl FnOnce(&Arc<Gpu>)) -> Vec<String> {
    let options = GpuOptions { sync_validation: true, ..common::validated_options() };
    let gpu = Gpu::new(&options).expect("a Vulkan device with validation layers (bash scripts/setup)");
    let counters = gpu.validation();
    f(&gpu);
    assert_eq!(Arc::strong_count(&gpu), 1, "a GPU resource outlived the test body");
    drop(gpu);
    counters.messages()
}

/// The sphere's light turned about the vertical axis by `degrees`.
fn turned_light(renderer: &Renderer, degrees: f32) -> translucent::scene::Light {
    let mut light = renderer.scene().scene.file.lights[0].clone();
    if let translucent::scene::Light::Directional { direction, .. } = &mut light {
        *direction = glam::Quat::from_rotation_y(degrees.to_radians()).mul_vec3(glam::Vec3::from(*direction)).into();
    }
    light
}

#[test]
fn recorded_exitance_without_shading_equals_what_record_frame_gathers() {
    common::with_gpu(|gpu| {
        let images = HostImages::new(gpu, 64, 64, host::COLOR);
        let (mut framed, mut alone) = (host_renderer(gpu), host_renderer(gpu));
        for step in 0..2 {
            if step == 1 {
                // A partial frame: one light moved, its shadows, splat and gather rerun.
                let light = turned_light(&framed, 40.0);
                framed.edit(SceneEdit::Light { index: 0, light: light.clone() }).unwrap();
                alone.edit(SceneEdit::Light { index: 0, light }).unwrap();
            }
            record(gpu, &mut framed, &images, &images.whole()).unwrap();
            let frame = gpu
                .one_shot("exitance", |cmd| alone.record_exitance(cmd, extent(64, 64), &[Access::HostRead]))
                .unwrap()
                .unwrap();
            assert!(frame.passes.contains(&Pass::Gather), "step {step}: {:?}", frame.passes);
            assert!(!frame.passes.contains(&Pass::Shade), "step {step}: shading recorded: {:?}", frame.passes);
            let framed_exitance: Vec<[f32; 4]> = framed.scene_data().buffers().exitance().read().unwrap();
            let exitance: Vec<[f32; 4]> = alone.scene_data().buffers().exitance().read().unwrap();
            assert!(exitance.iter().filter(|e| e[0] > 0.0).count() > exitance.len() / 4, "step {step}: little lit");
            assert_eq!(exitance, framed_exitance, "step {step}: record_exitance and record_frame differ");
        }
        // Nothing changed since: nothing to record, and shading still follows in record_frame.
        let idle = gpu.one_shot("idle", |cmd| alone.record_exitance(cmd, extent(64, 64), &[])).unwrap().unwrap();
        assert!(idle.passes.is_empty(), "{:?}", idle.passes);
    });
}

#[test]
fn record_exitance_refuses_an_own_target_a_write_and_an_empty_extent() {
    common::with_gpu(|gpu| {
        let mut host = host_renderer(gpu);
        let commands = HostCommands::begin(gpu);
        let error = host.record_exitance(commands.cmd, extent(64, 64), &[Access::ComputeWrite]).unwrap_err();
        assert!(matches!(error, RenderError::ExitanceReader(Access::ComputeWrite)), "{error}");
        let error = host.record_exitance(commands.cmd, extent(0, 64), &[]).unwrap_err();
        assert!(matches!(error, RenderError::HostTargetEmpty { extent: [0, 64] }), "{error}");
        let mut own = Renderer::new(gpu, sphere()).unwrap();
        let error = own.record_exitance(commands.cmd, extent(64, 64), &[]).unwrap_err();
        assert!(matches!(error, RenderError::ExitanceOnOwnTarget), "{error}");
        // Nothing was recorded: the first frame still runs everything.
        let frame = host.record_exitance(commands.cmd, extent(64, 64), &[]).unwrap();
        assert!(frame.passes.contains(&Pass::Splat), "{:?}", frame.passes);
        commands.submit();
        commands.wait();
    });
}

/// The host's compute reader of the exitance (glsl/test/exitance_probe.comp: a copy into a
/// buffer of its own), recorded into `cmd` after `record_exitance`, then read after the fence.
struct HostReader {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    out: Buffer,
    count: u32,
}

impl HostReader {
    fn new(gpu: &Arc<Gpu>, renderer: &Renderer) -> HostReader {
        let pipeline = ComputePipeline::new(gpu, "test/exitance_probe.comp").unwrap();
        let exitance = &renderer.scene_data().buffers().exitance();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let out = Buffer::new(gpu, &BufferDesc::readback("host's copy", exitance.size(), usage)).unwrap();
        let set = pipeline
            .descriptor_set(&[
                Named { name: "Exitance", binding: Binding::Buffer(exitance) },
                Named { name: "Probe", binding: Binding::Buffer(&out) },
            ])
            .unwrap();
        HostReader { pipeline, set, out, count: (exitance.size() / 16) as u32 }
    }

    fn record(&self, gpu: &Gpu, cmd: vk::CommandBuffer) {
        self.pipeline.dispatch(cmd, &self.set, &self.count, [self.count, 1, 1]);
        memory_barrier(gpu.device(), cmd, &[Access::ComputeWrite], &[Access::HostRead]);
    }
}

/// Two `record_exitance` calls in one command buffer, a light turned between them, each
/// followed by a host compute pass reading the exitance as `readers` declares (nothing else
/// of the host's orders them); the values each read.
fn two_exitances_read_by_the_host(gpu: &Arc<Gpu>, readers: &[Access]) -> [Vec<[f32; 4]>; 2] {
    let mut renderer = host_renderer(gpu);
    let light = turned_light(&renderer, 60.0);
    let probes = [HostReader::new(gpu, &renderer), HostReader::new(gpu, &renderer)];
    gpu.one_shot("host frame", |cmd| {
        renderer.record_exitance(cmd, extent(64, 64), readers).unwrap();
        probes[0].record(gpu, cmd);
        // The next gather overwrites what the host's pass reads: it must wait for that pass.
        renderer.edit(SceneEdit::Light { index: 0, light }).unwrap();
        renderer.record_exitance(cmd, extent(64, 64), readers).unwrap();
        probes[1].record(gpu, cmd);
    })
    .unwrap();
    let last: Vec<[f32; 4]> = renderer.scene_data().buffers().exitance().read().unwrap();
    let read = probes.map(|p| p.out.read::<[f32; 4]>().unwrap());
    assert_eq!(read[1], last, "the host's second read holds the second gather");
    read
}

#[test]
fn a_host_reader_declared_to_record_exitance_needs_no_barrier_of_its_own() {
    let messages = sync_messages(|gpu| {
        let [first, second] = two_exitances_read_by_the_host(gpu, &[Access::ComputeRead]);
        assert_ne!(first, second, "the light turned between the two gathers");
        assert!(first.iter().filter(|e| e[0] > 0.0).count() > first.len() / 4, "the first read holds a gather");
    });
    assert!(messages.is_empty(), "validation:\n{}", messages.join("\n"));
}

#[test]
fn the_same_reader_undeclared_is_a_hazard_synchronisation_validation_reports() {
    // The control: the layer sees the host's pass, so the clean run above means something.
    let messages = sync_messages(|gpu| {
        two_exitances_read_by_the_host(gpu, &[]);
    });
    assert!(messages.iter().any(|m| m.contains("SYNC-HAZARD")), "no hazard reported: {messages:?}");
}

#[test]
fn a_host_chosen_frames_in_flight_count_is_when_timings_are_overwritten() {
    common::with_gpu(|gpu| {
        for in_flight in [1, 5] {
            let options = RendererOptions { frames_in_flight: in_flight, ..RendererOptions::default() };
            let mut renderer = Renderer::with_options(gpu, sphere(), host::desc(), options).unwrap();
            let images = HostImages::new(gpu, 32, 32, host::COLOR);
            let mut frames: Vec<_> =
                (0..in_flight).map(|_| record(gpu, &mut renderer, &images, &images.whole()).unwrap()).collect();
            for f in &frames {
                assert!(renderer.read_timings(f).is_ok(), "{in_flight} in flight: frame {} refused", f.generation());
            }
            frames.push(record(gpu, &mut renderer, &images, &images.whole()).unwrap());
            let error = renderer.read_timings(&frames[0]).unwrap_err();
            let by = in_flight as u64 + 1;
            assert!(
                matches!(error, RenderError::TimingsOverwritten { frame: 1, by: b, in_flight: n } if b == by && n == in_flight),
                "{error}"
            );
            for f in &frames[1..] {
                assert!(renderer.read_timings(f).is_ok(), "{in_flight} in flight: frame {} refused", f.generation());
            }
        }
    });
}

#[test]
fn renderer_options_out_of_range_are_refused_naming_them() {
    common::with_gpu(|gpu| {
        let with = |options| Renderer::with_options(gpu, sphere(), host::desc(), options).err().expect("refused");
        for given in [0, Renderer::MAX_FRAMES_IN_FLIGHT + 1] {
            let error = with(RendererOptions { frames_in_flight: given, ..RendererOptions::default() });
            assert!(matches!(error, RenderError::FramesInFlight { given: g, .. } if g == given), "{error}");
        }
        let wrong = DepthTest { convention: DepthConvention::Reversed, compare: vk::CompareOp::LESS_OR_EQUAL };
        let error = with(RendererOptions { depth: wrong, ..RendererOptions::default() });
        assert!(error.to_string().contains("GREATER or GREATER_OR_EQUAL"), "{error}");
        let wrong = DepthTest { convention: DepthConvention::Standard, compare: vk::CompareOp::NEVER };
        assert!(matches!(
            with(RendererOptions { depth: wrong, ..RendererOptions::default() }),
            RenderError::DepthCompare { .. }
        ));
    });
}

/// RGBA32F host images, so that images compare in linear radiance.
const LINEAR: vk::Format = vk::Format::R32G32B32A32_SFLOAT;

/// A renderer of the sphere into RGBA32F host images with `depth`'s test.
fn linear_renderer(gpu: &Arc<Gpu>, depth: DepthTest) -> Renderer {
    let desc = TargetDesc::Host { color_format: LINEAR, depth_format: host::DEPTH };
    Renderer::with_options(gpu, sphere(), desc, RendererOptions { depth, ..RendererOptions::default() }).unwrap()
}

/// One frame of `renderer` into `target` of `images`, after the host cleared them (colour,
/// depth) when `clear` says; the colour image afterwards, RGBA f32 per pixel.
fn draw(
    gpu: &Arc<Gpu>,
    renderer: &mut Renderer,
    images: &HostImages,
    target: &HostTarget,
    clear: Option<([f32; 4], f32)>,
) -> Vec<[f32; 4]> {
    gpu.one_shot("host frame", |cmd| {
        images.to_attachments(gpu, cmd);
        if let Some((color, depth)) = clear {
            images.clear(gpu, cmd, color, depth);
        }
        renderer.record_frame(cmd, Some(target))
    })
    .unwrap()
    .unwrap();
    bytemuck::pod_collect_to_vec(&images.read_color())
}

/// The largest difference of two linear images in 8-bit display levels, and how many pixels
/// are lit (not the black background) in `a`.
fn display_difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> (i64, usize) {
    use translucent::render::tonemap::display_value;
    let level = |v: f32| display_value(f64::from(v), 1.0) as i64;
    let max = a.iter().zip(b).flat_map(|(p, q)| (0..3).map(move |c| (level(p[c]) - level(q[c])).abs())).max();
    (max.unwrap_or(0), a.iter().filter(|p| p[0] > 0.0).count())
}

#[test]
fn a_reversed_z_host_draws_what_a_standard_depth_host_draws() {
    common::with_gpu(|gpu| {
        let images = HostImages::new(gpu, 64, 64, LINEAR);
        let standard = draw(gpu, &mut linear_renderer(gpu, DepthTest::STANDARD), &images, &images.whole(), None);
        let mut reversed = linear_renderer(gpu, DepthTest::REVERSED);
        let cleared = draw(gpu, &mut reversed, &images, &images.whole(), None);
        // The host's own reversed-Z depth, cleared to its far plane (0), kept (`load`).
        let mut loaded = images.whole();
        loaded.load = true;
        reversed.edit(SceneEdit::Camera(CameraView::of_scene(reversed.scene()).reversed_depth())).unwrap();
        let kept = draw(gpu, &mut reversed, &images, &loaded, Some(([0.0, 0.0, 0.0, 1.0], 0.0)));
        let (cleared_max, lit) = display_difference(&standard, &cleared);
        let (kept_max, _) = display_difference(&standard, &kept);
        eprintln!(
            "reversed-Z against standard: {lit} lit pixels, largest difference {cleared_max}/255 (cleared), {kept_max}/255 (host's depth)"
        );
        assert!(lit > 64 * 64 / 10, "only {lit} lit pixels: the sphere is not drawn");
        assert!(cleared_max <= 1 && kept_max <= 1, "differences {cleared_max}/255, {kept_max}/255");
        // The control: a standard-depth renderer against that reversed-Z depth draws nothing
        // (issue 28's case), so the images above did depend on the convention.
        let mut standard = linear_renderer(gpu, DepthTest::STANDARD);
        let hidden = draw(gpu, &mut standard, &images, &loaded, Some(([0.0, 0.0, 0.0, 1.0], 0.0)));
        assert_eq!(display_difference(&hidden, &hidden).1, 0, "standard depth drew behind the far plane");
    });
}

#[test]
fn a_host_target_offset_draws_the_same_view_into_that_rectangle_only() {
    common::with_gpu(|gpu| {
        let small = HostImages::new(gpu, 64, 64, LINEAR);
        let whole = draw(gpu, &mut linear_renderer(gpu, DepthTest::STANDARD), &small, &small.whole(), None);
        let (width, height, offset) = (96usize, 80usize, vk::Offset2D { x: 24, y: 10 });
        let large = HostImages::new(gpu, width as u32, height as u32, LINEAR);
        let mut target = large.target(extent(64, 64));
        target.offset = offset;
        let marker = [0.25, 0.5, 0.75, 1.0];
        let mut renderer = linear_renderer(gpu, DepthTest::STANDARD);
        let drawn = draw(gpu, &mut renderer, &large, &target, Some((marker, 1.0)));
        let (x0, y0) = (offset.x as usize, offset.y as usize);
        let inside = |x: usize, y: usize| (x0..x0 + 64).contains(&x) && (y0..y0 + 64).contains(&y);
        let cut: Vec<_> =
            (0..64).flat_map(|y| (0..64).map(move |x| (x, y))).map(|(x, y)| drawn[(y0 + y) * width + x0 + x]).collect();
        let (max, lit) = display_difference(&whole, &cut);
        let outside = (0..height).flat_map(|y| (0..width).map(move |x| (x, y))).filter(|&(x, y)| !inside(x, y));
        let untouched = outside.clone().filter(|&(x, y)| drawn[y * width + x] == marker).count();
        eprintln!(
            "offset target: {lit} lit pixels, largest difference {max}/255 from a 64x64 image; {untouched} of {} outside untouched",
            outside.count()
        );
        assert!(lit > 64 * 64 / 10 && max <= 1, "the rectangle differs from the 64x64 image by up to {max}/255");
        assert_eq!(untouched, width * height - 64 * 64, "pixels outside the render area were written");
        // An area past the image from its offset, or at a negative offset, is refused.
        target.offset = vk::Offset2D { x: 40, y: 10 };
        let error = draw_refused(gpu, &mut renderer, &large, &target);
        assert!(matches!(error, RenderError::HostTargetTooLarge { offset: [40, 10], .. }), "{error}");
        target.offset = vk::Offset2D { x: -1, y: 0 };
        let error = draw_refused(gpu, &mut renderer, &large, &target);
        assert!(matches!(error, RenderError::HostTargetOffset { offset: [-1, 0] }), "{error}");
    });
}

/// `record_frame` into `target` of `images`, which must refuse.
fn draw_refused(gpu: &Arc<Gpu>, renderer: &mut Renderer, images: &HostImages, target: &HostTarget) -> RenderError {
    record(gpu, renderer, images, target).expect_err("refused")
}

/// The state the host's copy of its colour image reads it in.
const COPY_SOURCE: ImageState = ImageState {
    layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
    stages: vk::PipelineStageFlags2::COPY,
    access: vk::AccessFlags2::TRANSFER_READ,
};

/// The state the host's own depth testing uses its depth image in.
fn depth_testing() -> ImageState {
    ImageState {
        layout: vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
        stages: vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS,
        access: vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE,
    }
}

/// The host's copy of its colour image (in TRANSFER_SRC_OPTIMAL) into `to`, made visible to
/// host reads, recorded into `cmd`.
fn copy_color(gpu: &Gpu, cmd: vk::CommandBuffer, images: &HostImages, to: &Buffer) {
    let vk::Extent2D { width, height } = images.color.extent();
    let region = [vk::BufferImageCopy::default()
        .image_subresource(
            vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1),
        )
        .image_extent(vk::Extent3D { width, height, depth: 1 })];
    let layout = vk::ImageLayout::TRANSFER_SRC_OPTIMAL;
    // SAFETY: `cmd` is recording outside rendering; `to` holds the whole image.
    unsafe { gpu.device().cmd_copy_image_to_buffer(cmd, images.color.raw(), layout, to.raw(), &region) };
    memory_barrier(gpu.device(), cmd, &[Access::TransferWrite], &[Access::HostRead]);
}

/// Two frames into one command buffer with declared states, the camera turned between them:
/// the first from new images, not loaded, the second loaded and entered as `second_entry`;
/// each time the colour image is left in TRANSFER_SRC_OPTIMAL and the host copies it with no
/// barrier of its own. The two copies.
fn declared_frames(gpu: &Arc<Gpu>, second_entry: ImageState) -> [Vec<u8>; 2] {
    let images = HostImages::new(gpu, 64, 64, host::COLOR);
    let mut renderer = host_renderer(gpu);
    let size = 64 * 64 * 8;
    let usage = vk::BufferUsageFlags::TRANSFER_DST;
    let copies = [(); 2].map(|_| Buffer::new(gpu, &BufferDesc::readback("host copy", size, usage)).unwrap());
    let declared = |color_entry, depth_entry| HostSync::Declared {
        color: DeclaredImage { image: images.color.raw(), entry: color_entry, exit: COPY_SOURCE },
        depth: DeclaredImage { image: images.depth.raw(), entry: depth_entry, exit: depth_testing() },
    };
    let turned = CameraView::of_scene(renderer.scene()).orbited(glam::Vec3::ZERO, 25.0);
    gpu.one_shot("declared frames", |cmd| {
        let mut target = HostTarget { sync: declared(ImageState::UNUSED, ImageState::UNUSED), ..images.whole() };
        renderer.record_frame(cmd, Some(&target)).unwrap();
        copy_color(gpu, cmd, &images, &copies[0]);
        renderer.edit(SceneEdit::Camera(turned)).unwrap();
        (target.load, target.sync) = (true, declared(second_entry, depth_testing()));
        renderer.record_frame(cmd, Some(&target)).unwrap();
        copy_color(gpu, cmd, &images, &copies[1]);
    })
    .unwrap();
    copies.map(|c| c.read::<u8>().unwrap())
}

/// The same two frames with the default hand-over (attachment layouts), the host's barriers
/// its own: the colour image after each.
fn attachment_frames(gpu: &Arc<Gpu>) -> [Vec<u8>; 2] {
    let images = HostImages::new(gpu, 64, 64, host::COLOR);
    let mut renderer = host_renderer(gpu);
    record(gpu, &mut renderer, &images, &images.whole()).unwrap();
    let first = images.read_color();
    renderer.edit(SceneEdit::Camera(CameraView::of_scene(renderer.scene()).orbited(glam::Vec3::ZERO, 25.0))).unwrap();
    gpu.one_shot("loaded frame", |cmd| {
        let color = vk::ImageAspectFlags::COLOR;
        ImageBarrier::new(images.color.raw(), color, &[Access::TransferRead], &[Access::ColorAttachmentWrite])
            .record(gpu.device(), cmd);
        renderer.record_frame(cmd, Some(&HostTarget { load: true, ..images.whole() })).unwrap();
    })
    .unwrap();
    [first, images.read_color()]
}

#[test]
fn declared_entry_and_exit_states_draw_the_same_frames_with_no_host_barrier() {
    let messages = sync_messages(|gpu| {
        let declared = declared_frames(gpu, COPY_SOURCE);
        let attachments = attachment_frames(gpu);
        assert_eq!(declared[0], attachments[0], "the first frame differs from the attachment hand-over's");
        assert_eq!(declared[1], attachments[1], "the loaded second frame differs from the attachment hand-over's");
        assert_ne!(declared[0], declared[1], "the camera turned between them");
    });
    assert!(messages.is_empty(), "validation:\n{}", messages.join("\n"));
}

#[test]
fn a_wrong_declared_entry_state_is_a_hazard_synchronisation_validation_reports() {
    // The control: the second frame declared as if nothing had used the image since (not the
    // copy), so the rendering's writes do not wait for the copy's reads.
    let stale = ImageState { layout: vk::ImageLayout::TRANSFER_SRC_OPTIMAL, ..ImageState::UNUSED };
    let messages = sync_messages(|gpu| {
        declared_frames(gpu, stale);
    });
    assert!(messages.iter().any(|m| m.contains("SYNC-HAZARD")), "no hazard reported: {messages:?}");
}

#[test]
fn declared_states_that_cannot_be_right_are_refused() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 32, 32, host::COLOR);
        let image = |entry, exit| DeclaredImage { image: images.color.raw(), entry, exit };
        let depth = DeclaredImage { image: images.depth.raw(), entry: ImageState::UNUSED, exit: depth_testing() };
        let cases = [
            (image(ImageState::UNUSED, ImageState::UNUSED), false, "exit layout is UNDEFINED"),
            (image(ImageState::UNUSED, COPY_SOURCE), true, "would be lost"),
            (DeclaredImage { image: vk::Image::null(), ..image(COPY_SOURCE, COPY_SOURCE) }, false, "null"),
        ];
        for (color, load, expected) in cases {
            let target = HostTarget { sync: HostSync::Declared { color, depth }, load, ..images.whole() };
            let error = draw_refused(gpu, &mut renderer, &images, &target);
            assert!(matches!(error, RenderError::HostTargetState { which: "colour", .. }), "{error}");
            assert!(error.to_string().contains(expected), "{error}");
        }
    });
}

/// Whether pixel (x, y) of a 64x64 `image` and its eight neighbours are all lit or all
/// background: away from the silhouette, where multisampling changes nothing.
fn inside_or_outside(image: &[[f32; 4]], x: usize, y: usize) -> bool {
    let lit = |x: usize, y: usize| image[y * 64 + x][0] > 0.0;
    let around = (y.saturating_sub(1)..=(y + 1).min(63))
        .flat_map(|j| (x.saturating_sub(1)..=(x + 1).min(63)).map(move |i| (i, j)));
    let mut states = around.map(|(i, j)| lit(i, j));
    let first = states.next().unwrap_or(false);
    states.all(|s| s == first)
}

#[test]
fn a_multisampled_host_draws_the_single_sampled_image_away_from_the_silhouette() {
    common::with_gpu(|gpu| {
        let single = HostImages::new(gpu, 64, 64, LINEAR);
        let reference = draw(gpu, &mut linear_renderer(gpu, DepthTest::STANDARD), &single, &single.whole(), None);
        let samples = vk::SampleCountFlags::TYPE_4;
        let desc = TargetDesc::Host { color_format: LINEAR, depth_format: host::DEPTH };
        let options = RendererOptions { samples, ..RendererOptions::default() };
        let mut renderer = Renderer::with_options(gpu, sphere(), desc, options).unwrap();
        let (msaa, resolved) =
            (HostImages::multisampled(gpu, 64, 64, LINEAR, samples), HostImages::new(gpu, 64, 64, LINEAR));
        let target = HostTarget { resolve: Some(resolved.whole().color), ..msaa.whole() };
        gpu.one_shot("multisampled frame", |cmd| {
            msaa.to_attachments(gpu, cmd);
            resolved.to_attachments(gpu, cmd);
            renderer.record_frame(cmd, Some(&target))
        })
        .unwrap()
        .unwrap();
        let image: Vec<[f32; 4]> = bytemuck::pod_collect_to_vec(&resolved.read_color());
        let (mut inner, mut outer): (Vec<usize>, Vec<usize>) = (Vec::new(), Vec::new());
        for i in 0..64 * 64 {
            if inside_or_outside(&reference, i % 64, i / 64) { inner.push(i) } else { outer.push(i) }
        }
        let pick = |image: &[[f32; 4]], at: &[usize]| at.iter().map(|&i| image[i]).collect::<Vec<_>>();
        // A pixel a triangle edge crosses is shaded once per triangle and averaged, so even
        // away from the silhouette a few pixels differ: the claim is on the mean and the share.
        let differences: Vec<i64> = inner.iter().map(|&i| display_difference(&[reference[i]], &[image[i]]).0).collect();
        let mean = differences.iter().sum::<i64>() as f64 / inner.len() as f64;
        let within = differences.iter().filter(|&&d| d <= 1).count();
        let (max, lit) = display_difference(&pick(&reference, &inner), &pick(&image, &inner));
        let (edge_max, _) = display_difference(&pick(&reference, &outer), &pick(&image, &outer));
        eprintln!(
            "4x MSAA: {} pixels away from the silhouette ({lit} lit): mean {mean:.3}/255, {within} within 1/255, \
             largest {max}/255; {} at it, up to {edge_max}/255 apart",
            inner.len(),
            outer.len()
        );
        assert!(lit > 64 * 64 / 20, "only {lit} lit pixels");
        assert!(mean <= 1.0 / 16.0, "mean difference {mean:.3}/255 away from the silhouette");
        assert!(within * 100 >= inner.len() * 99, "only {within} of {} pixels within 1/255", inner.len());
        assert!(edge_max > 1, "the silhouette is not antialiased: were 4 samples drawn?");
    });
}

#[test]
fn sample_counts_that_cannot_be_drawn_are_refused() {
    common::with_gpu(|gpu| {
        let options = |samples| RendererOptions { samples, ..RendererOptions::default() };
        let four = vk::SampleCountFlags::TYPE_4;
        let error = Renderer::with_options(gpu, sphere(), TargetDesc::Own, options(four)).err().expect("refused");
        assert!(matches!(error, RenderError::Samples { .. }) && error.to_string().contains("host target"), "{error}");
        let error = Renderer::with_options(gpu, sphere(), host::desc(), options(four | vk::SampleCountFlags::TYPE_1));
        assert!(matches!(error.err(), Some(RenderError::Samples { .. })));
        // Single-sampled images for a 4x renderer, and a resolve image for a 1x one.
        let mut renderer = Renderer::with_options(gpu, sphere(), host::desc(), options(four)).unwrap();
        let images = HostImages::new(gpu, 32, 32, host::COLOR);
        let error = draw_refused(gpu, &mut renderer, &images, &images.whole());
        assert!(matches!(error, RenderError::HostTargetSamples { which: "colour", .. }), "{error}");
        let mut single = host_renderer(gpu);
        let target = HostTarget { resolve: Some(images.whole().color), ..images.whole() };
        let error = draw_refused(gpu, &mut single, &images, &target);
        assert!(matches!(error, RenderError::HostTargetState { which: "resolve", .. }), "{error}");
    });
}

#[test]
fn declared_states_with_a_render_area_smaller_than_the_image_keep_the_pixels_outside_it() {
    common::with_gpu(|gpu| {
        let (width, height) = (96usize, 80usize);
        let images = HostImages::new(gpu, width as u32, height as u32, LINEAR);
        let drawing = ImageState {
            layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
            stages: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
            access: vk::AccessFlags2::COLOR_ATTACHMENT_WRITE,
        };
        let sync = HostSync::Declared {
            color: DeclaredImage { image: images.color.raw(), entry: drawing, exit: drawing },
            depth: DeclaredImage { image: images.depth.raw(), entry: depth_testing(), exit: depth_testing() },
        };
        let target = HostTarget { offset: vk::Offset2D { x: 24, y: 10 }, sync, ..images.target(extent(64, 64)) };
        let marker = [0.25, 0.5, 0.75, 1.0];
        let mut renderer = linear_renderer(gpu, DepthTest::STANDARD);
        // Not loaded: the render area is cleared, but a discard of the whole image would lose the
        // host's pixels around it (lavapipe keeps memory through a discard, so this checks the
        // rest: validation and what is drawn where).
        let drawn = draw(gpu, &mut renderer, &images, &target, Some((marker, 1.0)));
        let inside = |i: usize| (24..88).contains(&(i % width)) && (10..74).contains(&(i / width));
        let untouched = (0..width * height).filter(|&i| !inside(i) && drawn[i] == marker).count();
        let lit = (0..width * height).filter(|&i| inside(i) && drawn[i][0] > 0.0).count();
        assert_eq!(untouched, width * height - 64 * 64, "pixels outside the render area were written");
        assert!(lit > 64 * 64 / 10, "only {lit} lit pixels in the render area");
    });
}
