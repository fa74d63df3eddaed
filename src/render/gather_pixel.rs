//! Pixel-gather pass (`glsl/gather_pixel.comp`), for `render.gather = "pixel"`: the dipole sum
//! (`glsl/common/gather.glsl`, as in the vertex gather) at every pixel that shows a translucent
//! object, added in place to the HDR image with the outgoing factor the shading pass left in its
//! alpha. Exact at each visible point and only where the surface is seen; it must rerun whenever
//! the view changes.
//!
//! Bindings: `BINDINGS`, in binding order (the HDR image as a storage image). Push:
//! `GatherPixelPush`.

use super::graph::{Resource, Resources, Use, read, write};
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{Access, ComputePipeline, DescriptorSet, Gpu, GpuError, GpuResult};
use ash::vk;
use std::sync::Arc;

/// `GatherPixelPush` in glsl/gather_pixel.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GatherPixelPush {
    /// HDR image width in pixels; invocations outside the image return.
    pub width: u32,
    /// HDR image height in pixels.
    pub height: u32,
}

/// glsl/gather_pixel.comp's bindings, in binding order.
const BINDINGS: [Resource; 5] =
    [Resource::Surface, Resource::Samples, Resource::Splat, Resource::Objects, Resource::Hdr];

/// The pixel gather: one dispatch of glsl/gather_pixel.comp over the HDR image, reading the
/// surface image the shading pass drew and adding exitance into the HDR image in place (a
/// storage image, GENERAL, for the dispatch). Both images are frame targets
/// (`FrameTargets::camera`), which must outlive it.
pub struct GatherPixelPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    push: GatherPixelPush,
}

impl GatherPixelPass {
    /// The pipeline and one descriptor set over `BINDINGS`; the frame targets must have the
    /// camera's HDR and surface images.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<GatherPixelPass> {
        let pipeline = ComputePipeline::new(gpu, "gather_pixel.comp")?;
        let missing = || GpuError::MissingImages { pass: "pixel gather", images: "HDR and surface images" };
        let hdr = resources.targets.hdr().ok_or_else(missing)?;
        let mut bindings = resources.bind_all(&BINDINGS[..4])?;
        bindings.push(Resource::Hdr.bind(resources.targets.storage_hdr().ok_or_else(missing)?));
        let set = pipeline.descriptor_set(&bindings)?;
        let extent = hdr.extent();
        let push = GatherPixelPush { width: extent.width, height: extent.height };
        Ok(GatherPixelPass { pipeline, set, push })
    }
}

impl RenderPass for GatherPixelPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        vec![
            read(Resource::Surface, Access::ComputeSampledRead),
            read(Resource::Samples, Access::ComputeRead),
            read(Resource::Splat, Access::ComputeRead),
            read(Resource::Objects, Access::ComputeRead),
            write(Resource::Hdr, Access::ComputeImageReadWrite),
        ]
    }

    /// The gather adding into the HDR image in place.
    fn record(&self, cmd: vk::CommandBuffer, _: &FrameInputs) {
        self.pipeline.dispatch(cmd, &self.set, &self.push, [self.push.width, self.push.height, 1]);
    }
}
