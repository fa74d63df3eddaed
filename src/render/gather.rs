//! Dipole-gather pass (`glsl/gather.comp`): radiant exitance at every vertex of each translucent
//! object, the discrete dipole sum of seed Eq. 11 with the energy-conserving near-field kernel
//! (`optics::kernel`), samples staged through shared memory, Kahan-compensated f32 sums.
//!
//! Bindings: 0 = vertices, 1 = samples, 2 = splat, 3 = objects, 4 = exitance. Push: object index.
//! One dispatch per translucent object, over its vertex range.

use crate::gpu::{Binding, BindingKind, Buffer, ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

pub struct GatherPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    /// (object index, vertex count) of every translucent object.
    receivers: Vec<(u32, u32)>,
}

impl GatherPass {
    pub fn new(
        gpu: &Arc<Gpu>,
        vertices: &Buffer,
        samples: &Buffer,
        splat: &Buffer,
        objects: &Buffer,
        exitance: &Buffer,
        receivers: Vec<(u32, u32)>,
    ) -> GpuResult<GatherPass> {
        let s = BindingKind::StorageBuffer;
        let pipeline = ComputePipeline::new(gpu, "gather.comp", &[s, s, s, s, s], 4)?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(vertices),
            Binding::Buffer(samples),
            Binding::Buffer(splat),
            Binding::Buffer(objects),
            Binding::Buffer(exitance),
        ])?;
        Ok(GatherPass { pipeline, set, receivers })
    }

    pub fn record(&self, cmd: vk::CommandBuffer) {
        for &(object, vertex_count) in &self.receivers {
            if vertex_count > 0 {
                self.pipeline.dispatch(cmd, &self.set, bytemuck::bytes_of(&object), [vertex_count.div_ceil(64), 1, 1]);
            }
        }
    }
}
