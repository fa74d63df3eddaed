//! Local-exitance pass (`glsl/local_exitance.comp`): the exitance shading draws for the channels
//! the planner computes locally, `M = R_d,total E_t`, evaluated at every vertex of one object.
//! It is not part of a frame: `Renderer::exitance_drawn` records it on demand, so that exported
//! exitance is what the image shows, local channels included.
//!
//! Reads vertices, objects, lights, the shadow maps and the environment's per-vertex cache;
//! writes the local exitance (vec4 per vertex), bound in that order (`BINDINGS`). Push:
//! `LocalExitancePush`.

use super::graph::{Resource, Resources, Use, compute_uses};
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `LocalExitancePush` in glsl/local_exitance.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct LocalExitancePush {
    /// The object's first vertex in the shared buffers.
    pub first_vertex: u32,
    /// Its vertex count; invocations beyond it return.
    pub vertex_count: u32,
    /// The object's index (its `ObjectRecord`).
    pub object: u32,
    /// Key lights, first in the light buffer; the environment arrives through its cache.
    pub key_light_count: u32,
    /// The shadow filter shading uses: 0, one bilinear tap; 1, the four-tap tent.
    pub shadow_radius: i32,
}

/// glsl/local_exitance.comp's bindings, in binding order.
const BINDINGS: [Resource; 6] = [
    Resource::Vertices,
    Resource::Objects,
    Resource::Lights,
    Resource::ShadowMaps,
    Resource::EnvironmentIrradiance,
    Resource::LocalExitance,
];

/// One dispatch of glsl/local_exitance.comp for object `object` when it is translucent with a
/// local channel (`GpuScene::local_channels`), writing `GpuScene::local_exitance` at its
/// vertices.
pub struct LocalExitancePass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    key_light_count: u32,
    object: usize,
}

impl LocalExitancePass {
    /// The pipeline and one descriptor set over `BINDINGS`, for object `object`.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources, object: usize) -> GpuResult<LocalExitancePass> {
        let pipeline = ComputePipeline::new(gpu, "local_exitance.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(LocalExitancePass { pipeline, set, key_light_count: resources.scene.key_light_count, object })
    }
}

impl RenderPass for LocalExitancePass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&BINDINGS, &[Resource::LocalExitance])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let r = frame.scene.object_range(self.object);
        // The channels the last recorded frame computed locally.
        if r.eta == 0.0 || frame.scene.local_channels(self.object) == 0 {
            return;
        }
        let push = LocalExitancePush {
            first_vertex: r.first_vertex,
            vertex_count: r.vertex_count,
            object: self.object as u32,
            key_light_count: self.key_light_count,
            shadow_radius: i32::from(!frame.plan.one_tap_shadows),
        };
        self.pipeline.dispatch(cmd, &self.set, &push, [r.vertex_count, 1, 1]);
    }
}
