//! Irradiance-splat pass (`glsl/splat.comp`): for every sample point, the irradiance
//! transmitted into the medium from every light (Fresnel transmission, cosine, shadow-map
//! visibility) and its area; together the flux `E_i A_i` each sample injects. Also each sample's
//! near-field energy per channel, which the gather's kernel needs once per sample.
//!
//! Bindings: 0 = samples, 1 = objects, 2 = lights, 3 = shadow maps, 4 = splat output
//! (`SplatRecord` per sample). Push: `SplatPush`.

use super::gpu_scene::GpuScene;
use super::pass::{FrameInputs, RenderPass};
use super::shadow::ShadowPass;
use crate::gpu::{Access, Binding, ComputePipeline, DescriptorSet, Gpu, GpuResult, memory_barrier};
use ash::vk;
use std::sync::Arc;

/// `SplatPush` in glsl/splat.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SplatPush {
    /// The object's first sample in the shared buffers.
    pub first_sample: u32,
    /// Its sample count; invocations beyond it return.
    pub sample_count: u32,
    /// Lights in the light buffer; each adds its transmitted irradiance at every sample.
    pub light_count: u32,
}

/// The irradiance splat: one dispatch of glsl/splat.comp per object the plan splats, writing
/// `SplatRecord`s into `GpuScene::splat`, then a barrier to compute reads (the gathers).
pub struct SplatPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    light_count: u32,
}

impl SplatPass {
    /// The pipeline and one descriptor set over the samples, objects, lights, shadow maps and splat
    /// buffer.
    pub fn new(gpu: &Arc<Gpu>, scene: &GpuScene, shadow: &ShadowPass) -> GpuResult<SplatPass> {
        let pipeline = ComputePipeline::new(gpu, "splat.comp")?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(&scene.samples),
            Binding::Buffer(&scene.objects),
            Binding::Buffer(&scene.lights),
            shadow.binding(),
            Binding::Buffer(&scene.splat),
        ])?;
        Ok(SplatPass { pipeline, set, light_count: scene.light_count })
    }
}

impl RenderPass for SplatPass {
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        // One dispatch per object the plan splats: the others keep their last irradiance.
        for (i, r) in frame.scene.object_ranges().enumerate() {
            if r.sample_count == 0 || !frame.plan.splats(i) {
                continue;
            }
            let push =
                SplatPush { first_sample: r.first_sample, sample_count: r.sample_count, light_count: self.light_count };
            self.pipeline.dispatch(cmd, &self.set, &push, [r.sample_count, 1, 1]);
        }
        memory_barrier(frame.gpu.device(), cmd, &[Access::ComputeWrite], &[Access::ComputeRead]);
    }
}
