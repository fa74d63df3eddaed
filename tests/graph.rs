//! The frame as a declared pipeline: bindings are matched to the GLSL's names, and barriers follow
//! from what each pass declares, checked by the validation layer's synchronisation validation.

mod common;

use ash::vk;
use common::{plane_scene, validated_options, with_gpu};
use std::cell::RefCell;
use std::sync::Arc;
use translucent::gpu::{
    Binding, Buffer, BufferDesc, ComputePipeline, DescriptorSet, Gpu, GpuError, GpuOptions, Hazards,
};
use translucent::render::edit::SceneEdit;
use translucent::render::gather::GatherPass;
use translucent::render::gpu_scene::GpuScene;
use translucent::render::graph::{Resource, Resources, Use, compute_uses};
use translucent::render::pass::{FrameInputs, RenderPass};
use translucent::render::plan::{Change, Plan};
use translucent::render::renderer::Renderer;
use translucent::render::splat::SplatPass;
use translucent::render::targets::FrameTargets;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::{Scene, lights};

fn plane(extra: &str) -> PreparedScene {
    let text = plane_scene("marble", 20.0, 200, extra);
    PreparedScene::new(&Scene::parse(&text, "graph.toml", None).unwrap(), &Overrides::default()).unwrap()
}

/// Validation with synchronisation validation on; the messages it gave, after the device is gone.
fn with_sync_gpu(f: impl FnOnce(&Arc<Gpu>)) -> Vec<String> {
    let options = GpuOptions { sync_validation: true, ..validated_options() };
    let gpu = Gpu::new(&options).expect("a Vulkan device with validation layers (bash scripts/setup)");
    let counters = gpu.validation();
    f(&gpu);
    assert_eq!(Arc::strong_count(&gpu), 1, "a GPU resource outlived the test body");
    drop(gpu);
    counters.messages()
}

#[test]
fn a_swapped_binding_fails_at_pipeline_creation_naming_both() {
    with_gpu(|gpu| {
        let pipeline = ComputePipeline::new(gpu, "splat.comp").unwrap();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let buffer = Buffer::new(gpu, &BufferDesc::gpu_only("any", 256, usage)).unwrap();
        let prepared = plane("");
        let scene = GpuScene::new(gpu, &prepared).unwrap();
        let targets = FrameTargets::new(gpu, 64, prepared.shadow_layers, None).unwrap();
        let resources = Resources { scene: &scene, targets: &targets };
        // Samples and objects swapped: both are storage buffers, so only the names tell.
        let mut bindings = resources
            .bind_all(&[Resource::Objects, Resource::Samples, Resource::Lights, Resource::ShadowMaps])
            .unwrap();
        bindings.push(Resource::Splat.bind(Binding::Buffer(&buffer)));
        bindings.extend(
            resources.bind_all(&[Resource::SplatEnvironment, Resource::BvhNodes, Resource::BvhTriangles]).unwrap(),
        );
        match pipeline.descriptor_set(&bindings) {
            Err(e @ GpuError::BindingMismatch { binding: 0, .. }) => {
                let message = e.to_string();
                assert!(message.contains("`Samples`") && message.contains("`Objects`"), "{message}");
                assert!(message.contains("splat.comp"), "{message}");
            }
            Err(e) => panic!("another error: {e}"),
            Ok(_) => panic!("a swapped binding was accepted"),
        }
        // In order, the same resources bind.
        bindings.swap(0, 1);
        pipeline.descriptor_set(&bindings).expect("the declared order binds");
    });
}

/// A reader of the exitance that no pass knew of (glsl/test/exitance_probe.comp).
struct Probe {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _out: Buffer,
    count: u32,
}

const PROBE_BINDINGS: [Resource; 1] = [Resource::Exitance];

impl Probe {
    fn new(gpu: &Arc<Gpu>, resources: &Resources) -> Probe {
        let pipeline = ComputePipeline::new(gpu, "test/exitance_probe.comp").unwrap();
        let count = resources.scene.vertex_count;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let out = Buffer::new(gpu, &BufferDesc::gpu_only("probe", 16 * count as u64, usage)).unwrap();
        let mut bindings = resources.bind_all(&PROBE_BINDINGS).unwrap();
        bindings.push(translucent::gpu::Named { name: "Probe", binding: Binding::Buffer(&out) });
        let set = pipeline.descriptor_set(&bindings).unwrap();
        Probe { pipeline, set, _out: out, count }
    }
}

impl RenderPass for Probe {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&PROBE_BINDINGS, &[])
    }
    fn record(&self, cmd: vk::CommandBuffer, _: &FrameInputs) {
        self.pipeline.dispatch(cmd, &self.set, &self.count, [self.count, 1, 1]);
    }
}

/// Two frames of splat, gather and the probe in one command buffer, each pass after the barrier
/// its declaration gives; the probe's declaration is skipped when `declare_probe` is false.
fn two_frames_with_a_new_reader(gpu: &Arc<Gpu>, declare_probe: bool) {
    let prepared = plane("");
    let scene = GpuScene::new(gpu, &prepared).unwrap();
    let targets = FrameTargets::new(gpu, 64, prepared.shadow_layers, None).unwrap();
    let resources = Resources { scene: &scene, targets: &targets };
    let splat = SplatPass::new(gpu, &resources, prepared.scene.file.render.splat_visibility).unwrap();
    let gather = GatherPass::new(gpu, &resources).unwrap();
    let probe = Probe::new(gpu, &resources);
    let hazards = RefCell::new(Hazards::new());
    targets.track(&mut hazards.borrow_mut());
    let plan = Plan::default();
    let frame = FrameInputs {
        gpu,
        scene: &scene,
        targets: &targets,
        plan: &plan,
        shadow_layers: None,
        view_proj: glam::Mat4::IDENTITY,
        eye: glam::Vec3::ZERO,
        background: [0.0; 3],
        target: None,
        exposure: 1.0,
        hazards: &hazards,
    };
    let passes: [(&dyn RenderPass, bool); 3] = [(&splat, true), (&gather, true), (&probe, declare_probe)];
    gpu.one_shot("frames with a probe", |cmd| {
        for _ in 0..2 {
            for (pass, declared) in passes {
                if declared {
                    frame.before(cmd, &pass.uses(&frame));
                }
                pass.record(cmd, &frame);
            }
        }
    })
    .unwrap();
}

#[test]
fn a_new_reader_gets_its_barrier_without_touching_the_producer() {
    let messages = with_sync_gpu(|gpu| two_frames_with_a_new_reader(gpu, true));
    assert!(messages.is_empty(), "synchronisation validation:\n{}", messages.join("\n"));
    // The control: the same reader recorded without its declaration is a hazard the layer sees
    // (so the clean run above is the barriers' doing, not a layer that checks nothing).
    let messages = with_sync_gpu(|gpu| two_frames_with_a_new_reader(gpu, false));
    assert!(messages.iter().any(|m| m.contains("SYNC-HAZARD")), "no hazard reported:\n{}", messages.join("\n"));
}

/// A sphere casting a shadow onto the plane under a point light: the shadow pass runs.
const CASTER: &str = r#"
[[object]]
shape = { type = "sphere", radius = 2.0 }
transform = { translate = [0.0, 4.0, 0.0] }
material = { type = "opaque", albedo = [0.5, 0.5, 0.5] }

[[light]]
type = "point"
position = [5.0, 30.0, 5.0]
intensity = [40.0, 40.0, 40.0]
"#;

#[test]
fn every_gather_and_frame_change_is_clean_under_synchronisation_validation() {
    for gather in ["vertex", "sparse", "hierarchical", "pixel", "texture"] {
        let messages = with_sync_gpu(|gpu| {
            let extra = format!("[render]\ngather = \"{gather}\"\n{CASTER}");
            let mut renderer = Renderer::new(gpu, plane(&extra)).unwrap();
            let everything = renderer.plan(Change::Everything);
            renderer.frame(&everything).unwrap();
            // One light moved: its shadow maps redrawn alone, then splat, gather and shading.
            let moved = lights::orbit(&renderer.scene().scene.file.lights[1], glam::Vec3::ZERO, 10.0).unwrap();
            renderer.edit(SceneEdit::Light { index: 1, light: moved }).unwrap();
            let light = renderer.plan(Change::Light(1));
            renderer.frame(&light).unwrap();
            let camera = renderer.camera().orbited(glam::Vec3::ZERO, 5.0);
            renderer.edit(SceneEdit::Camera(camera)).unwrap();
            let camera_plan = renderer.plan(Change::Camera);
            renderer.frame(&camera_plan).unwrap();
            renderer.frame_isolated(&light).unwrap();
            renderer.hdr_image().unwrap();
            renderer.frame(&camera_plan).unwrap();
            // A readback mid-sweep gathers what the sweep left (the hierarchical gather).
            let light = renderer.plan(Change::Light(1));
            renderer.frame(&light).unwrap();
            renderer.exitance_at_level(0).unwrap();
            renderer.frame(&renderer.plan(Change::Camera)).unwrap();
        });
        assert!(messages.is_empty(), "{gather} gather, synchronisation validation:\n{}", messages.join("\n"));
    }
}

#[test]
fn a_transform_edit_keeps_the_renderer_and_draws_what_a_fresh_one_draws() {
    let messages = with_sync_gpu(|gpu| {
        let mut renderer = Renderer::new(gpu, plane(CASTER)).unwrap();
        renderer.frame(&renderer.plan(Change::Everything)).unwrap();
        let (before, _) = renderer.image().unwrap();
        let transform: translucent::scene::Transform =
            toml::from_str("translate = [3.0, 5.0, -2.0]").expect("a transform");
        renderer.edit(SceneEdit::Transform { object: 1, transform: transform.clone() }).unwrap();
        let plan = renderer.plan(renderer.pending_change().expect("the edit is pending"));
        renderer.frame(&plan).unwrap();
        let (edited, _) = renderer.image().unwrap();
        // The same scene with the sphere placed there from the start.
        let mut moved = plane(CASTER);
        moved.set_transform(1, transform).unwrap();
        let mut fresh = Renderer::new(gpu, moved).unwrap();
        fresh.frame(&fresh.plan(Change::Everything)).unwrap();
        let (expected, _) = fresh.image().unwrap();
        assert!(edited != before, "moving the sphere changed nothing in the image");
        assert!(edited == expected, "the edited renderer's image differs from a fresh renderer's");
        // An index past the objects is an error naming it, and changes nothing.
        let err = renderer.edit(SceneEdit::Transform { object: 7, transform: Default::default() }).unwrap_err();
        assert!(err.to_string().contains("object 7"), "{err}");
    });
    assert!(messages.is_empty(), "synchronisation validation:\n{}", messages.join("\n"));
}
