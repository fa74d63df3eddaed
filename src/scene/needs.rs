//! What a prepared scene contains that decides which passes it needs, and its backdrop: facts
//! about the scene, read by the planner (`render::plan`) and the renderer.

use super::Light;
use super::build::PreparedScene;
use glam::Vec3;

/// What a scene contains that decides its passes.
#[derive(Clone, Debug)]
pub struct SceneNeeds {
    /// Layers of the shadow-map array (0: no shadow pass).
    pub shadow_layers: u32,
    /// Objects with sample points, i.e. translucent ones (0: no splat or gather passes).
    pub translucent_objects: usize,
    /// Scene lights that own at least one shadow-map layer.
    pub shadowed_lights: Vec<usize>,
    /// The scene's environment light, if any (cached per vertex by the vertex-light pass).
    pub environment: Option<usize>,
    /// Exitance gathered per pixel (after shading, every frame) instead of per vertex.
    pub pixel_gather: bool,
    /// Drawn into a host engine's images, which the host tone-maps (set by the renderer).
    pub host_target: bool,
}

impl PreparedScene {
    /// The passes' view of this scene (see `render::plan`).
    pub fn needs(&self) -> SceneNeeds {
        let mut shadowed_lights: Vec<usize> =
            self.lights.iter().filter(|l| l.shadow_layer.is_some()).map(|l| l.source).collect();
        shadowed_lights.dedup();
        SceneNeeds {
            shadow_layers: self.shadow_layers,
            translucent_objects: self.objects.iter().filter(|o| !o.samples.is_empty()).count(),
            shadowed_lights,
            environment: self.lights.iter().find(|l| l.environment).map(|l| l.source),
            pixel_gather: self.scene.file.render.gather == super::GatherMode::Pixel,
            host_target: false,
        }
    }

    /// The colour behind everything: `render.background`, else the environment's radiance at
    /// the horizon (scaled as the light is), else black.
    pub fn background(&self) -> [f32; 3] {
        if let Some(colour) = self.scene.file.render.background {
            return colour;
        }
        let Some(env) = &self.environment else {
            return [0.0; 3];
        };
        let scale = self
            .scene
            .file
            .lights
            .iter()
            .find_map(|l| match l {
                Light::Environment { scale, .. } => Some(*scale),
                _ => None,
            })
            .unwrap_or(1.0);
        let row = env.height / 2 - 1;
        let sum: Vec3 = env.radiance[row * env.width..(row + 1) * env.width].iter().sum();
        (sum / env.width as f32 * scale).to_array()
    }

    /// The shadow-map layers of scene light `source` (several for an environment).
    pub fn shadow_layers_of(&self, source: usize) -> Vec<u32> {
        self.lights.iter().filter(|l| l.source == source).filter_map(|l| l.shadow_layer).collect()
    }
}
