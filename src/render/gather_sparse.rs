//! Sparse-gather pass (`glsl/gather_sparse.comp`), for `render.gather = "sparse"`: the dipole sum
//! only at the sample points, then blended to every vertex with the near-field Shepard weights.
//! Far cheaper than the vertex gather (one weight per sample-vertex pair instead of the kernel's
//! exponentials); the cost is detail finer than the sample spacing in the far field, which the
//! far kernel smooths at that scale anyway. `tests/render.rs` measures the difference.
//!
//! Stage 0 writes exitance at the samples of each object the plan gathers into a buffer this
//! pass owns; stage 1 visits, per group of 8 vertices (`sampling::ReceiverGroups`), only the
//! samples whose blend radius reaches the group (`GpuScene::blend_items`), not every sample.
//! The two stages' shape is `group_gather`'s.
//!
//! Bindings: `BINDINGS`, in binding order. Push: `GatherSparsePush`.

use super::graph::{Resource, Resources, Use, compute_uses};
use super::group_gather::{GroupGather, Stage0};
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{Binding, Buffer, BufferDesc, ComputePipeline, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `GatherSparsePush` in glsl/gather_sparse.comp: the two-stage gathers' push block
/// (0: exitance at the samples; 1: blended to the vertices).
pub use super::group_gather::GroupGatherPush as GatherSparsePush;

/// glsl/gather_sparse.comp's bindings, in binding order.
const BINDINGS: [Resource; 12] = [
    Resource::Vertices,
    Resource::Samples,
    Resource::Splat,
    Resource::Objects,
    Resource::SampleExitance,
    Resource::Exitance,
    Resource::TreeNodes,
    Resource::TreeOrder,
    Resource::ReceiverOrder,
    Resource::ReceiverGroups,
    Resource::BlendItems,
    Resource::VertexBoundary,
];

/// The sparse gather: two dispatches of glsl/gather_sparse.comp per translucent object the plan
/// gathers, writing exitance at its vertices into `GpuScene::exitance`.
pub struct GatherSparsePass {
    stages: GroupGather,
    _sample_exitance: Buffer,
}

impl GatherSparsePass {
    /// The pipeline, the per-sample exitance buffer (one vec4 per sample, device-local) and one
    /// descriptor set over `BINDINGS`.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<GatherSparsePass> {
        let pipeline = ComputePipeline::new(gpu, "gather_sparse.comp")?;
        let bytes = 16 * resources.scene.sample_count.max(1) as u64;
        let sample_exitance =
            Buffer::new(gpu, &BufferDesc::gpu_only("sample exitance", bytes, vk::BufferUsageFlags::STORAGE_BUFFER))?;
        let mut bindings = resources.bind_all(&BINDINGS[..4])?;
        bindings.push(Resource::SampleExitance.bind(Binding::Buffer(&sample_exitance)));
        bindings.extend(resources.bind_all(&BINDINGS[5..])?);
        let set = pipeline.descriptor_set(&bindings)?;
        let stages = GroupGather::new(pipeline, set, Resource::SampleExitance, Stage0::Threads(|r| r.sample_count));
        Ok(GatherSparsePass { stages, _sample_exitance: sample_exitance })
    }
}

impl RenderPass for GatherSparsePass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&BINDINGS, &[Resource::SampleExitance, Resource::Exitance])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        self.stages.record(cmd, frame);
    }
}
