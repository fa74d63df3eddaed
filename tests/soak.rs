//! A soak test the engine way (issue 47): frames recorded into the host's command buffers with
//! random edits between them (light moves, materials, transforms, camera moves, host-target
//! resizes, abandoned records handed to `discard`), 1 to 4 frames in flight, validation on.
//! At checkpoints the image equals a fresh renderer's for the same scene and camera, and the
//! device memory stays flat. The default run soaks 200 frames; the long one
//! `TRANSLUCENT_SOAK_FRAMES=10000 cargo test --release --test soak -- --ignored --nocapture`.

mod common;
#[path = "../examples/embed.rs"]
#[allow(dead_code)]
mod embed;

use common::host::{self, HostCommands, HostImages};
use rand::{RngExt, SeedableRng};
use std::collections::VecDeque;
use std::sync::Arc;
use translucent::gpu::Gpu;
use translucent::optics::Material;
use translucent::scene::{Transform, lights};
use translucent::{Overrides, PreparedScene, RecordedFrame, Renderer, RendererOptions, Scene, SceneEdit};

/// Frames between checkpoints (and between renderers of another frames-in-flight count).
const SEGMENT: usize = 50;

/// The embedding example's sphere with the dipole in every channel: under `"auto"` a material
/// edited to ketchup would give it single scattering's beam tables, after which a material edit
/// is refused (`RenderError::MaterialWithBeamTables`), as the soak's random edits may not be.
fn sphere() -> PreparedScene {
    let (from, to) = ("mm_per_unit = 1000.0 }", "mm_per_unit = 1000.0, model = \"dipole\" }");
    assert!(embed::SPHERE_SCENE.contains(from));
    let scene = Scene::parse(&embed::SPHERE_SCENE.replacen(from, to, 1), "sphere", None).unwrap();
    PreparedScene::new(&scene, &Overrides::default()).unwrap()
}

fn renderer(gpu: &Arc<Gpu>, scene: PreparedScene, frames_in_flight: usize) -> Renderer {
    let options = RendererOptions { frames_in_flight, ..RendererOptions::default() };
    Renderer::with_options(gpu, scene, host::desc(), options).unwrap()
}

/// The host's side of the loop: its images and the frames it has in flight.
struct Host<'a> {
    gpu: &'a Arc<Gpu>,
    images: HostImages,
    in_flight: VecDeque<(HostCommands, RecordedFrame)>,
}

impl Host<'_> {
    /// Record a frame and submit it, with at most `limit` in flight (reading the timings of
    /// each one it waits for).
    fn frame(&mut self, renderer: &mut Renderer, limit: usize) {
        // Read a frame's timings before `frames_in_flight` more are recorded (the contract).
        while self.in_flight.len() >= limit.max(1) {
            self.retire(renderer);
        }
        let commands = HostCommands::begin(self.gpu);
        self.images.to_attachments(self.gpu, commands.cmd);
        let frame = renderer.record_frame(commands.cmd, Some(&self.images.whole())).unwrap();
        commands.submit();
        self.in_flight.push_back((commands, frame));
    }

    fn retire(&mut self, renderer: &Renderer) {
        let (commands, frame) = self.in_flight.pop_front().expect("a frame in flight");
        commands.wait();
        renderer.read_timings(&frame).unwrap();
    }

    fn flush(&mut self, renderer: &Renderer) {
        while !self.in_flight.is_empty() {
            self.retire(renderer);
        }
    }

    /// A frame recorded and never submitted, handed back to the renderer.
    fn abandon(&mut self, renderer: &mut Renderer) {
        let commands = HostCommands::begin(self.gpu);
        self.images.to_attachments(self.gpu, commands.cmd);
        let frame = renderer.record_frame(commands.cmd, Some(&self.images.whole())).unwrap();
        renderer.discard(frame).unwrap();
    }

    /// What `renderer` draws now, after every frame in flight.
    fn image(&mut self, renderer: &mut Renderer) -> Vec<u8> {
        self.frame(renderer, 1);
        self.flush(renderer);
        self.images.read_color()
    }
}

/// One random edit of the scene, or of the host's target.
fn edit(renderer: &mut Renderer, host: &mut Host, rng: &mut rand_pcg::Pcg64) {
    let centre = renderer.scene().bounds.0;
    match rng.random_range(0..7) {
        0 => {
            let light = &renderer.scene().scene.file.lights[0];
            let moved = lights::orbit(light, centre, rng.random_range(-30.0..30.0)).unwrap();
            renderer.edit(SceneEdit::Light { index: 0, light: moved }).unwrap();
        }
        1 => {
            let preset = ["marble", "skimmilk", "ketchup", "apple"][rng.random_range(0..4)];
            renderer.edit(SceneEdit::Material { object: 0, material: Material::preset(preset).unwrap() }).unwrap();
        }
        2 => {
            let offset = [rng.random_range(-0.004..0.004), 0.0, rng.random_range(-0.004..0.004)];
            let transform = Transform { translate: Some(offset), ..Transform::default() };
            renderer.edit(SceneEdit::Transform { object: 0, transform }).unwrap();
        }
        3 => {
            let camera = renderer.camera().orbited(centre, rng.random_range(-20.0..20.0));
            renderer.edit(SceneEdit::Camera(camera)).unwrap();
        }
        4 => {
            host.flush(renderer);
            let (w, h) = (rng.random_range(24..96), rng.random_range(24..96));
            host.images = HostImages::new(host.gpu, w, h, host::COLOR);
        }
        5 => host.abandon(renderer),
        _ => {}
    }
}

/// Resident pages of this process (`/proc/self/statm`), where Linux says.
fn resident_pages() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    statm.split_whitespace().nth(1).and_then(|p| p.parse().ok()).unwrap_or(0)
}

/// Soak `frames` frames; returns the device memory and the resident pages at each checkpoint.
fn soak(gpu: &Arc<Gpu>, frames: usize) -> Vec<(u64, u64)> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(47);
    let mut host = Host { gpu, images: HostImages::new(gpu, 64, 64, host::COLOR), in_flight: VecDeque::new() };
    let mut scene = sphere();
    let mut memory = Vec::new();
    for (segment, start) in (0..frames).step_by(SEGMENT).enumerate() {
        let in_flight = 1 + segment % 4;
        let mut soaked = renderer(gpu, scene, in_flight);
        for _ in start..(start + SEGMENT).min(frames) {
            edit(&mut soaked, &mut host, &mut rng);
            host.frame(&mut soaked, in_flight);
        }
        // Measured with the host's images at one size, before the fresh renderer is made.
        host.flush(&soaked);
        host.images = HostImages::new(gpu, 64, 64, host::COLOR);
        memory.push((soaked.device_memory(), resident_pages()));
        let drawn = host.image(&mut soaked);
        let mut fresh = renderer(gpu, soaked.scene().clone(), in_flight);
        fresh.edit(SceneEdit::Camera(soaked.camera())).unwrap();
        let expected = host.image(&mut fresh);
        let differ = drawn.iter().zip(&expected).filter(|(a, b)| a.abs_diff(**b) > 1).count();
        assert_eq!(differ, 0, "segment {segment}: {differ} bytes differ from a fresh renderer's image");
        scene = soaked.scene().clone();
    }
    memory
}

/// Whether every value of `values` is within `share` of the smallest.
fn flat(values: impl Iterator<Item = u64> + Clone, share: f64) -> bool {
    let low = values.clone().min().unwrap_or(0);
    values.max().unwrap_or(0) as f64 <= low as f64 * (1.0 + share)
}

#[test]
fn two_hundred_frames_of_random_edits_draw_what_a_fresh_renderer_draws_in_flat_memory() {
    let memory = common::with_gpu(|gpu| soak(gpu, 200));
    println!("device memory and resident pages at each checkpoint: {memory:?}");
    assert!(flat(memory.iter().map(|m| m.0), 0.01), "device memory not flat: {memory:?}");
}

#[test]
#[ignore = "the long soak: TRANSLUCENT_SOAK_FRAMES=10000 cargo test --release --test soak -- --ignored --nocapture"]
fn the_long_soak() {
    let frames = std::env::var("TRANSLUCENT_SOAK_FRAMES").ok().and_then(|f| f.parse().ok()).unwrap_or(10_000);
    let start = std::time::Instant::now();
    let memory = common::with_gpu(|gpu| soak(gpu, frames));
    let device = memory.iter().map(|m| m.0);
    // Resident memory climbs 4 to 6% over the first few thousand frames and then levels off
    // (measured; the cause is not pinned down): flat is asked of the second half.
    let resident: Vec<u64> = memory.iter().map(|m| m.1).collect();
    let second_half = resident[resident.len() / 2..].iter().copied();
    println!(
        "{frames} frames in {:.0} s; device memory {} to {} bytes; resident pages at each checkpoint {resident:?}",
        start.elapsed().as_secs_f64(),
        device.clone().min().unwrap(),
        device.clone().max().unwrap(),
    );
    assert!(flat(device, 0.01), "device memory not flat");
    assert!(flat(second_half, 0.01), "resident memory not flat over the second half: {resident:?}");
}
