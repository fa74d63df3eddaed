//! Vertex-light pass (`glsl/vertex_light.comp`): irradiance from the environment light's
//! directions at every mesh vertex, with shadow-map visibility, cached across frames. The
//! shading pass interpolates it for diffuse surfaces, so a pixel looks up only the shadow maps
//! of the other (key) lights; the cache is recomputed only when the environment changes.
//!
//! Reads vertices, lights and the shadow maps; writes the environment irradiance (vec4 per
//! vertex), bound in that order (`BINDINGS`). Push: `VertexLightPush`.

use super::graph::{Resource, Resources, Use, compute_uses};
use super::error::RenderError;
use super::pass::{FrameInputs, PassContext, Rebuild, RegisteredPass, RenderPass};
use crate::gpu::{ComputePipeline, DescriptorSet, Gpu, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `VertexLightPush` in glsl/vertex_light.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct VertexLightPush {
    /// The object's first vertex in the shared buffers.
    pub first_vertex: u32,
    /// Its vertex count; invocations beyond it return.
    pub vertex_count: u32,
    /// Lights in the light buffer; the shader adds only the environment's directions.
    pub light_count: u32,
    /// A translucent object's index of refraction (its irradiance is weighed by `F_t`, what the
    /// local exitance needs); 0 for an opaque one.
    pub eta: f32,
}

/// glsl/vertex_light.comp's bindings, in binding order.
const BINDINGS: [Resource; 4] =
    [Resource::Vertices, Resource::Lights, Resource::ShadowMaps, Resource::EnvironmentIrradiance];

/// The environment cache: one dispatch of glsl/vertex_light.comp per object, writing
/// `GpuScene::environment_irradiance`.
pub struct VertexLightPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    light_count: u32,
}

impl VertexLightPass {
    /// The pipeline and one descriptor set over `BINDINGS`.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<VertexLightPass> {
        let pipeline = ComputePipeline::new(gpu, "vertex_light.comp")?;
        let set = pipeline.descriptor_set(&resources.bind_all(&BINDINGS)?)?;
        Ok(VertexLightPass { pipeline, set, light_count: resources.scene.light_count })
    }
}

impl RenderPass for VertexLightPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        compute_uses(&BINDINGS, &[Resource::EnvironmentIrradiance])
    }

    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        for r in frame.scene.object_ranges() {
            let push = VertexLightPush {
                first_vertex: r.first_vertex,
                vertex_count: r.vertex_count,
                light_count: self.light_count,
                eta: r.eta,
            };
            self.pipeline.dispatch(cmd, &self.set, &push, [r.vertex_count, 1, 1]);
        }
    }
}

impl RegisteredPass for VertexLightPass {
    const REBUILT_ON: &'static [Rebuild] = &[Rebuild::SceneData];

    fn build(context: &PassContext) -> Result<Option<Self>, RenderError> {
        Ok(Some(VertexLightPass::new(context.gpu, &context.resources)?))
    }
}
