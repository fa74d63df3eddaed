//! The renderer owns its frames' lifetimes (issue 47): every sequence of safe calls an engine's
//! frame loop makes, in any order of submission, ends without a crash or a validation message,
//! and a frame recorded but never submitted can be discarded. The host here is
//! tests/common/host.rs on the tests' own validated `Gpu`.

mod common;
#[path = "../examples/embed.rs"]
#[allow(dead_code)]
mod embed;

use common::host::{self, HostCommands, HostImages};
use std::sync::Arc;
use translucent::gpu::Gpu;
use translucent::{Overrides, PreparedScene, RecordedFrame, RenderError, Renderer, Scene};

fn host_renderer(gpu: &Arc<Gpu>) -> Renderer {
    let scene = Scene::parse(embed::SPHERE_SCENE, "sphere", None).unwrap();
    Renderer::with_target(gpu, PreparedScene::new(&scene, &Overrides::default()).unwrap(), host::desc()).unwrap()
}

/// `record_frame` into a command buffer of the host's, not yet submitted.
fn recorded(gpu: &Arc<Gpu>, renderer: &mut Renderer, images: &HostImages) -> (HostCommands, RecordedFrame) {
    let commands = HostCommands::begin(gpu);
    images.to_attachments(gpu, commands.cmd);
    let frame = renderer.record_frame(commands.cmd, Some(&images.whole())).unwrap();
    (commands, frame)
}

/// Defect 1: three frames fenced and read, a fourth recorded: its timings before its
/// submission are `FrameNotDone`, not the first frame's (whose queries its slot held), and
/// dropping the renderer right after submitting it waits for it.
#[test]
fn a_frames_timings_before_it_ran_are_not_done_and_drop_still_waits_for_it() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 48, 48, host::COLOR);
        for _ in 0..Renderer::FRAMES_IN_FLIGHT {
            let (commands, frame) = recorded(gpu, &mut renderer, &images);
            commands.submit();
            commands.wait();
            assert!(renderer.read_timings(&frame).is_ok());
        }
        let (commands, fourth) = recorded(gpu, &mut renderer, &images);
        let early = renderer.read_timings(&fourth);
        let generation = Renderer::FRAMES_IN_FLIGHT as u64 + 1;
        assert!(matches!(early, Err(RenderError::FrameNotDone(g)) if g == generation), "{early:?}");
        commands.submit();
        drop(renderer);
        assert!(commands.finished(), "the renderer was destroyed while its frame was in flight");
    });
}

/// Defect 2: frame B submitted, fenced and read before frame A, recorded earlier, is submitted;
/// dropping the renderer then waits for A.
#[test]
fn frames_submitted_out_of_order_are_all_waited_for_at_drop() {
    common::with_gpu(|gpu| {
        let mut renderer = host_renderer(gpu);
        let images = HostImages::new(gpu, 48, 48, host::COLOR);
        let (a, _) = recorded(gpu, &mut renderer, &images);
        let (b, frame_b) = recorded(gpu, &mut renderer, &images);
        b.submit();
        b.wait();
        assert!(renderer.read_timings(&frame_b).is_ok());
        a.submit();
        drop(renderer);
        assert!(a.finished(), "the renderer was destroyed while an earlier frame was in flight");
    });
}

/// Defect 3: a frame recorded and never submitted (the swapchain went out of date) is
/// discarded; the next frame redoes what it did and draws what a fresh renderer's first frame
/// draws. Only the last recorded frame can be discarded.
#[test]
fn a_discarded_frame_is_redone_by_the_next_which_draws_what_a_fresh_renderer_draws() {
    common::with_gpu(|gpu| {
        let images = HostImages::new(gpu, 48, 48, host::COLOR);
        let draw = |renderer: &mut Renderer| {
            let (commands, _) = recorded(gpu, renderer, &images);
            commands.submit();
            commands.wait();
            images.read_color()
        };
        let expected = draw(&mut host_renderer(gpu));
        let mut renderer = host_renderer(gpu);
        let (abandoned, frame) = recorded(gpu, &mut renderer, &images);
        renderer.discard(frame).unwrap();
        drop(abandoned);
        assert_eq!(draw(&mut renderer), expected, "the frame after a discarded one drew something else");
        let (first, one) = recorded(gpu, &mut renderer, &images);
        let (second, _) = recorded(gpu, &mut renderer, &images);
        let refused = renderer.discard(one);
        assert!(matches!(refused, Err(RenderError::DiscardNotLast { .. })), "{refused:?}");
        first.submit();
        second.submit();
        second.wait();
        first.wait();
    });
}

/// Defect 4: a renderer moves to another thread (an engine's render thread) and renders there.
#[test]
fn a_renderer_moves_to_another_thread_and_renders_there() {
    common::with_gpu(|gpu| {
        let renderer = host_renderer(gpu);
        let moved = {
            let gpu = gpu.clone();
            std::thread::spawn(move || {
                let mut renderer = renderer;
                let images = HostImages::new(&gpu, 48, 48, host::COLOR);
                let (commands, frame) = recorded(&gpu, &mut renderer, &images);
                commands.submit();
                commands.wait();
                let timings = renderer.read_timings(&frame).unwrap();
                drop((renderer, commands, images));
                timings
            })
            .join()
            .unwrap()
        };
        assert!(!moved.passes.is_empty(), "no pass ran on the render thread");
    });
}
