//! Pixel-gather pass (`glsl/gather_pixel.comp`), for `render.gather = "pixel"`: the dipole sum
//! (`glsl/common/gather.glsl`, as in the vertex gather) at every pixel that shows a translucent
//! object, added in place to the HDR image with the outgoing factor the shading pass left in its
//! alpha. Exact at each visible point and only where the surface is seen; it must rerun whenever
//! the view changes.
//!
//! Bindings: 0 = surface (sampled), 1 = samples, 2 = splat, 3 = objects, 4 = HDR (storage image).
//! Push: `GatherPixelPush`.

use super::gpu_scene::GpuScene;
use super::pass::{FrameInputs, RenderPass};
use crate::gpu::{Access, Binding, ComputePipeline, DescriptorSet, Gpu, GpuResult, Image, ImageBarrier, Sampler};
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

/// The pixel gather: one dispatch of glsl/gather_pixel.comp over the HDR image, reading the shading
/// pass's surface image and adding exitance into the HDR image in place (moved to GENERAL for the
/// dispatch and back to sampled reads after). It owns the nearest sampler it reads the surface
/// with; both images belong to the `ShadePass`, which must outlive it.
pub struct GatherPixelPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _sampler: Sampler,
    hdr: vk::Image,
    push: GatherPixelPush,
}

impl GatherPixelPass {
    /// `surface` and `hdr` are the shading pass's images, which it leaves readable by compute.
    pub fn new(gpu: &Arc<Gpu>, scene: &GpuScene, surface: &Image, hdr: &Image) -> GpuResult<GatherPixelPass> {
        let pipeline = ComputePipeline::new(gpu, "gather_pixel.comp")?;
        let sampler = Sampler::new(gpu, vk::Filter::NEAREST)?;
        let set = pipeline.descriptor_set(&[
            Binding::Image {
                view: surface.view(),
                layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                sampler: sampler.raw(),
            },
            Binding::Buffer(&scene.samples),
            Binding::Buffer(&scene.splat),
            Binding::Buffer(&scene.objects),
            Binding::Image { view: hdr.view(), layout: vk::ImageLayout::GENERAL, sampler: vk::Sampler::null() },
        ])?;
        let extent = hdr.extent();
        let push = GatherPixelPush { width: extent.width, height: extent.height };
        Ok(GatherPixelPass { pipeline, set, _sampler: sampler, hdr: hdr.raw(), push })
    }
}

impl RenderPass for GatherPixelPass {
    /// HDR to GENERAL, the gather adding in place, HDR back to sampled reads for the tone map.
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        let device = frame.gpu.device();
        let (sampled, storage) = ([Access::ComputeSampledRead], [Access::ComputeImageReadWrite]);
        let color = vk::ImageAspectFlags::COLOR;
        ImageBarrier::new(self.hdr, color, &sampled, &storage).record(device, cmd);
        self.pipeline.dispatch(cmd, &self.set, &self.push, [self.push.width, self.push.height, 1]);
        ImageBarrier::new(self.hdr, color, &storage, &sampled).record(device, cmd);
    }
}
