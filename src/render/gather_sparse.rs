//! Sparse-gather pass (`glsl/gather_sparse.comp`), for `render.gather = "sparse"`: the dipole sum
//! only at the sample points, then blended to every vertex with the near-field Shepard weights.
//! Far cheaper than the vertex gather (one weight per sample-vertex pair instead of the kernel's
//! exponentials); the cost is detail finer than the sample spacing in the far field, which the
//! far kernel smooths at that scale anyway. `tests/render.rs` measures the difference.
//!
//! Bindings: 0 = vertices, 1 = samples, 2 = splat, 3 = objects, 4 = sample exitance,
//! 5 = exitance. Push: object index, stage (0: at samples, 1: blend to vertices).

use crate::gpu::{
    Binding, BindingKind, Buffer, BufferDesc, ComputePipeline, DescriptorSet, Gpu, GpuResult, memory_barrier,
};
use ash::vk;
use std::sync::Arc;

pub struct GatherSparsePass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _sample_exitance: Buffer,
    /// (object index, vertex count, sample count) of every translucent object.
    receivers: Vec<(u32, u32, u32)>,
}

impl GatherSparsePass {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        gpu: &Arc<Gpu>,
        vertices: &Buffer,
        samples: &Buffer,
        sample_count: u32,
        splat: &Buffer,
        objects: &Buffer,
        exitance: &Buffer,
        receivers: Vec<(u32, u32, u32)>,
    ) -> GpuResult<GatherSparsePass> {
        let s = BindingKind::StorageBuffer;
        let pipeline = ComputePipeline::new(gpu, "gather_sparse.comp", &[s, s, s, s, s, s], 8)?;
        let sample_exitance = Buffer::new(
            gpu,
            &BufferDesc::gpu_only(
                "sample exitance",
                16 * sample_count.max(1) as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            ),
        )?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(vertices),
            Binding::Buffer(samples),
            Binding::Buffer(splat),
            Binding::Buffer(objects),
            Binding::Buffer(&sample_exitance),
            Binding::Buffer(exitance),
        ])?;
        Ok(GatherSparsePass { pipeline, set, _sample_exitance: sample_exitance, receivers })
    }

    pub fn record(&self, gpu: &Gpu, cmd: vk::CommandBuffer) {
        for stage in [0u32, 1] {
            for &(object, vertex_count, sample_count) in &self.receivers {
                let count = if stage == 0 { sample_count } else { vertex_count };
                if count > 0 {
                    let push = [object, stage];
                    self.pipeline.dispatch(cmd, &self.set, bytemuck::bytes_of(&push), [count.div_ceil(64), 1, 1]);
                }
            }
            if stage == 0 {
                // Stage 1 reads what stage 0 wrote.
                memory_barrier(
                    gpu.device(),
                    cmd,
                    (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_WRITE),
                    (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_STORAGE_READ),
                );
            }
        }
    }
}
