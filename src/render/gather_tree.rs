//! Hierarchical-gather pass (`glsl/gather_tree.comp`), for `render.gather = "hierarchical"`:
//! the vertex gather's dipole sum with far clusters of samples standing in for their members
//! (after Jensen and Buhler 2002). Per translucent object, stage 0 aggregates each node of its
//! sample hierarchy (`sampling::SampleTree`) from this frame's splat, a compute-to-compute
//! barrier, then stage 1 sums, for every vertex, the list of samples and nodes that
//! `sampling::SampleTree::cut` chose for its group of 64 (built once in `GpuScene::new`).
//! `render.gather_epsilon` is the accuracy knob: the solid-angle bound below which a node is used
//! whole; 0 is the flat sum. `reference::tree::gather` is its f64 twin.
//!
//! Bindings: 0 = vertices, 1 = samples, 2 = splat, 3 = objects, 4 = tree nodes, 5 = tree order,
//! 6 = node power, 7 = receiver order, 8 = receiver groups, 9 = group items, 10 = exitance, 11 = boundary distances.
//! Push: `GatherTreePush`.

use super::gather::exitance_written;
use super::gpu_scene::{GpuScene, Receiver};
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{Access, Binding, ComputePipeline, DescriptorSet, Gpu, GpuResult, memory_barrier};
use ash::vk;
use std::sync::Arc;

/// `GatherTreePush` in glsl/gather_tree.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherTreePush {
    /// Index of the receiving translucent object (its `ObjectRecord`).
    pub object: u32,
    /// 0: aggregate the nodes; 1: gather at the vertices.
    pub stage: u32,
    /// The object's root in `GpuScene::tree_nodes`.
    pub first_node: u32,
    /// Its node count.
    pub node_count: u32,
    /// Its first entry in `GpuScene::receiver_order`.
    pub first_receiver: u32,
    /// Its first group in `GpuScene::receiver_groups`.
    pub first_group: u32,
}

impl GatherTreePush {
    /// The push block for `stage` of a dispatch over `receiver`.
    pub fn new(receiver: &Receiver, stage: u32) -> GatherTreePush {
        GatherTreePush {
            object: receiver.object,
            stage,
            first_node: receiver.first_node,
            node_count: receiver.node_count,
            first_receiver: receiver.first_receiver,
            first_group: receiver.first_group,
        }
    }
}

/// The hierarchical gather: two dispatches of glsl/gather_tree.comp per translucent object,
/// writing exitance at its vertices into `GpuScene::exitance`, then the vertex gather's barrier.
pub struct GatherTreePass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
}

impl GatherTreePass {
    /// The pipeline and one descriptor set over the scene's buffers (whose group items
    /// `GpuScene::new` built for the scene's `render.gather_epsilon`).
    pub fn new(gpu: &Arc<Gpu>, scene: &GpuScene) -> GpuResult<GatherTreePass> {
        let pipeline = ComputePipeline::new(gpu, "gather_tree.comp")?;
        assert_group_size(&pipeline);
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(&scene.vertices),
            Binding::Buffer(&scene.samples),
            Binding::Buffer(&scene.splat),
            Binding::Buffer(&scene.objects),
            Binding::Buffer(&scene.tree_nodes),
            Binding::Buffer(&scene.tree_order),
            Binding::Buffer(&scene.node_power),
            Binding::Buffer(&scene.receiver_order),
            Binding::Buffer(&scene.receiver_groups),
            Binding::Buffer(&scene.group_items),
            Binding::Buffer(&scene.exitance),
            Binding::Buffer(&scene.vertex_boundary),
        ])?;
        Ok(GatherTreePass { pipeline, set })
    }
}

impl RenderPass for GatherTreePass {
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let push = GatherTreePush::new;
        for r in frame.scene.receivers.iter().filter(|r| frame.plan.gathers(r.object as usize)) {
            self.pipeline.dispatch(cmd, &self.set, &push(r, 0), [r.node_count, 1, 1]);
        }
        // Stage 1 reads the node power stage 0 wrote.
        memory_barrier(frame.gpu.device(), cmd, &[Access::ComputeWrite], &[Access::ComputeRead]);
        for r in &frame.scene.receivers {
            self.pipeline.dispatch(cmd, &self.set, &push(r, 1), [r.vertex_count, 1, 1]);
        }
        exitance_written(frame, cmd);
    }
}

/// A gather whose workgroups are receiver groups (`sampling::ReceiverGroups`) must have their
/// size as its local size.
pub(super) fn assert_group_size(pipeline: &ComputePipeline) {
    let n = crate::sampling::RECEIVER_GROUP_SIZE as u32;
    assert!(
        pipeline.groups([n, 1, 1]) == [1, 1, 1] && pipeline.groups([n + 1, 1, 1]) == [2, 1, 1],
        "{}: local size is not RECEIVER_GROUP_SIZE",
        pipeline.name()
    );
}
