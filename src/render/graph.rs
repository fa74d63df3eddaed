//! The frame's resources by name, and what each pass declares it reads and writes. A small
//! render graph for a fixed set of passes, after kajiya-rg's `.read()` / `.write()` handles but
//! simpler: the passes run in the plan's order, each says which named `Resource`s it touches and
//! how (`RenderPass::uses`), and the pass loop records the barriers that follow from that
//! (`gpu::Hazards`), across frames too. A pass never names who reads its output, so a new
//! reader needs no edit to its producer.
//!
//! The resources themselves are declared once in `resource`; this module adds the registry that
//! binds them. The same names bind descriptor sets: `Resources::bind` gives each resource with its GLSL
//! block or variable name, and pipeline creation checks it against the name the shader
//! declares at that binding (`gpu::GpuError::BindingMismatch`).

use super::gpu_scene::GpuScene;
use super::targets::FrameTargets;
use crate::gpu::{Binding, Buffer, GpuError, GpuResult, Named};

pub use super::resource::{HOST_READ, Resource, SCENE_BUFFERS, Use, compute_uses, compute_uses_read_write, overwrite, read, write};

/// The registry of the frame's shared resources: the scene's buffers and the frame targets.
/// Passes bind from it by name, so no binding list restates which buffer is which.
#[derive(Clone, Copy)]
pub struct Resources<'a> {
    /// The scene's buffers.
    pub scene: &'a GpuScene,
    /// The shadow maps and camera images.
    pub targets: &'a FrameTargets,
}

impl<'a> Resources<'a> {
    /// The buffer behind a scene resource (`SceneBuffers`), if it is one.
    pub fn buffer(&self, resource: Resource) -> Option<&'a Buffer> {
        self.scene.buffers.get(resource)
    }

    /// `resource` as a descriptor binding under its GLSL name: a scene buffer, or a frame
    /// target's image with its sampler and the layout its readers find it in. An error names a
    /// resource this registry does not hold (a pass's own, or a camera image of a host target).
    pub fn bind(&self, resource: Resource) -> GpuResult<Named<'a>> {
        if let Some(buffer) = self.buffer(resource) {
            return Ok(resource.bind(Binding::Buffer(buffer)));
        }
        self.targets
            .binding(resource)
            .map(|b| resource.bind(b))
            .ok_or_else(|| GpuError::NotShared { resource: resource.glsl_name() })
    }

    /// Every resource of `list` bound in order (binding i = `list[i]`).
    pub fn bind_all(&self, list: &[Resource]) -> GpuResult<Vec<Named<'a>>> {
        list.iter().map(|&r| self.bind(r)).collect()
    }
}
