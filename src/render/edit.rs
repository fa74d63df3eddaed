//! `SceneEdit`: one change a host or the command line makes to a renderer's scene between
//! frames (`Renderer::edit`). Each is applied to the prepared scene and re-prepared only as far
//! as it reaches: a camera or light is re-packed, a material re-packs one object's record, a
//! transform re-places and resamples one object and remakes the scene's GPU data, a resize
//! remakes the camera images. The renderer itself, its timers, frame targets and planner
//! history, stays; the planner learns what changed (`plan::Change`).

use super::camera::CameraView;
use crate::optics::Material;
use crate::scene::{Light, Transform};

/// One edit of the scene a renderer draws.
#[derive(Clone, Debug)]
pub enum SceneEdit {
    /// Move the camera (`Change::Camera`).
    Camera(CameraView),
    /// Resize the own target (`Change::Camera`); the camera's projection is the caller's.
    Resize {
        /// New width in pixels.
        width: u32,
        /// New height in pixels.
        height: u32,
    },
    /// Replace scene light `index` by a light of the same kind (`Change::Light`).
    Light {
        /// Index in the scene's lights.
        index: usize,
        /// The new light.
        light: Light,
    },
    /// Replace a translucent object's coefficients, same samples (`Change::Material`).
    Material {
        /// Index in the scene's objects.
        object: usize,
        /// The new material.
        material: Material,
    },
    /// Move an object: placed and resampled anew (`Change::Geometry`).
    Transform {
        /// Index in the scene's objects.
        object: usize,
        /// Its new transform.
        transform: Transform,
    },
    /// Draw another prepared scene: the same file prepared with other settings (the gather,
    /// the error target and so the sample counts, an object's model), or another file. The
    /// scene's GPU data, frame targets and passes are made anew; the renderer keeps its
    /// timers, its frame numbers (a frame recorded before can still be timed) and its camera.
    /// The next frame computes everything (`Change::Everything`). Call with no frame of this
    /// renderer in flight; on an error nothing changed.
    Scene(Box<crate::scene::build::PreparedScene>),
}
