//! Pixel-gather pass (`glsl/gather_pixel.comp`), for `render.gather = "pixel"`: the dipole sum
//! (`glsl/common/gather.glsl`, as in the vertex gather) at every pixel that shows a translucent
//! object, added in place to the HDR image with the outgoing factor the shading pass left in its
//! alpha. Exact at each visible point and only where the surface is seen; it must rerun whenever
//! the view changes.
//!
//! Bindings: 0 = surface (sampled), 1 = samples, 2 = splat, 3 = objects, 4 = HDR (storage image).
//! Push: width, height.

use crate::gpu::{
    Binding, BindingKind, Buffer, ComputePipeline, DescriptorSet, Gpu, GpuResult, Image, Sampler, image_barrier,
};
use ash::vk;
use std::sync::Arc;

pub struct GatherPixelPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    _sampler: Sampler,
    hdr: vk::Image,
    extent: vk::Extent2D,
}

impl GatherPixelPass {
    pub fn new(
        gpu: &Arc<Gpu>,
        surface: &Image,
        samples: &Buffer,
        splat: &Buffer,
        objects: &Buffer,
        hdr: &Image,
    ) -> GpuResult<GatherPixelPass> {
        let s = BindingKind::StorageBuffer;
        let pipeline = ComputePipeline::new(
            gpu,
            "gather_pixel.comp",
            &[BindingKind::CombinedImageSampler, s, s, s, BindingKind::StorageImage],
            8,
        )?;
        let sampler = Sampler::new(gpu, vk::Filter::NEAREST)?;
        let set = pipeline.descriptor_set(&[
            Binding::Image {
                view: surface.view(),
                layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                sampler: sampler.raw(),
            },
            Binding::Buffer(samples),
            Binding::Buffer(splat),
            Binding::Buffer(objects),
            Binding::Image { view: hdr.view(), layout: vk::ImageLayout::GENERAL, sampler: vk::Sampler::null() },
        ])?;
        Ok(GatherPixelPass { pipeline, set, _sampler: sampler, hdr: hdr.raw(), extent: hdr.extent() })
    }

    /// Record: HDR to GENERAL, the gather, HDR back to SHADER_READ_ONLY_OPTIMAL for the tone map.
    pub fn record(&self, gpu: &Gpu, cmd: vk::CommandBuffer) {
        let device = gpu.device();
        let read = (vk::PipelineStageFlags2::COMPUTE_SHADER, vk::AccessFlags2::SHADER_SAMPLED_READ);
        let storage = (
            vk::PipelineStageFlags2::COMPUTE_SHADER,
            vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
        );
        let color = vk::ImageAspectFlags::COLOR;
        let (ro, general) = (vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL, vk::ImageLayout::GENERAL);
        image_barrier(device, cmd, self.hdr, color, (ro, general), read, storage);
        let push = [self.extent.width, self.extent.height];
        self.pipeline.dispatch(
            cmd,
            &self.set,
            bytemuck::bytes_of(&push),
            [self.extent.width.div_ceil(8), self.extent.height.div_ceil(8), 1],
        );
        image_barrier(device, cmd, self.hdr, color, (general, ro), storage, read);
    }
}
