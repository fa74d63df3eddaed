//! The camera's matrices, in Vulkan conventions (depth 0..1, framebuffer y down).

use super::format::Camera;
use glam::camera::rh::{proj::vulkan, view::look_at_mat4};
use glam::{Mat4, Vec3};

impl Camera {
    /// World -> view matrix looking from `eye` at `target` with `up` as the image's up.
    pub fn view(&self) -> Mat4 {
        // `up` is normalised in f64: the checks allow any non-zero finite vector, even one whose
        // squared length is 0 or infinite in f32.
        look_at_mat4(Vec3::from(self.eye), Vec3::from(self.target), super::lights::unit(Vec3::from(self.up)))
    }

    /// Perspective projection with near and far planes fitted around a scene bounding sphere.
    pub fn projection(&self, scene_center: Vec3, scene_radius: f32) -> Mat4 {
        let aspect = self.resolution[0] as f32 / self.resolution[1] as f32;
        let (near, far) = self.depth_range(scene_center, scene_radius);
        // The Vulkan variant outputs y down, as the framebuffer is, so +y is up in the image.
        vulkan::perspective(self.fov_y.to_radians(), aspect, near, far)
    }

    /// The near and far planes' distances around a scene bounding sphere: the sphere's depth
    /// seen from `eye`, the near plane at least 1e-4 of the far one (depth precision).
    pub fn depth_range(&self, scene_center: Vec3, scene_radius: f32) -> (f32, f32) {
        let distance = (Vec3::from(self.eye) - scene_center).length();
        let far = (distance + scene_radius) * 1.05;
        ((distance - scene_radius).max(far * 1e-4), far)
    }
}
