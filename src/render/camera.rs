//! `CameraView`: where the camera is, as the passes and the planner see it.

use crate::scene::build::PreparedScene;
use glam::{Mat4, Vec3};

/// Where the camera is: world -> view, view -> clip (Vulkan: depth 0..1, y down), and its
/// position (for the specular lobe).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraView {
    /// World -> view.
    pub view: Mat4,
    /// View -> clip (Vulkan clip space: depth 0..1, y down).
    pub projection: Mat4,
    /// Camera position in world space.
    pub eye: Vec3,
}

impl CameraView {
    /// The scene file's camera, its near and far planes fitted around the scene.
    pub fn of_scene(scene: &PreparedScene) -> CameraView {
        CameraView::of_camera(&scene.scene.file.camera, scene)
    }

    /// `camera` (a scene file's `[camera]`: eye, target, up, field of view, and its resolution
    /// for the aspect ratio) in `scene`, its near and far planes fitted around the scene: how a
    /// host that moves the camera itself (the viewer) gives it to `SceneEdit::Camera`.
    pub fn of_camera(camera: &crate::scene::Camera, scene: &PreparedScene) -> CameraView {
        CameraView {
            view: camera.view(),
            projection: camera.projection(scene.bounds.0, scene.bounds.1),
            eye: Vec3::from(camera.eye),
        }
    }

    /// This camera with its depth reversed (reversed-Z, `DepthConvention::Reversed`): clip
    /// depth `z` becomes `w - z`, so that the near plane is at 1 and the far plane at 0; what
    /// is drawn where is unchanged.
    pub fn reversed_depth(self) -> CameraView {
        let reverse = Mat4::from_cols(
            glam::Vec4::X,
            glam::Vec4::Y,
            glam::Vec4::new(0.0, 0.0, -1.0, 0.0),
            glam::Vec4::new(0.0, 0.0, 1.0, 1.0),
        );
        CameraView { projection: reverse * self.projection, ..self }
    }

    /// This camera turned by `degrees` about the vertical axis through `centre` (the world
    /// turning the other way in its view).
    pub fn orbited(self, centre: Vec3, degrees: f32) -> CameraView {
        let turn = Mat4::from_translation(centre)
            * Mat4::from_rotation_y(degrees.to_radians())
            * Mat4::from_translation(-centre);
        CameraView {
            view: self.view * turn.inverse(),
            projection: self.projection,
            eye: turn.transform_point3(self.eye),
        }
    }
}

