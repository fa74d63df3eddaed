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
use translucent::gpu::{EnabledFeatures, Gpu, GpuOptions, HostVulkan};
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
