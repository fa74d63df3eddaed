//! The window and its events (winit): the mouse moves the camera and the lights, the keys
//! switch settings, and each redraw applies what changed as `SceneEdit`s and draws a frame.

use super::controls::{self, Orbit};
use super::host::Host;
use super::present::Marker;
use super::viewer::Viewer;
use super::{Args, Outcome};
use anyhow::{Context, Result};
use ash::vk;
use glam::Vec3;
use std::time::{Duration, Instant};
use translucent::scene::{Light, MaterialSpec, Scene};
use translucent::{CameraView, Overrides, PreparedScene, SceneEdit};
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::ActiveEventLoop;
use winit::keyboard::{Key, ModifiersState, NamedKey};
use winit::window::{Window, WindowId};

/// What a mouse drag moves.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Drag {
    Orbit,
    Pan,
    Light(usize),
}

/// The viewer's state between events. `viewer` is declared before `window`: it drops first,
/// so the surface goes before the window it was made for.
pub struct App {
    args: Args,
    gpu_args: super::super::GpuArgs,
    scene: Scene,
    overrides: Overrides,
    /// The scene prepared before the window opens (sampling takes seconds on a large mesh, and
    /// a bad scene is better refused before a window appears); taken by the viewer.
    prepared: Option<PreparedScene>,
    pub viewer: Option<Viewer>,
    window: Option<Window>,
    orbit: Option<Orbit>,
    lights: Vec<Light>,
    moved_lights: Vec<usize>,
    camera_moved: bool,
    drag: Option<Drag>,
    cursor: [f32; 2],
    modifiers: ModifiersState,
    frames: u64,
    closing: bool,
    /// The window's size as its last resize said: asked of X only when the window opens, since
    /// a window destroyed under the viewer cannot be asked (winit panics).
    size: PhysicalSize<u32>,
    title_at: Option<Instant>,
    pub outcome: Option<Result<Outcome>>,
}

impl App {
    pub fn new(args: Args, gpu_args: super::super::GpuArgs, scene: Scene, overrides: Overrides) -> Result<App> {
        let lights = scene.file.lights.clone();
        // The kernels `model = "auto"` or `"transport"` chose, as `render` attaches them, so the
        // window shows what `render` writes (walked once with a progress bar, then cached).
        let mut prepared = PreparedScene::new(&scene, &overrides)?;
        super::super::attach_kernels(&mut prepared, None)?;
        let prepared = Some(prepared);
        Ok(App {
            args,
            gpu_args,
            scene,
            overrides,
            prepared,
            viewer: None,
            window: None,
            orbit: None,
            lights,
            moved_lights: Vec::new(),
            camera_moved: true,
            drag: None,
            cursor: [0.0; 2],
            modifiers: ModifiersState::empty(),
            frames: 0,
            closing: false,
            size: PhysicalSize::new(0, 0),
            title_at: None,
            outcome: None,
        })
    }

    /// The window, the Vulkan on it and the renderer, at the scene's resolution.
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let [w, h] = self.scene.file.camera.resolution;
        let attributes =
            Window::default_attributes().with_title("translucent").with_inner_size(PhysicalSize::new(w, h));
        let window = event_loop.create_window(attributes).context("opening a window (is DISPLAY set?)")?;
        let validation = self.gpu_args.options().validation;
        let host = Host::new(&window, self.gpu_args.device.as_deref(), validation)?;
        let prepared = self.prepared.take().context("the window opens once")?;
        let radius = prepared.bounds.1;
        let size = window.inner_size();
        self.size = size;
        let viewer =
            Viewer::new(host, prepared, vk::Extent2D { width: size.width, height: size.height }, self.args.vsync)?;
        let mut camera = self.scene.file.camera.clone();
        let extent = viewer.extent();
        camera.resolution = [extent.width, extent.height];
        self.orbit = Some(Orbit::new(camera, radius));
        self.viewer = Some(viewer);
        self.window = Some(window);
        Ok(())
    }

    /// Apply what the input changed, draw a frame, and end the loop when asked to.
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<()> {
        let (Some(_), Some(viewer), Some(orbit)) = (&self.window, &mut self.viewer, &mut self.orbit) else {
            return Ok(());
        };
        let size = self.size;
        if size.width == 0 || size.height == 0 {
            return Ok(()); // minimised: nothing to draw until the window comes back
        }
        if viewer.stale || viewer.extent() != (vk::Extent2D { width: size.width, height: size.height }) {
            viewer.recreate(vk::Extent2D { width: size.width, height: size.height })?;
            let extent = viewer.extent();
            orbit.camera.resolution = [extent.width, extent.height];
            self.camera_moved = true;
        }
        if self.args.orbit {
            orbit.turn(3.0);
            self.camera_moved = true;
        }
        if std::mem::take(&mut self.camera_moved) {
            viewer.edit(SceneEdit::Camera(CameraView::of_camera(&orbit.camera, viewer.renderer.scene())))?;
        }
        for index in std::mem::take(&mut self.moved_lights) {
            viewer.edit(SceneEdit::Light { index, light: self.lights[index].clone() })?;
        }
        viewer.markers = markers(&self.lights, viewer, orbit, self.modifiers.control_key(), self.drag);
        let last = self.closing || self.args.frames.is_some_and(|n| self.frames + 1 >= n);
        let shot = last && self.args.screenshot.is_some();
        let image = viewer.draw(shot)?;
        if viewer.lost {
            // The window was destroyed under the viewer: close as if asked to.
            self.outcome = Some(Ok(Outcome::closed(self)));
            event_loop.exit();
            return Ok(());
        }
        if viewer.stale && image.is_none() && shot {
            return Ok(()); // out of date: the next redraw remakes the swapchain and tries again
        }
        let camera = orbit.camera.clone();
        self.frames += 1;
        self.show_title();
        if last {
            let outcome = Outcome { image, camera, lights: self.lights.clone() };
            self.outcome = Some(Ok(outcome));
            event_loop.exit();
        }
        Ok(())
    }

    /// Frames per second, the passes' timestamps, what the planner ran and why, the settings
    /// and the predicted error, in the window's title, twice a second.
    fn show_title(&mut self) {
        let (Some(window), Some(viewer)) = (&self.window, &mut self.viewer) else { return };
        let now = Instant::now();
        if self.title_at.is_some_and(|t| now - t < Duration::from_millis(500)) {
            return;
        }
        self.title_at = Some(now);
        window.set_title(&super::title(viewer));
    }

    fn on_key(&mut self, key: &Key) -> Result<()> {
        match key {
            Key::Named(NamedKey::Escape) => self.closing = true,
            Key::Character(c) => match c.as_str() {
                "q" => self.closing = true,
                "m" => self.cycle(Setting::Model)?,
                "g" => self.cycle(Setting::Gather)?,
                "e" => self.cycle(Setting::Error)?,
                "r" => {
                    let resolution = self.orbit.as_ref().map(|o| o.camera.resolution);
                    let mut camera = self.scene.file.camera.clone();
                    camera.resolution = resolution.unwrap_or(camera.resolution);
                    let radius = self.viewer.as_ref().map_or(1.0, |v| v.renderer.scene().bounds.1);
                    self.orbit = Some(Orbit::new(camera, radius));
                    self.camera_moved = true;
                }
                _ => {}
            },
            _ => {}
        }
        Ok(())
    }

    /// Switch a setting the renderer takes when it is made, and make it again.
    fn cycle(&mut self, setting: Setting) -> Result<()> {
        let file = &mut self.scene.file;
        match setting {
            Setting::Model => {
                for object in &mut file.objects {
                    if let MaterialSpec::Translucent { model, .. } = &mut object.material {
                        *model = controls::next_model(*model);
                    }
                }
            }
            Setting::Gather => {
                let now = self.overrides.gather.unwrap_or(file.render.gather);
                self.overrides.gather = Some(controls::next_gather(now));
            }
            Setting::Error => {
                let now = self.overrides.max_error.unwrap_or(file.render.max_error);
                self.overrides.max_error = Some(controls::next_error(now));
            }
        }
        file.lights.clone_from(&self.lights);
        let mut prepared = PreparedScene::new(&self.scene, &self.overrides)?;
        super::super::attach_kernels(&mut prepared, None)?;
        if let Some(viewer) = &mut self.viewer {
            viewer.rebuild(prepared)?;
            self.camera_moved = true;
            self.title_at = None;
        }
        Ok(())
    }

    fn on_cursor(&mut self, x: f32, y: f32) {
        let (dx, dy) = (x - self.cursor[0], y - self.cursor[1]);
        self.cursor = [x, y];
        let (Some(drag), Some(orbit)) = (self.drag, &mut self.orbit) else { return };
        match drag {
            Drag::Orbit => orbit.orbit(dx, dy),
            Drag::Pan => orbit.pan(dx, dy, orbit.camera.resolution[1] as f32),
            Drag::Light(i) => {
                let Some(viewer) = &self.viewer else { return };
                let centre = viewer.renderer.scene().bounds.0;
                let camera = CameraView::of_camera(&orbit.camera, viewer.renderer.scene());
                let right = camera.view.inverse().transform_vector3(Vec3::X);
                self.lights[i] = controls::turn_light(&self.lights[i], centre, Vec3::Y, right, dx, dy);
                if !self.moved_lights.contains(&i) {
                    self.moved_lights.push(i);
                }
                return;
            }
        }
        self.camera_moved = true;
    }

    fn on_button(&mut self, button: MouseButton, state: ElementState) {
        if state == ElementState::Released {
            self.drag = None;
            return;
        }
        self.drag = match button {
            MouseButton::Left if self.modifiers.control_key() => self.pick_light().map(Drag::Light),
            MouseButton::Left => Some(Drag::Orbit),
            MouseButton::Right | MouseButton::Middle => Some(Drag::Pan),
            _ => None,
        };
    }

    /// The light whose marker is under the cursor.
    fn pick_light(&self) -> Option<usize> {
        let (viewer, orbit) = (self.viewer.as_ref()?, self.orbit.as_ref()?);
        let camera = CameraView::of_camera(&orbit.camera, viewer.renderer.scene());
        let size = orbit.camera.resolution.map(|v| v as f32);
        let (target, reach) = orbit.anchor_frame();
        controls::pick_light(&self.lights, target, reach, camera.projection * camera.view, self.cursor, size)
    }

    fn fail(&mut self, event_loop: &ActiveEventLoop, error: anyhow::Error) {
        self.outcome = Some(Err(error));
        event_loop.exit();
    }
}

/// Rings over the lights' anchors while Ctrl is held or a light is dragged; none otherwise (so
/// what is presented is the scene alone).
fn markers(lights: &[Light], viewer: &Viewer, orbit: &Orbit, picking: bool, drag: Option<Drag>) -> Vec<Marker> {
    let dragged = match drag {
        Some(Drag::Light(i)) => Some(i),
        _ => None,
    };
    if !picking && dragged.is_none() {
        return Vec::new();
    }
    let camera = CameraView::of_camera(&orbit.camera, viewer.renderer.scene());
    let size = orbit.camera.resolution.map(|v| v as f32);
    let (target, reach) = orbit.anchor_frame();
    controls::screen_anchors(lights, target, reach, camera.projection * camera.view, size)
        .into_iter()
        .map(|(i, at)| Marker { at, radius: 10.0, dragged: dragged == Some(i) })
        .collect()
}

#[derive(Clone, Copy)]
enum Setting {
    Model,
    Gather,
    Error,
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.window.is_none()
            && let Err(e) = self.open(event_loop)
        {
            self.fail(event_loop, e);
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let result = match event {
            WindowEvent::CloseRequested => {
                self.closing = true;
                if self.args.screenshot.is_none() {
                    self.outcome = Some(Ok(Outcome::closed(self)));
                    event_loop.exit();
                }
                Ok(())
            }
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::Destroyed => {
                self.outcome = Some(Ok(Outcome::closed(self)));
                event_loop.exit();
                Ok(())
            }
            WindowEvent::Resized(size) => {
                self.size = size;
                self.viewer.iter_mut().for_each(|v| v.stale = true);
                Ok(())
            }
            WindowEvent::ModifiersChanged(m) => {
                self.modifiers = m.state();
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } if event.state == ElementState::Pressed => {
                self.on_key(&event.logical_key)
            }
            WindowEvent::CursorMoved { position, .. } => {
                self.on_cursor(position.x as f32, position.y as f32);
                Ok(())
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.on_button(button, state);
                Ok(())
            }
            WindowEvent::MouseWheel { delta, .. } => {
                let steps = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(orbit) = &mut self.orbit {
                    orbit.zoom(steps);
                    self.camera_moved = true;
                }
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(event_loop, e);
        }
    }

    fn about_to_wait(&mut self, _event_loop: &ActiveEventLoop) {
        if let Some(window) = &self.window {
            window.request_redraw();
        }
    }
}

impl Outcome {
    /// What a window closed without a last frame leaves.
    fn closed(app: &App) -> Outcome {
        let camera = app.orbit.as_ref().map_or_else(|| app.scene.file.camera.clone(), |o| o.camera.clone());
        Outcome { image: None, camera, lights: app.lights.clone() }
    }
}
