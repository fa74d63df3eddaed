//! Irradiance-splat pass (`glsl/splat.comp`): for every sample point, the irradiance
//! transmitted into the medium from every light (Fresnel transmission, cosine, and visibility
//! from a shadow ray into the casters' hierarchy or from the light's shadow map,
//! `SplatVisibility`) and its area; together the flux `E_i A_i` each sample injects. Also each sample's
//! near-field energy per channel, which the gather's kernel needs once per sample.
//!
//! The environment's directions' part is kept per sample (`GpuScene::splat_environment`): when
//! the plan says only key lights changed for an object (`SplatLights::KeyLights`), the dispatch
//! reads it back and evaluates the key lights alone.
//!
//! Reads samples, objects, lights, the shadow maps and the casters' hierarchy; writes the splat output (`SplatRecord`
//! per sample) and the kept environment part, bound in that order (`BINDINGS`). Push:
//! `SplatPush`.

use super::graph::{Resource, Resources, Use, compute_uses};
use super::error::RenderError;
use super::pass::{FrameInputs, PassContext, Rebuild, RegisteredPass, RenderPass};
use super::plan::SplatLights;
use crate::gpu::{ComputePipeline, DescriptorSet, Gpu, GpuResult};
use crate::scene::SplatVisibility;
use ash::vk;
use std::sync::Arc;

/// `SplatPush` in glsl/splat.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SplatPush {
    /// The object's index (its `ObjectRecord`).
    pub object: u32,
    /// The object's first sample in the shared buffers.
    pub first_sample: u32,
    /// Its sample count; invocations beyond it return.
    pub sample_count: u32,
    /// Lights in the light buffer; each adds its transmitted irradiance at every sample.
    pub light_count: u32,
    /// The first `key_light_count` lights are key lights, the rest the environment's directions.
    pub key_light_count: u32,
    /// 1: the environment's part is read from `SplatEnvironment`; 0: computed and kept there.
    pub environment_kept: u32,
    /// Triangles in the casters' hierarchy (`GpuScene::caster_triangles`; 0: none casts).
    pub caster_triangles: u32,
    /// A shadow ray's start off the surface and least hit distance (`GpuScene::ray_offset`).
    pub ray_offset: f32,
}

/// glsl/splat.comp's bindings, in binding order.
const BINDINGS: [Resource; 8] = [
    Resource::Samples,
    Resource::Objects,
    Resource::Lights,
    Resource::ShadowMaps,
    Resource::Splat,
    Resource::SplatEnvironment,
    Resource::BvhNodes,
    Resource::BvhTriangles,
];

/// The irradiance splat: one dispatch of glsl/splat.comp per object the plan splats, writing
/// `SplatRecord`s into `GpuScene::splat`.
pub struct SplatPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    light_count: u32,
    key_light_count: u32,
    caster_triangles: u32,
    ray_offset: f32,
}

impl SplatPass {
    /// The pipeline for `visibility` and the scene's key-light count
    /// (`shade::unrolled_key_lights`), both specialization constants, so the other ways cost
    /// nothing, and one descriptor set over `BINDINGS`.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources, visibility: SplatVisibility) -> GpuResult<SplatPass> {
        let constant = match visibility {
            SplatVisibility::ShadowMaps => 0,
            SplatVisibility::Rays => 1,
            SplatVisibility::Hybrid => 2,
        };
        let keys = super::shade::unrolled_key_lights(resources.scene.key_light_count);
        let pipeline = ComputePipeline::specialized(gpu, "splat.comp", &[constant, keys])?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        let s = resources.scene;
        Ok(SplatPass {
            pipeline,
            set,
            light_count: s.light_count,
            key_light_count: s.key_light_count,
            caster_triangles: s.caster_triangles,
            ray_offset: s.ray_offset,
        })
    }
}

impl RenderPass for SplatPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        // The kept environment part counts as written even on frames that only read it: one
        // declaration, and a barrier the splat's own cost dwarfs.
        compute_uses(&BINDINGS, &[Resource::Splat, Resource::SplatEnvironment])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        // One dispatch per object the plan splats: the others keep their last irradiance.
        for (i, r) in frame.scene.object_ranges().enumerate() {
            if r.sample_count == 0 || !frame.plan.splats(i) {
                continue;
            }
            let push = SplatPush {
                object: i as u32,
                first_sample: r.first_sample,
                sample_count: r.sample_count,
                light_count: self.light_count,
                key_light_count: self.key_light_count,
                environment_kept: u32::from(frame.plan.splat_lights(i) == SplatLights::KeyLights),
                caster_triangles: self.caster_triangles,
                ray_offset: self.ray_offset,
            };
            self.pipeline.dispatch(cmd, &self.set, &push, [r.sample_count, 1, 1]);
        }
    }
}

impl RegisteredPass for SplatPass {
    const REBUILT_ON: &'static [Rebuild] = &[Rebuild::SceneData];

    fn build(context: &PassContext) -> Result<Option<Self>, RenderError> {
        let visibility = context.scene.scene.file.render.splat_visibility;
        Ok(Some(SplatPass::new(context.gpu, &context.resources, visibility)?))
    }
}
