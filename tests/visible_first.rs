//! The hierarchical gather's visible-first receivers (`render::plan::receivers`): after a
//! change it recomputes the receivers an eye may see and sweeps the rest over the next frames,
//! and every image, and every readback, equals a gather of every receiver: with the dipole alone
//! and with a transport kernel scaling the bunny's exitance.

mod common;

use common::{builtin, with_gpu};
use glam::Vec3;
use std::sync::Arc;
use translucent::gpu::Gpu;
use translucent::reference::rte_mesh::{KernelSettings, object_kernel};
use translucent::render::camera::CameraView;
use translucent::render::edit::SceneEdit;
use translucent::render::plan::{Change, ReceiverScope, SWEEP_FRAMES, View};
use translucent::render::receiver_view::{FINISH, GATHER, kernel_gathered, seen_receivers};
use translucent::render::renderer::Renderer;
use translucent::render::target::DepthConvention;
use translucent::scene::build::{Overrides, PreparedScene};
use translucent::scene::needs::KernelState;
use translucent::scene::{Camera, GatherMode, ReceiverPolicy, lights};

/// The built-in scene gathered hierarchically at 400 samples, its receivers under `policy`.
fn prepared(policy: ReceiverPolicy) -> PreparedScene {
    let overrides =
        Overrides { gather: Some(GatherMode::Hierarchical), receivers: Some(policy), ..Overrides::default() };
    builtin(&overrides)
}

/// A renderer of `prepared(policy)`.
fn renderer(gpu: &Arc<Gpu>, policy: ReceiverPolicy) -> Renderer {
    Renderer::new(gpu, prepared(policy)).expect("renderer")
}

/// Render the frame the pending change calls for; the image and the bunny's receiver scope.
fn frame(renderer: &mut Renderer) -> (Vec<u8>, ReceiverScope) {
    let plan = renderer.plan(renderer.pending_change().unwrap_or(Change::Camera));
    renderer.frame(&plan).expect("frame");
    (renderer.image().expect("image").0, plan.objects[0].receivers)
}

/// How many of the bunny's vertices the last frame's pick marked, out of how many.
fn picked(renderer: &Renderer) -> (usize, usize) {
    let state: Vec<[u32; 2]> = renderer.scene_data().buffers().receiver_state().read().expect("state");
    let count = renderer.scene().objects[0].mesh.positions().len();
    (state[..count].iter().filter(|s| s[1] == 1).count(), count)
}

/// Two light moves, then an orbit long enough to finish the sweep and go past it, by
/// `degrees` (light, camera) a step, both renderers alike: each frame's images are equal.
fn drag_and_orbit(visible: &mut Renderer, every: &mut Renderer, [light, camera]: [f32; 2]) {
    for step in 0..(2 + SWEEP_FRAMES as usize + 3) {
        for r in [&mut *visible, &mut *every] {
            let edit = if step < 2 {
                let moved = lights::orbit(&r.scene().scene.file.lights[0], Vec3::ZERO, light).unwrap();
                SceneEdit::Light { index: 0, light: moved }
            } else {
                SceneEdit::Camera(r.camera().orbited(Vec3::ZERO, camera))
            };
            r.edit(edit).unwrap();
        }
        let (a, scope) = frame(visible);
        assert_eq!(a, frame(every).0, "frame {step} ({scope:?})");
    }
}

#[test]
fn every_image_of_a_light_drag_and_an_orbit_equals_a_gather_of_every_receiver() {
    with_gpu(|gpu| {
        let mut visible = renderer(gpu, ReceiverPolicy::VisibleFirst);
        let mut every = renderer(gpu, ReceiverPolicy::Every);
        let (image, scope) = frame(&mut visible);
        assert!(matches!(scope, ReceiverScope::VisibleFirst { fresh: true, sweep: None, .. }), "{scope:?}");
        let (first, count) = picked(&visible);
        assert!(first > 0 && first < count * 3 / 4, "the first frame picked {first} of {count} vertices");
        assert_eq!(image, frame(&mut every).0, "first frame");
        drag_and_orbit(&mut visible, &mut every, [20.0, 25.0]);
        // The sweep has finished: every vertex of the level holds the last generation's
        // exitance, and a camera frame gathers nothing.
        let plan = visible.plan(Change::Camera);
        assert!(!plan.objects[0].gather, "{plan}");
    });
}

/// The bunny's vertices the last frame marked to gather, and to scale.
fn marked(renderer: &Renderer) -> (Vec<u32>, Vec<u32>) {
    let state: Vec<[u32; 2]> = renderer.scene_data().buffers().receiver_state().read().expect("state");
    let count = renderer.scene().objects[0].mesh.positions().len() as u32;
    let with = |bit: u32| (0..count).filter(|&v| state[v as usize][1] & bit != 0).collect();
    (with(GATHER), with(FINISH))
}

#[test]
fn with_a_transport_kernel_every_image_and_readback_visible_first_equals_a_gather_of_every_receiver() {
    // A small kernel: what is tested is which vertices are gathered and scaled, not its noise.
    let settings = KernelSettings { patches: 128, walks: 128 * 20, seed: 3, more_on_small_meshes: false };
    let kernel = Arc::new(object_kernel(&prepared(ReceiverPolicy::Every).objects[0], &settings, &|_, _| {}).unwrap());
    with_gpu(|gpu| {
        let with_kernel = |policy| {
            let mut scene = prepared(policy);
            scene.objects[0].transport = Some(kernel.clone());
            let mut r = Renderer::new(gpu, scene).expect("renderer");
            // Close to the head: a quarter of the level's vertices may be seen, and the patches
            // they blend leave some of the rest unneeded.
            let file = &r.scene().scene.file.camera;
            let close = Camera { eye: [-0.03, 0.045, 0.05], target: [-0.01, 0.035, 0.0], ..file.clone() };
            r.edit(SceneEdit::Camera(CameraView::of_camera(&close, r.scene()))).unwrap();
            r
        };
        let (mut visible, mut every) = (with_kernel(ReceiverPolicy::VisibleFirst), with_kernel(ReceiverPolicy::Every));
        let plan = visible.plan(Change::Everything);
        assert!(matches!(plan.objects[0].transport, Some(KernelState::Scales { .. })), "{plan}");
        let (image, scope) = frame(&mut visible);
        assert!(matches!(scope, ReceiverScope::VisibleFirst { fresh: true, sweep: None, .. }), "{scope:?}");
        // The patches of the scaled vertices are gathered whole: more gathered than scaled,
        // as the host twin counts them.
        let (gathered, scaled) = marked(&visible);
        let (level, bunny) = (plan.objects[0].level, &visible.scene().objects[0]);
        let count = bunny.levels[level].vertices.len();
        let (g, s) = (gathered.len(), scaled.len());
        assert!(s > 0 && s < g && g < count, "{s} scaled, {g} gathered of the level's {count}");
        let view = View::of_camera(&visible.camera(), visible.scene().scene.file.camera.resolution[1]);
        let seen = seen_receivers(bunny, level, &view, DepthConvention::Standard);
        assert_eq!(scaled, seen);
        assert_eq!(gathered, kernel_gathered(bunny, level, &seen));
        assert_eq!(image, frame(&mut every).0, "first frame");
        drag_and_orbit(&mut visible, &mut every, [25.0, 40.0]);
        assert!(!visible.plan(Change::Camera).objects[0].gather, "the sweep has finished");
        // After a light move, a readback finishes the sweep: the scaled exitance of every vertex.
        for r in [&mut visible, &mut every] {
            let light = &r.scene().scene.file.lights[0];
            r.edit(SceneEdit::Light { index: 0, light: lights::orbit(light, Vec3::ZERO, 25.0).unwrap() }).unwrap();
            frame(r);
        }
        let level = |r: &Renderer| r.exitance_at_level(0).expect("exitance");
        assert_eq!(level(&visible), level(&every));
    });
}

#[test]
fn exitance_read_back_mid_sweep_equals_a_gather_of_every_receiver() {
    with_gpu(|gpu| {
        let read = |policy| {
            let mut r = renderer(gpu, policy);
            let mut plan = r.plan(Change::Everything);
            // Every vertex: the readback refuses a coarser level.
            plan.objects.iter_mut().for_each(|o| o.level = 0);
            r.frame(&plan).expect("frame");
            let before = picked(&r).0;
            (r.exitance(0).expect("exitance"), before)
        };
        let (visible, first) = read(ReceiverPolicy::VisibleFirst);
        let (every, _) = read(ReceiverPolicy::Every);
        assert!(first < visible.len(), "the first frame picked all {first} vertices: nothing left to finish");
        assert_eq!(visible, every);
    });
}

#[test]
fn the_gpu_picks_the_receivers_its_host_twin_sees_on_a_frame_of_change() {
    with_gpu(|gpu| {
        let mut r = renderer(gpu, ReceiverPolicy::VisibleFirst);
        for _ in 0..2 {
            let plan = r.plan(r.pending_change().unwrap_or(Change::Camera));
            r.frame(&plan).expect("frame");
            let state: Vec<[u32; 2]> = r.scene_data().buffers().receiver_state().read().expect("state");
            let gpu_picked: Vec<u32> = (0..r.scene().objects[0].mesh.positions().len() as u32)
                .filter(|&v| state[v as usize][1] == 1)
                .collect();
            let view = View::of_camera(&r.camera(), r.scene().scene.file.camera.resolution[1]);
            let host = seen_receivers(&r.scene().objects[0], plan.objects[0].level, &view, DepthConvention::Standard);
            assert!(!host.is_empty() && host.len() < r.scene().objects[0].levels[plan.objects[0].level].vertices.len());
            assert_eq!(gpu_picked, host);
            // From the other side of the bunny, after a light move: a fresh pick.
            r.edit(SceneEdit::Camera(r.camera().orbited(Vec3::ZERO, 150.0))).unwrap();
            let light = &r.scene().scene.file.lights[0];
            let moved = lights::orbit(light, Vec3::ZERO, 10.0).unwrap();
            r.edit(SceneEdit::Light { index: 0, light: moved }).unwrap();
        }
    });
}

#[test]
fn a_plan_recorded_again_after_later_frames_still_gathers_what_its_splat_changed() {
    with_gpu(|gpu| {
        let mut rows = [renderer(gpu, ReceiverPolicy::VisibleFirst), renderer(gpu, ReceiverPolicy::Every)];
        let move_light = |r: &mut Renderer| {
            let light = &r.scene().scene.file.lights[0];
            let moved = lights::orbit(light, Vec3::ZERO, 30.0).unwrap();
            r.edit(SceneEdit::Light { index: 0, light: moved }).unwrap();
        };
        for r in rows.iter_mut() {
            frame(r);
        }
        // Made now, recorded after another light frame has marked the receivers it saw.
        let old = rows[0].plan(Change::Light(0));
        for r in rows.iter_mut() {
            move_light(r);
            frame(r);
            move_light(r);
        }
        rows[0].frame(&old).unwrap();
        let fresh = rows[1].plan(Change::Light(0));
        rows[1].frame(&fresh).unwrap();
        assert_eq!(rows[0].image().unwrap().0, rows[1].image().unwrap().0);
    });
}
