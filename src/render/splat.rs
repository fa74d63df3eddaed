//! Irradiance-splat pass (`glsl/splat.comp`): for every sample point, the irradiance
//! transmitted into the medium from every light (Fresnel transmission, cosine, shadow-map
//! visibility) and its area; together the flux `E_i A_i` each sample injects. Also each sample's
//! near-field energy per channel, which the gather's kernel needs once per sample.
//!
//! Reads samples, objects, lights and the shadow maps; writes the splat output (`SplatRecord`
//! per sample), bound in that order (`BINDINGS`). Push: `SplatPush`.

use super::graph::{Resource, Resources, Use, compute_uses};
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{ComputePipeline, DescriptorSet, Gpu, GpuResult};
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

/// glsl/splat.comp's bindings, in binding order.
const BINDINGS: [Resource; 5] =
    [Resource::Samples, Resource::Objects, Resource::Lights, Resource::ShadowMaps, Resource::Splat];

/// The irradiance splat: one dispatch of glsl/splat.comp per object the plan splats, writing
/// `SplatRecord`s into `GpuScene::splat`.
pub struct SplatPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    light_count: u32,
}

impl SplatPass {
    /// The pipeline and one descriptor set over `BINDINGS`.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<SplatPass> {
        let pipeline = ComputePipeline::new(gpu, "splat.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(SplatPass { pipeline, set, light_count: resources.scene.light_count })
    }
}

impl RenderPass for SplatPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&BINDINGS, &[Resource::Splat])
    }

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
    }
}
