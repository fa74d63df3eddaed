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
use translucent::gpu::{
    Access, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorSet, EnabledFeatures, Gpu, GpuOptions, HostVulkan,
    Named, memory_barrier,
};
use translucent::render::plan::Pass;
use translucent::{CameraView, Change, Overrides, PreparedScene, RenderError, Renderer, Scene};

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
            one.set_camera(turned);
            one.record_frame(cmd, Some(&b.whole())).unwrap()
        })
        .unwrap();
        let (first, second) = (a.read_color(), b.read_color());
        let mut apart = host_renderer(gpu);
        let c = HostImages::new(gpu, 64, 64, host::COLOR);
        record(gpu, &mut apart, &c, &c.whole()).unwrap();
        assert_eq!(first, c.read_color(), "the first frame differs from the same frame submitted alone");
        apart.set_camera(turned);
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

#[test]
fn a_host_device_lacking_several_features_gets_all_of_them_named() {
    common::with_gpu(|gpu| {
        let host = HostVulkan {
            entry: gpu.entry().clone(),
            instance: gpu.instance().clone(),
            physical_device: gpu.physical_device(),
            device: gpu.device().clone(),
            queue: *gpu.queue(),
            queue_family: gpu.queue_family(),
            enabled_features: EnabledFeatures {
                synchronization2: false,
                shader_output_layer: false,
                ..EnabledFeatures::ALL
            },
        };
        // SAFETY: the handles are the live `gpu`'s; the call fails before it makes anything.
        let error = unsafe { Gpu::from_host(host, &GpuOptions::default()) }.err().expect("refused").to_string();
        assert!(error.contains("synchronization2, shaderOutputLayer features"), "{error}");
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
                framed.set_light(0, light.clone()).unwrap();
                alone.set_light(0, light).unwrap();
            }
            record(gpu, &mut framed, &images, &images.whole()).unwrap();
            let frame = gpu
                .one_shot("exitance", |cmd| alone.record_exitance(cmd, extent(64, 64), &[Access::HostRead]))
                .unwrap()
                .unwrap();
            assert!(frame.passes.contains(&Pass::Gather), "step {step}: {:?}", frame.passes);
            assert!(!frame.passes.contains(&Pass::Shade), "step {step}: shading recorded: {:?}", frame.passes);
            let framed_exitance: Vec<[f32; 4]> = framed.buffers().exitance.read().unwrap();
            let exitance: Vec<[f32; 4]> = alone.buffers().exitance.read().unwrap();
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
        let exitance = &renderer.buffers().exitance;
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
        renderer.set_light(0, light).unwrap();
        renderer.record_exitance(cmd, extent(64, 64), readers).unwrap();
        probes[1].record(gpu, cmd);
    })
    .unwrap();
    let last: Vec<[f32; 4]> = renderer.buffers().exitance.read().unwrap();
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
