//! Dipole-gather pass (`glsl/gather.comp`): radiant exitance at every vertex of each translucent
//! object, the discrete dipole sum of seed Eq. 11 with the energy-conserving near-field kernel
//! (`optics::kernel`), samples staged through shared memory, Kahan-compensated f32 sums.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `GatherPush`.
//! One dispatch per translucent object, over the vertices of its level of detail this frame.

use super::graph::{Resource, Resources, Use, compute_uses};
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `GatherPush` in glsl/gather.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherPush {
    /// Index of the receiving translucent object (its `ObjectRecord`); the dispatch covers its
    /// vertex range.
    pub object: u32,
    /// Its root in `GpuScene::tree_nodes` (the nearest-sample fallback walks the hierarchy).
    pub first_node: u32,
    /// Its node count.
    pub node_count: u32,
    /// First entry of its level of detail's vertex list in `GpuScene::level_vertices`.
    pub first_entry: u32,
    /// Vertices in that list: the receivers of the dispatch.
    pub receiver_count: u32,
}

/// glsl/gather.comp's bindings, in binding order.
const BINDINGS: [Resource; 9] = [
    Resource::Vertices,
    Resource::Samples,
    Resource::Splat,
    Resource::Objects,
    Resource::Exitance,
    Resource::TreeNodes,
    Resource::TreeOrder,
    Resource::VertexBoundary,
    Resource::LevelVertices,
];

/// The vertex gather: one dispatch of glsl/gather.comp per translucent object the plan gathers
/// (`GpuScene::receivers`), writing exitance at the vertices of its level of detail into
/// `GpuScene::exitance`.
pub struct GatherPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
}

impl GatherPass {
    /// The pipeline and one descriptor set over `BINDINGS`.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<GatherPass> {
        let pipeline = ComputePipeline::new(gpu, "gather.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(GatherPass { pipeline, set })
    }
}

impl RenderPass for GatherPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&BINDINGS, &[Resource::Exitance])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        for r in frame.scene.receivers.iter().filter(|r| frame.plan.gathers(r.object as usize)) {
            let level = frame.scene.level(r.object as usize, frame.plan.level(r.object as usize));
            let push = GatherPush {
                object: r.object,
                first_node: r.first_node,
                node_count: r.node_count,
                first_entry: level.first_entry,
                receiver_count: level.vertex_count,
            };
            self.pipeline.dispatch(cmd, &self.set, &push, [level.vertex_count, 1, 1]);
        }
    }
}
