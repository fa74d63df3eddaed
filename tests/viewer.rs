//! `translucent view` used as a person would (issue 48): on an X display of its own (Xvfb), the
//! viewer opens the built-in scene; xdotool orbits the camera, drags a light with Ctrl held and
//! resizes the window, then presses `q`. The image the viewer presented last, read back from
//! its swapchain, must match a headless render of the camera and lights it reports, and the
//! validation layer must have stayed silent throughout.
#![cfg(all(feature = "viewer", feature = "study"))]

mod common;

use common::{run_all, temp_dir, text, with_gpu};
use std::path::Path;
use std::process::{Child, Command, Output, Stdio};
use std::thread::sleep;
use std::time::{Duration, Instant};
use translucent::scene::{Light, Scene};
use translucent::{Overrides, PreparedScene};

/// The FLIP mean the window may differ from the headless image by. Both tone-map with the same
/// curve in f32; a driver may round the swapchain's UNORM conversion differently from
/// `packUnorm4x8`, which moves a channel by one step: FLIP means well under 0.001.
const FLIP_TOLERANCE: f64 = 0.002;

const INSTALL: &str = "the viewer's test needs Xvfb and xdotool: run `bash scripts/setup` (Debian: xvfb xdotool)";

/// An Xvfb server on a display number no other server holds, killed on drop.
struct Display {
    server: Child,
    name: String,
}

impl Display {
    /// A server on the first free display from `first` (each test its own range: the tests of
    /// this file run in parallel). One server starts at a time: on a fresh machine two Xvfb
    /// starting at once race to create `/tmp/.X11-unix`, and the loser runs without its socket
    /// file (reproduced). Ready when a client connects, through whichever socket it has.
    fn start(first: u32) -> Display {
        static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());
        let _starting = ONE_AT_A_TIME.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let number =
            (first..first + 100).find(|n| !Path::new(&format!("/tmp/.X{n}-lock")).exists()).expect("a free display");
        let name = format!(":{number}");
        let server = Command::new("Xvfb")
            .args([&name, "-screen", "0", "1024x768x24", "-nolisten", "tcp"])
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start Xvfb ({e}): {INSTALL}"));
        // Owned from here, so a failed start still kills the server.
        let mut display = Display { server, name };
        let started = Instant::now();
        while !display.accepts() {
            let exited = display.server.try_wait().expect("waiting on Xvfb");
            assert!(exited.is_none(), "Xvfb {} exited at start: {exited:?}", display.name);
            assert!(started.elapsed() < Duration::from_secs(30), "Xvfb {} took no client in 30 s", display.name);
            sleep(Duration::from_millis(100));
        }
        display
    }

    /// Whether the server takes a client.
    fn accepts(&self) -> bool {
        Command::new("xdotool")
            .arg("getdisplaygeometry")
            .env("DISPLAY", &self.name)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .unwrap_or_else(|e| panic!("cannot run xdotool ({e}): {INSTALL}"))
            .success()
    }

    fn xdotool(&self, args: &[&str]) -> String {
        let output = Command::new("xdotool")
            .args(args)
            .env("DISPLAY", &self.name)
            .output()
            .unwrap_or_else(|e| panic!("cannot run xdotool ({e}): {INSTALL}"));
        assert!(output.status.success(), "xdotool {args:?}: {}", text(&output.stderr));
        text(&output.stdout)
    }

    /// `translucent view ARGS` on this display with validation on, and its window once it is
    /// mapped.
    fn open_viewer(&self, args: &[&str]) -> (Child, String) {
        let viewer = Command::new(env!("CARGO_BIN_EXE_translucent"))
            .arg("view")
            .args(args)
            .env("DISPLAY", &self.name)
            .env("TRANSLUCENT_VALIDATION", "1")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("the translucent binary");
        let window = self.xdotool(&["search", "--sync", "--name", "^translucent"]);
        (viewer, window.lines().next().expect("the viewer's window").to_string())
    }

    /// Press button 1 at `from`, move to `to` in steps, release.
    fn drag(&self, window: &str, from: (i32, i32), to: (i32, i32)) {
        self.xdotool(&["mousemove", "--window", window, &from.0.to_string(), &from.1.to_string(), "mousedown", "1"]);
        for step in 1..=10 {
            let x = from.0 + (to.0 - from.0) * step / 10;
            let y = from.1 + (to.1 - from.1) * step / 10;
            self.xdotool(&["mousemove", "--window", window, &x.to_string(), &y.to_string()]);
            sleep(Duration::from_millis(40));
        }
        self.xdotool(&["mouseup", "1"]);
        sleep(Duration::from_millis(300));
    }
}

impl Drop for Display {
    fn drop(&mut self) {
        let _ = self.server.kill();
        let _ = self.server.wait();
    }
}

/// Wait for the viewer to exit, at most three minutes after it was asked to.
fn finish(mut viewer: Child) -> Output {
    let started = Instant::now();
    while viewer.try_wait().expect("waiting on the viewer").is_none() {
        if started.elapsed() > Duration::from_secs(180) {
            let _ = viewer.kill();
            panic!("the viewer did not close within 3 minutes of `q`");
        }
        sleep(Duration::from_millis(100));
    }
    viewer.wait_with_output().expect("the viewer's output")
}

/// The built-in scene with the camera and lights the viewer's `--state` reports.
fn scene_of_state(state: &serde_json::Value) -> PreparedScene {
    let three = |v: &serde_json::Value| -> [f32; 3] { std::array::from_fn(|i| v[i].as_f64().unwrap() as f32) };
    let mut scene = Scene::builtin();
    let camera = &mut scene.file.camera;
    camera.eye = three(&state["eye"]);
    camera.target = three(&state["target"]);
    camera.up = three(&state["up"]);
    camera.fov_y = state["fov_y"].as_f64().unwrap() as f32;
    camera.resolution = std::array::from_fn(|i| state["resolution"][i].as_u64().unwrap() as u32);
    for (light, place) in scene.file.lights.iter_mut().zip(state["lights"].as_array().unwrap()) {
        match light {
            Light::Directional { direction, .. } => *direction = three(place),
            Light::Point { position, .. } | Light::Spot { position, .. } => *position = three(place),
            _ => {}
        }
    }
    let mut prepared = PreparedScene::new(&scene, &Overrides::default()).unwrap();
    attach_kernels(&mut prepared);
    prepared
}

/// The transport kernels `model = "auto"` chose for `prepared`, from the cache the viewer reads
/// (walked there by the first test that needs them, while the others wait, so that no two walk
/// the bunny's at once).
fn attach_kernels(prepared: &mut PreparedScene) {
    use translucent::reference::{rte_mesh::KernelSettings, transport_cache, truth};
    static WALK: std::sync::Mutex<()> = std::sync::Mutex::new(());
    let _one = WALK.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let dir = truth::default_cache_dir();
    transport_cache::attach(&mut prepared.objects, &KernelSettings::default(), &dir, &|_, _, _| {}).unwrap();
}

#[test]
fn the_window_after_orbit_light_drag_and_resize_shows_the_headless_image_without_a_validation_message() {
    let dir = temp_dir("viewer");
    let (shot, state) = (dir.join("shot.png"), dir.join("state.json"));
    let display = Display::start(90);
    attach_kernels(&mut PreparedScene::new(&Scene::builtin(), &Overrides::default()).unwrap());
    let (viewer, window) =
        display.open_viewer(&["--screenshot", shot.to_str().unwrap(), "--state", state.to_str().unwrap()]);
    sleep(Duration::from_secs(2));
    display.xdotool(&["windowfocus", "--sync", &window]);
    // Sideways: the sky stays in view, so the background is compared too.
    display.drag(&window, (256, 256), (336, 256));
    display.xdotool(&["keydown", "ctrl"]);
    display.drag(&window, (300, 100), (200, 150));
    display.xdotool(&["keyup", "ctrl"]);
    display.xdotool(&["windowsize", "--sync", &window, "400", "320"]);
    sleep(Duration::from_secs(2));
    display.xdotool(&["key", "q"]);
    let output = finish(viewer);
    assert!(output.status.success(), "the viewer failed: {}{}", text(&output.stdout), text(&output.stderr));
    assert!(text(&output.stdout).contains(", 0 validation messages"), "{}", text(&output.stdout));

    let state: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&state).unwrap()).unwrap();
    assert_eq!(state["resolution"], serde_json::json!([400, 320]), "the resize reached the viewer");
    assert_ne!(state["eye"], serde_json::json!([0.0, 0.075, 0.16]), "the orbit moved the camera");
    assert_ne!(state["lights"][0], serde_json::json!([0.7, 0.6, -0.4]), "the Ctrl-drag turned the sun");
    let window_image = image::open(&shot).unwrap().to_rgba8();
    assert_eq!(window_image.dimensions(), (400, 320));
    let headless = with_gpu(|gpu| run_all(gpu, scene_of_state(&state)).image().unwrap().0);
    let flip = translucent::study::flip::flip_mean(&headless, window_image.as_raw(), 400, 320).unwrap();
    let differing = headless.iter().zip(window_image.as_raw()).filter(|(a, b)| a != b).count();
    eprintln!("window against headless: FLIP mean {flip:.2e}, {differing} bytes differ");
    assert!(flip <= FLIP_TOLERANCE, "FLIP mean {flip} over {FLIP_TOLERANCE} ({differing} bytes differ)");
}

/// Closing mid-frame: the window destroyed under the viewer while it draws (its surface lost)
/// ends it as a close does, with status 0 and no validation message.
#[test]
fn a_window_destroyed_mid_frame_closes_the_viewer_without_a_validation_message() {
    let display = Display::start(190);
    attach_kernels(&mut PreparedScene::new(&Scene::builtin(), &Overrides::default()).unwrap());
    let (viewer, window) = display.open_viewer(&["--samples", "2000"]);
    // The title shows frames/s once frames are being drawn.
    let started = Instant::now();
    while !display.xdotool(&["getwindowname", &window]).contains("frames/s") {
        assert!(started.elapsed() < Duration::from_secs(120), "the viewer drew nothing in two minutes");
        sleep(Duration::from_millis(200));
    }
    display.xdotool(&["windowclose", &window]);
    let output = finish(viewer);
    assert!(output.status.success(), "the viewer failed: {}{}", text(&output.stdout), text(&output.stderr));
    assert!(text(&output.stdout).contains(", 0 validation messages"), "{}", text(&output.stdout));
}
