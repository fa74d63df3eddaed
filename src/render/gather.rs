//! Dipole-gather pass (`glsl/gather.comp`): radiant exitance at every vertex of each translucent
//! object, the discrete dipole sum of seed Eq. 11 with the energy-conserving near-field kernel
//! (`optics::kernel`), samples staged through shared memory, Kahan-compensated f32 sums.
//!
//! Bindings: 0 = vertices, 1 = samples, 2 = splat, 3 = objects, 4 = exitance, 5 = tree nodes,
//! 6 = tree order, 7 = boundary distances, 8 = level vertices. Push: `GatherPush`.
//! One dispatch per translucent object, over the vertices of its level of detail this frame.

use super::gpu_scene::GpuScene;
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{Access, Binding, ComputePipeline, DescriptorSet, Gpu, GpuResult, memory_barrier};
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

/// The vertex gather: one dispatch of glsl/gather.comp per translucent object
/// (`GpuScene::receivers`), writing exitance at its vertices into `GpuScene::exitance`, then a
/// barrier to vertex-attribute reads by shading and to host reads.
pub struct GatherPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
}

impl GatherPass {
    /// The pipeline and one descriptor set over the scene's vertices, samples, splat, objects and
    /// exitance buffers.
    pub fn new(gpu: &Arc<Gpu>, scene: &GpuScene) -> GpuResult<GatherPass> {
        let pipeline = ComputePipeline::new(gpu, "gather.comp")?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(&scene.vertices),
            Binding::Buffer(&scene.samples),
            Binding::Buffer(&scene.splat),
            Binding::Buffer(&scene.objects),
            Binding::Buffer(&scene.exitance),
            Binding::Buffer(&scene.tree_nodes),
            Binding::Buffer(&scene.tree_order),
            Binding::Buffer(&scene.vertex_boundary),
            Binding::Buffer(&scene.level_vertices),
        ])?;
        Ok(GatherPass { pipeline, set })
    }
}

impl RenderPass for GatherPass {
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
        exitance_written(frame, cmd);
    }
}

/// After a gather into the per-vertex exitance buffer: shading reads it as a vertex attribute,
/// the host may read it back.
pub(super) fn exitance_written(frame: &FrameInputs, cmd: vk::CommandBuffer) {
    let next = [Access::VertexAttributeRead, Access::HostRead];
    memory_barrier(frame.gpu.device(), cmd, &[Access::ComputeWrite], &next);
}
