//! Irradiance-splat pass (`glsl/splat.comp`): for every sample point, the irradiance
//! transmitted into the medium from every light (Fresnel transmission, cosine, shadow-map
//! visibility) and its area; together the flux `E_i A_i` each sample injects. Also each sample's
//! near-field energy per channel, which the gather's kernel needs once per sample.
//!
//! Bindings: 0 = samples, 1 = objects, 2 = lights, 3 = shadow maps, 4 = splat output
//! (2 x vec4 per sample). Push: sample count, light count.

use super::shadow::ShadowPass;
use crate::gpu::{Binding, BindingKind, Buffer, ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

pub struct SplatPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    sample_count: u32,
    light_count: u32,
}

/// Bytes of splat output per sample: vec4 (E rgb, area) + vec4 (near energy rgb, 0).
pub const SPLAT_STRIDE: u64 = 32;

impl SplatPass {
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        gpu: &Arc<Gpu>,
        samples: &Buffer,
        sample_count: u32,
        objects: &Buffer,
        lights: &Buffer,
        light_count: u32,
        shadow: &ShadowPass,
        output: &Buffer,
    ) -> GpuResult<SplatPass> {
        let s = BindingKind::StorageBuffer;
        let pipeline = ComputePipeline::new(gpu, "splat.comp", &[s, s, s, BindingKind::CombinedImageSampler, s], 8)?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(samples),
            Binding::Buffer(objects),
            Binding::Buffer(lights),
            shadow.binding(),
            Binding::Buffer(output),
        ])?;
        Ok(SplatPass { pipeline, set, sample_count, light_count })
    }

    pub fn record(&self, cmd: vk::CommandBuffer) {
        if self.sample_count == 0 {
            return;
        }
        let push = [self.sample_count, self.light_count];
        self.pipeline.dispatch(cmd, &self.set, bytemuck::bytes_of(&push), [self.sample_count.div_ceil(64), 1, 1]);
    }
}
