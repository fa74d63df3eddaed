//! What the mouse and keys do to the scene, without a window: the orbit camera (orbit, zoom,
//! pan), picking and turning a light about the scene's centre, and the settings the keys cycle.

use glam::{Mat4, Quat, Vec3};
use translucent::scene::{Camera, GatherMode, Light, ScatteringModel};

/// Degrees the camera or a light turns per pixel dragged.
const DEGREES_PER_PIXEL: f32 = 0.4;
/// The camera's pitch stays this far from the poles, so `up` never lines up with the view.
const MAX_PITCH_DEGREES: f32 = 89.0;

/// The scene file's camera, moved by the mouse. Until the first move it is the file's own, bit
/// for bit, so the first frame is the one `translucent render` draws.
#[derive(Clone, Debug)]
pub struct Orbit {
    /// The camera as a scene file would state it (its resolution is the window's).
    pub camera: Camera,
    /// The scene's bounding sphere, which zoom keeps the camera outside of a sliver of.
    radius: f32,
}

impl Orbit {
    pub fn new(camera: Camera, radius: f32) -> Orbit {
        Orbit { camera, radius }
    }

    fn eye(&self) -> Vec3 {
        Vec3::from(self.camera.eye)
    }

    fn target(&self) -> Vec3 {
        Vec3::from(self.camera.target)
    }

    fn up(&self) -> Vec3 {
        Vec3::from(self.camera.up).normalize()
    }

    /// The image's right and up directions in the world.
    fn image_axes(&self) -> (Vec3, Vec3) {
        let forward = (self.target() - self.eye()).normalize();
        let right = forward.cross(self.up()).normalize();
        (right, right.cross(forward))
    }

    /// Turn about the target: `dx` pixels about the up axis, `dy` about the image's horizontal
    /// axis, the pitch kept off the poles.
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        let offset = self.eye() - self.target();
        let up = self.up();
        let pitch_now = (offset.normalize().dot(up)).clamp(-1.0, 1.0).asin().to_degrees();
        let pitch = (pitch_now + dy * DEGREES_PER_PIXEL).clamp(-MAX_PITCH_DEGREES, MAX_PITCH_DEGREES) - pitch_now;
        let (right, _) = self.image_axes();
        let turn = Quat::from_axis_angle(up, (-dx * DEGREES_PER_PIXEL).to_radians())
            * Quat::from_axis_angle(right, (-pitch).to_radians());
        self.camera.eye = (self.target() + turn * offset).to_array();
    }

    /// Turn about the target by `degrees` about the up axis (`--orbit`: 3 a frame, as
    /// `translucent render --moving camera` turns).
    pub fn turn(&mut self, degrees: f32) {
        self.orbit(degrees / DEGREES_PER_PIXEL, 0.0);
    }

    /// Move the camera towards the target (`steps` > 0) or away, 10% of the distance a step.
    pub fn zoom(&mut self, steps: f32) {
        let offset = self.eye() - self.target();
        let distance = (offset.length() * 0.9f32.powf(steps)).max(self.radius * 1e-3);
        self.camera.eye = (self.target() + offset.normalize() * distance).to_array();
    }

    /// Where directional lights are grabbed: towards each from the target, a third of the way
    /// to the eye (so on screen unless the light is behind the eye or the view).
    pub fn anchor_frame(&self) -> (Vec3, f32) {
        (self.target(), (self.eye() - self.target()).length() / 3.0)
    }

    /// Slide the camera and its target in the image plane so that the point under the cursor
    /// follows it: `dx`, `dy` in pixels of a window `height` pixels tall.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let distance = (self.eye() - self.target()).length();
        let per_pixel = 2.0 * distance * (self.camera.fov_y.to_radians() * 0.5).tan() / height.max(1.0);
        let (right, up) = self.image_axes();
        let shift = (-dx * right + dy * up) * per_pixel;
        self.camera.eye = (self.eye() + shift).to_array();
        self.camera.target = (self.target() + shift).to_array();
    }
}

/// Where a light is grabbed: a point light's or spot's position, or for a directional light
/// the point `reach` from `centre` towards it. None for the sky.
pub fn light_anchor(light: &Light, centre: Vec3, reach: f32) -> Option<Vec3> {
    match light {
        Light::Directional { direction, .. } => Some(centre + Vec3::from(*direction).normalize() * reach),
        Light::Point { position, .. } | Light::Spot { position, .. } => Some(Vec3::from(*position)),
        _ => None,
    }
}

/// Where each light's anchor lands in a `size` window seen through `view_proj` (pixels), for
/// the lights in front of the camera.
pub fn screen_anchors(
    lights: &[Light],
    centre: Vec3,
    reach: f32,
    view_proj: Mat4,
    size: [f32; 2],
) -> Vec<(usize, [f32; 2])> {
    let on_screen = |p: Vec3| {
        let clip = view_proj * p.extend(1.0);
        (clip.w > 0.0).then(|| [(clip.x / clip.w * 0.5 + 0.5) * size[0], (clip.y / clip.w * 0.5 + 0.5) * size[1]])
    };
    lights
        .iter()
        .enumerate()
        .filter_map(|(i, l)| light_anchor(l, centre, reach).and_then(on_screen).map(|p| (i, p)))
        .collect()
}

/// The light whose anchor lands nearest `cursor` (pixels) in a `size` window seen through
/// `view_proj`, among those in front of the camera (the nearest however far: the rings are
/// drawn while Ctrl is held, so the user sees which).
pub fn pick_light(
    lights: &[Light],
    centre: Vec3,
    reach: f32,
    view_proj: Mat4,
    cursor: [f32; 2],
    size: [f32; 2],
) -> Option<usize> {
    screen_anchors(lights, centre, reach, view_proj, size)
        .into_iter()
        .map(|(i, p)| (i, (p[0] - cursor[0]).hypot(p[1] - cursor[1])))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|(i, _)| i)
}

/// `light` turned about `centre` as the camera's orbit turns the eye: `dx` pixels about
/// `up`, `dy` about `right`. The sky stays.
pub fn turn_light(light: &Light, centre: Vec3, up: Vec3, right: Vec3, dx: f32, dy: f32) -> Light {
    let turn = Quat::from_axis_angle(up, (dx * DEGREES_PER_PIXEL).to_radians())
        * Quat::from_axis_angle(right, (-dy * DEGREES_PER_PIXEL).to_radians());
    let about = |p: [f32; 3]| (centre + turn * (Vec3::from(p) - centre)).to_array();
    let mut light = light.clone();
    match &mut light {
        Light::Directional { direction, .. } => *direction = (turn * Vec3::from(*direction)).to_array(),
        Light::Point { position, .. } => *position = about(*position),
        Light::Spot { position, direction, .. } => {
            *position = about(*position);
            *direction = (turn * Vec3::from(*direction)).to_array();
        }
        _ => {}
    }
    light
}

/// The next scattering model the `M` key gives (transport needs a walked kernel: not cycled).
pub fn next_model(model: ScatteringModel) -> ScatteringModel {
    match model {
        ScatteringModel::Dipole => ScatteringModel::Auto,
        ScatteringModel::Auto => ScatteringModel::Single,
        ScatteringModel::Single | ScatteringModel::Transport => ScatteringModel::Dipole,
    }
}

/// The next gather the `G` key gives (the pixel gather draws into the renderer's own image
/// only, so a host target never takes it).
pub fn next_gather(gather: GatherMode) -> GatherMode {
    match gather {
        GatherMode::Vertex => GatherMode::Hierarchical,
        GatherMode::Hierarchical => GatherMode::Sparse,
        _ => GatherMode::Vertex,
    }
}

/// The error targets the `E` key steps through, per vertex against the exact integral.
pub const ERROR_TARGETS: [f64; 4] = [0.01, 0.03, 0.1, 0.003];

/// The next error target after `now`.
pub fn next_error(now: f64) -> f64 {
    let at = ERROR_TARGETS.iter().position(|&e| (e - now).abs() < 1e-12);
    ERROR_TARGETS[at.map_or(0, |i| (i + 1) % ERROR_TARGETS.len())]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn camera() -> Camera {
        Camera { eye: [0.0, 0.0, 3.0], target: [0.0; 3], up: [0.0, 1.0, 0.0], fov_y: 35.0, resolution: [512, 512] }
    }

    #[test]
    fn orbiting_keeps_the_distance_and_stops_short_of_the_pole() {
        let mut orbit = Orbit::new(camera(), 1.0);
        orbit.orbit(100.0, 0.0);
        assert!((Vec3::from(orbit.camera.eye).length() - 3.0).abs() < 1e-5);
        assert!(orbit.camera.eye[0].abs() > 1.0, "{:?}", orbit.camera.eye);
        orbit.orbit(0.0, 10_000.0);
        let pitch = (orbit.camera.eye[1] / 3.0).asin().to_degrees();
        assert!((pitch - MAX_PITCH_DEGREES).abs() < 0.01, "{pitch}");
    }

    #[test]
    fn zoom_and_pan_move_the_eye_as_asked() {
        let mut orbit = Orbit::new(camera(), 1.0);
        orbit.zoom(1.0);
        assert!((orbit.camera.eye[2] - 2.7).abs() < 1e-5);
        orbit.pan(10.0, 0.0, 512.0);
        assert!(orbit.camera.eye[0] < 0.0 && orbit.camera.target[0] < 0.0);
    }

    #[test]
    fn a_turned_light_keeps_its_distance_and_the_nearest_anchor_is_picked() {
        let light = Light::Point { position: [2.0, 0.0, 0.0], intensity: [1.0; 3], shadows: true };
        let turned = turn_light(&light, Vec3::ZERO, Vec3::Y, Vec3::X, 90.0 / DEGREES_PER_PIXEL, 0.0);
        let Light::Point { position, .. } = turned else { unreachable!() };
        assert!((Vec3::from(position).length() - 2.0).abs() < 1e-5);
        assert!(position[2].abs() > 1.99, "{position:?}");
        let lights = [light, turned];
        let view_proj = Mat4::from_scale(Vec3::new(0.25, 0.25, 0.1)); // x and y in -4..4 across the window
        assert_eq!(pick_light(&lights, Vec3::ZERO, 1.0, view_proj, [384.0, 256.0], [512.0, 512.0]), Some(0));
        assert_eq!(pick_light(&lights, Vec3::ZERO, 1.0, view_proj, [250.0, 250.0], [512.0, 512.0]), Some(1));
        assert_eq!(pick_light(&lights[..0], Vec3::ZERO, 1.0, view_proj, [250.0, 250.0], [512.0, 512.0]), None);
    }

    #[test]
    fn the_keys_cycle_through_every_setting_and_back() {
        assert_eq!(next_model(next_model(next_model(ScatteringModel::Dipole))), ScatteringModel::Dipole);
        assert_eq!(next_gather(next_gather(next_gather(GatherMode::Vertex))), GatherMode::Vertex);
        let mut e = 0.01;
        for _ in 0..ERROR_TARGETS.len() {
            e = next_error(e);
        }
        assert_eq!(e, 0.01);
    }
}
