//! Sparse-gather pass (`glsl/gather_sparse.comp`), for `render.gather = "sparse"`: the dipole sum
//! only at the sample points, then blended to every vertex with the near-field Shepard weights.
//! Far cheaper than the vertex gather (one weight per sample-vertex pair instead of the kernel's
//! exponentials); the cost is detail finer than the sample spacing in the far field, which the
//! far kernel smooths at that scale anyway. `tests/render.rs` measures the difference.
//!
//! Stage 1 visits, per group of 32 vertices (`sampling::ReceiverGroups`), only the samples whose
//! blend radius reaches the group (`GpuScene::blend_items`), not every sample.
//!
//! Bindings: 0 = vertices, 1 = samples, 2 = splat, 3 = objects, 4 = sample exitance,
//! 5 = exitance, 6 = tree nodes, 7 = tree order, 8 = receiver order, 9 = receiver groups,
//! 10 = blend items, 11 = boundary distances. Push: `GatherSparsePush`.

use super::gather::exitance_written;
use super::gpu_scene::GpuScene;
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{Access, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorSet, Gpu, GpuResult, memory_barrier};
use ash::vk;
use std::sync::Arc;

// `GatherSparsePush` in glsl/gather_sparse.comp has the hierarchical gather's fields (stage 0:
// exitance at the samples, 1: blended to the vertices; the nearest-sample fallback walks the
// hierarchy), so one Rust type serves both.
pub use super::gather_tree::GatherTreePush as GatherSparsePush;

/// The sparse gather: per translucent object, stage 0 of glsl/gather_sparse.comp over its samples
/// (exitance into a per-sample buffer this pass owns), a compute-to-compute barrier, then stage 1
/// over its vertices into `GpuScene::exitance`; it ends with the vertex gather's barrier.
pub struct GatherSparsePass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _sample_exitance: Buffer,
}

impl GatherSparsePass {
    /// The pipeline, the per-sample exitance buffer (one vec4 per sample, device-local) and one
    /// descriptor set over it and the scene's buffers.
    pub fn new(gpu: &Arc<Gpu>, scene: &GpuScene) -> GpuResult<GatherSparsePass> {
        let pipeline = ComputePipeline::new(gpu, "gather_sparse.comp")?;
        super::gather_tree::assert_group_size(&pipeline);
        let bytes = 16 * scene.sample_count.max(1) as u64;
        let sample_exitance =
            Buffer::new(gpu, &BufferDesc::gpu_only("sample exitance", bytes, vk::BufferUsageFlags::STORAGE_BUFFER))?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(&scene.vertices),
            Binding::Buffer(&scene.samples),
            Binding::Buffer(&scene.splat),
            Binding::Buffer(&scene.objects),
            Binding::Buffer(&sample_exitance),
            Binding::Buffer(&scene.exitance),
            Binding::Buffer(&scene.tree_nodes),
            Binding::Buffer(&scene.tree_order),
            Binding::Buffer(&scene.receiver_order),
            Binding::Buffer(&scene.receiver_groups),
            Binding::Buffer(&scene.blend_items),
            Binding::Buffer(&scene.vertex_boundary),
        ])?;
        Ok(GatherSparsePass { pipeline, set, _sample_exitance: sample_exitance })
    }
}

impl RenderPass for GatherSparsePass {
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let push = GatherSparsePush::new;
        for r in frame.scene.receivers.iter().filter(|r| frame.plan.gathers(r.object as usize)) {
            self.pipeline.dispatch(cmd, &self.set, &push(r, 0), [r.sample_count, 1, 1]);
        }
        // Stage 1 reads what stage 0 wrote.
        memory_barrier(frame.gpu.device(), cmd, &[Access::ComputeWrite], &[Access::ComputeRead]);
        // Only where stage 0 ran: an object the plan computes wholly locally has no sample
        // exitance this frame, and blending it would spread whatever the buffer held.
        for r in frame.scene.receivers.iter().filter(|r| frame.plan.gathers(r.object as usize)) {
            self.pipeline.dispatch(cmd, &self.set, &push(r, 1), [r.vertex_count, 1, 1]);
        }
        exitance_written(frame, cmd);
    }
}
