//! `Frame`: one frame's inputs to the planner's rules (`objects`, `passes`), and what its change
//! makes stale scene-wide. Below the rules and the `Planner` that applies them.

use super::{Change, SceneNeeds, View};

/// One frame's inputs to the rules (objects.rs, passes.rs): the scene, the view, the change, and
/// what the change makes stale scene-wide.
pub(super) struct Frame<'a> {
    pub needs: &'a SceneNeeds,
    pub view: &'a View,
    pub change: Change,
    /// Visibility and irradiance are stale: lights or geometry changed.
    pub lights_stale: bool,
    /// The environment's per-vertex cache is stale (when the scene has one).
    pub environment_stale: bool,
}

impl<'a> Frame<'a> {
    pub(super) fn new(needs: &'a SceneNeeds, view: &'a View, change: Change) -> Frame<'a> {
        let lights_stale =
            matches!(change, Change::Everything | Change::Lights | Change::Light(_) | Change::Geometry(_));
        let environment_stale = match change {
            Change::Everything | Change::Lights | Change::Geometry(_) => true,
            Change::Light(i) => needs.environment == Some(i),
            Change::Camera | Change::Material(_) => false,
        };
        Frame { needs, view, change, lights_stale, environment_stale }
    }
}
