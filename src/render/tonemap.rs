//! Tone-map pass (`glsl/tonemap.comp`): linear HDR radiance to 8-bit sRGB (exposure, ACES fit
//! of Narkowicz 2015, sRGB transfer), counting non-finite pixels so a NaN is caught, not drawn.
//!
//! Bindings: 0 = HDR image (combined sampler), 1 = packed RGBA8 output, 2 = counters.
//! Push: width, height, exposure.

use crate::gpu::{
    Binding, BindingKind, Buffer, BufferDesc, ComputePipeline, DescriptorSet, Gpu, GpuResult, Image, Sampler,
};
use ash::vk;
use std::sync::Arc;

pub struct TonemapPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    output: Buffer,
    counters: Buffer,
    _sampler: Sampler,
    width: u32,
    height: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct Push {
    width: u32,
    height: u32,
    exposure: f32,
}

impl TonemapPass {
    /// `hdr` must be in SHADER_READ_ONLY_OPTIMAL when the pass runs.
    pub fn new(gpu: &Arc<Gpu>, hdr: &Image) -> GpuResult<TonemapPass> {
        let pipeline = ComputePipeline::new(
            gpu,
            "tonemap.comp",
            &[BindingKind::CombinedImageSampler, BindingKind::StorageBuffer, BindingKind::StorageBuffer],
            12,
        )?;
        let extent = hdr.extent();
        let sampler = Sampler::new(gpu, vk::Filter::NEAREST)?;
        let output = Buffer::new(
            gpu,
            &BufferDesc::readback(
                "tonemapped rgba8",
                4 * extent.width as u64 * extent.height as u64,
                vk::BufferUsageFlags::STORAGE_BUFFER,
            ),
        )?;
        let counters =
            Buffer::new(gpu, &BufferDesc::readback("tonemap counters", 16, vk::BufferUsageFlags::STORAGE_BUFFER))?;
        let set = pipeline.descriptor_set(&[
            Binding::Image {
                view: hdr.view(),
                layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
                sampler: sampler.raw(),
            },
            Binding::Buffer(&output),
            Binding::Buffer(&counters),
        ])?;
        Ok(TonemapPass {
            pipeline,
            set,
            output,
            counters,
            _sampler: sampler,
            width: extent.width,
            height: extent.height,
        })
    }

    /// Record the pass; zeroes the non-finite counter first.
    pub fn record(&self, gpu: &Gpu, cmd: vk::CommandBuffer, exposure: f32) {
        // SAFETY: `cmd` is recording outside a render pass; the counter buffer is ours.
        unsafe { gpu.device().cmd_fill_buffer(cmd, self.counters.raw(), 0, vk::WHOLE_SIZE, 0) };
        crate::gpu::memory_barrier(
            gpu.device(),
            cmd,
            (vk::PipelineStageFlags2::CLEAR, vk::AccessFlags2::TRANSFER_WRITE),
            (
                vk::PipelineStageFlags2::COMPUTE_SHADER,
                vk::AccessFlags2::SHADER_STORAGE_READ | vk::AccessFlags2::SHADER_STORAGE_WRITE,
            ),
        );
        let push = Push { width: self.width, height: self.height, exposure };
        self.pipeline.dispatch(
            cmd,
            &self.set,
            bytemuck::bytes_of(&push),
            [self.width.div_ceil(8), self.height.div_ceil(8), 1],
        );
    }

    /// The tone-mapped image, rows top to bottom, RGBA8, and the count of non-finite pixels.
    /// Call after the submission that recorded the pass has finished.
    pub fn read(&self) -> GpuResult<(Vec<u8>, u32)> {
        let counters: Vec<u32> = self.counters.read()?;
        Ok((self.output.read::<u8>()?, counters[0]))
    }
}
