//! Vertex-light pass (`glsl/vertex_light.comp`): irradiance from the environment light's
//! directions at every mesh vertex, with shadow-map visibility, cached across frames. The
//! shading pass interpolates it for diffuse surfaces, so a pixel looks up only the shadow maps
//! of the other (key) lights; the cache is recomputed only when the environment changes.
//!
//! Bindings: 0 = vertices, 1 = lights, 2 = shadow maps, 3 = output (vec4 per vertex).
//! Push: vertex count, light count.

use super::shadow::ShadowPass;
use crate::gpu::{Binding, BindingKind, Buffer, ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

pub struct VertexLightPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    vertex_count: u32,
    light_count: u32,
}

impl VertexLightPass {
    pub fn new(
        gpu: &Arc<Gpu>,
        vertices: &Buffer,
        vertex_count: u32,
        lights: &Buffer,
        light_count: u32,
        shadow: &ShadowPass,
        output: &Buffer,
    ) -> GpuResult<VertexLightPass> {
        let s = BindingKind::StorageBuffer;
        let pipeline =
            ComputePipeline::new(gpu, "vertex_light.comp", &[s, s, BindingKind::CombinedImageSampler, s], 8)?;
        let set = pipeline.descriptor_set(&[
            Binding::Buffer(vertices),
            Binding::Buffer(lights),
            shadow.binding(),
            Binding::Buffer(output),
        ])?;
        Ok(VertexLightPass { pipeline, set, vertex_count, light_count })
    }

    pub fn record(&self, cmd: vk::CommandBuffer) {
        let push = [self.vertex_count, self.light_count];
        self.pipeline.dispatch(cmd, &self.set, bytemuck::bytes_of(&push), [self.vertex_count.div_ceil(64), 1, 1]);
    }
}
