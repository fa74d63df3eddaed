//! `translucent view [SCENE]`: the scene in a window, live. The viewer is a host engine of its
//! own (docs/GPU.md, "Embedding"): it makes the instance, the device and the swapchain, gives
//! them to translucent through `Gpu::from_host`, and records translucent's frame into its own
//! command buffer, straight into the swapchain image (`record_frame` with a `HostTarget`, and
//! `Output::Display`: the shading pass applies the tone map's curve).
//!
//! Mouse: left drag orbits, right or middle drag pans, the wheel zooms, Ctrl + left drag turns
//! the light whose ring (drawn while Ctrl is held) is nearest about the scene. Keys: `m` model,
//! `g` gather, `e` error target (the scene prepared again, given to the renderer as
//! `SceneEdit::Scene`), `r` resets the camera, `q` or Escape quits.

mod app;
mod controls;
mod frames;
mod host;
mod present;
mod swapchain;
mod viewer;

use anyhow::{Context, Result, bail};
use std::path::PathBuf;
use translucent::scene::{Camera, Light, Scene};
use translucent::{Overrides, output};

#[derive(clap::Args, Clone, Debug, Default)]
pub struct Args {
    /// Scene file (TOML); the built-in scene without one
    pub scene: Option<PathBuf>,
    /// Close after this many frames (by default the window stays until closed)
    #[arg(long)]
    pub frames: Option<u64>,
    /// On closing, write the last presented image here (PNG), read back from the swapchain
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// On closing, write the camera and the lights as they were moved here (JSON)
    #[arg(long)]
    pub state: Option<PathBuf>,
    /// Turn the camera 3 degrees a frame about the scene (what `render --moving camera` does)
    #[arg(long)]
    pub orbit: bool,
    /// Present at the display's rate (FIFO); by default as soon as a frame is done
    #[arg(long)]
    pub vsync: bool,
    /// Sample points per translucent object (overrides the scene and the error target)
    #[arg(long)]
    pub samples: Option<usize>,
}

/// What the window left when it closed: the last presented image (with `--screenshot`), and
/// the camera and lights as the mouse left them.
pub struct Outcome {
    pub image: Option<image::RgbaImage>,
    pub camera: Camera,
    pub lights: Vec<Light>,
}

/// The camera and lights as `--state` writes them: what a headless render needs to draw the
/// same frame (`tests/viewer.rs`).
#[derive(serde::Serialize)]
struct State {
    eye: [f32; 3],
    target: [f32; 3],
    up: [f32; 3],
    fov_y: f32,
    resolution: [u32; 2],
    /// Per light: its direction (directional) or position (point, spot); null for the sky.
    lights: Vec<Option<[f32; 3]>>,
    /// Spots' axes, per light (null for the others).
    spot_directions: Vec<Option<[f32; 3]>>,
    /// Frames presented.
    frames: u64,
    /// Median wall time between frames over the latest `viewer::KEPT_FRAME_TIMES` of them.
    median_frame_ms: Option<f64>,
    validation_messages: usize,
}

pub fn run(gpu_args: &super::GpuArgs, args: &Args) -> Result<()> {
    if args.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    for path in args.screenshot.iter().chain(&args.state) {
        output::check_destination(path)?;
    }
    let scene = match &args.scene {
        Some(path) => Scene::load(path)?,
        None => Scene::builtin(),
    };
    let overrides = Overrides { samples: args.samples, ..Overrides::default() };
    let event_loop = winit::event_loop::EventLoop::new()
        .context("no window system: the viewer needs X11 (DISPLAY; under CI, xvfb-run)")?;
    event_loop.set_control_flow(winit::event_loop::ControlFlow::Poll);
    let mut app = app::App::new(args.clone(), gpu_args.clone(), scene, overrides)?;
    event_loop.run_app(&mut app)?;
    let outcome = app.outcome.take();
    let (frames, median) = app.viewer.as_ref().map_or((0, None), |v| (v.frame, median(v.frame_ms.iter().copied())));
    drop(app); // the viewer's Vulkan before the validation count
    let outcome = outcome.unwrap_or_else(|| bail!("the window closed before it was drawn"))?;
    let messages = host::validation_messages();
    if let Some(ms) = median {
        out!("{frames} frames, median {ms:.2} ms a frame ({:.1} frames/s), {messages} validation messages", 1e3 / ms);
    }
    write_outputs(args, &outcome, State::of(&outcome, frames, median, messages))?;
    if messages > 0 {
        bail!("{messages} validation messages (above)");
    }
    Ok(())
}

fn write_outputs(args: &Args, outcome: &Outcome, state: State) -> Result<()> {
    if let Some(path) = &args.screenshot {
        let image = outcome.image.as_ref().context(
            "no screenshot: the window went before its last frame, or its swapchain images cannot be copied from",
        )?;
        output::write_png(path, image.width(), image.height(), image.as_raw())?;
    }
    if let Some(path) = &args.state {
        let text = serde_json::to_string_pretty(&state)?;
        std::fs::write(path, text).with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

impl State {
    fn of(outcome: &Outcome, frames: u64, median_frame_ms: Option<f64>, validation_messages: usize) -> State {
        let c = &outcome.camera;
        let place = |l: &Light| match l {
            Light::Directional { direction, .. } => Some(*direction),
            Light::Point { position, .. } | Light::Spot { position, .. } => Some(*position),
            _ => None,
        };
        let axis = |l: &Light| match l {
            Light::Spot { direction, .. } => Some(*direction),
            _ => None,
        };
        State {
            eye: c.eye,
            target: c.target,
            up: c.up,
            fov_y: c.fov_y,
            resolution: c.resolution,
            lights: outcome.lights.iter().map(place).collect(),
            spot_directions: outcome.lights.iter().map(axis).collect(),
            frames,
            median_frame_ms,
            validation_messages,
        }
    }
}

fn median(values: impl Iterator<Item = f64>) -> Option<f64> {
    let mut v: Vec<f64> = values.collect();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

/// The window's title: frames per second over the last frames, the passes' GPU time, the
/// plan's reason for each pass of the latest frame, the settings and the predicted error.
fn title(viewer: &viewer::Viewer) -> String {
    let recent = viewer.frame_ms.iter().rev().take(30).copied();
    let fps = median(recent).map_or_else(|| "-".into(), |ms| format!("{:.1}", 1e3 / ms));
    let mut passes: Vec<_> = viewer.timings.passes.iter().map(|(p, ms)| (p.name(), *ms)).collect();
    passes.sort_by(|a, b| b.1.total_cmp(&a.1));
    let gpu: f64 = passes.iter().map(|p| p.1).sum();
    let top: Vec<String> = passes.iter().take(3).map(|(n, ms)| format!("{n} {ms:.1}")).collect();
    let scene = viewer.renderer.scene();
    let render = &scene.scene.file.render;
    let predicted = scene.objects.iter().filter_map(|o| o.density.as_ref().map(|d| d.worst())).fold(0.0, f64::max);
    let why = match viewer.last_change {
        Some(change) => {
            let plan = viewer.renderer.plan(change);
            let passes: Vec<&str> = plan.passes.iter().map(|(p, _)| p.name()).collect();
            format!("{change}: {}", passes.join(", "))
        }
        None => "nothing changed".into(),
    };
    let (device, top, gather) = (viewer.device_name(), top.join(", "), render.gather.name());
    let (target, predicted) = (render.max_error * 100.0, predicted * 100.0);
    format!(
        "translucent on {device} · {fps} frames/s · GPU {gpu:.1} ms ({top}) · {why} · gather {gather} · \
         max error {target}%, predicted {predicted:.2}%"
    )
}
