//! Tone-map pass (`glsl/tonemap.comp`): linear HDR radiance to 8-bit sRGB (exposure, ACES fit
//! of Narkowicz 2015, sRGB transfer), counting non-finite pixels so a NaN is caught, not drawn.
//!
//! Bindings: 0 = HDR image (`Resource::Hdr`, sampled), 1 = packed RGBA8 output
//! (`Resource::Tonemapped`), 2 = counters (`Resource::TonemapCounters`); the pass owns the last two.
//! Push: `TonemapPush`.

use super::graph::{Resource, Resources, Use, read, write};
use super::error::RenderError;
use super::pass::{FrameInputs, PassContext, Rebuild, RegisteredPass, RenderPass};
use crate::gpu::{Access, Binding, Buffer, BufferDesc, ComputePipeline, DescriptorSet, Gpu, GpuError, GpuResult};
use ash::vk;
use std::sync::Arc;

/// Where the tone curve's input is capped (`TONE_SATURATION` in glsl/common/tonemap.glsl): the curve
/// is 1 from 7.25 on, and the cap keeps its squares finite in f32.
pub const TONE_SATURATION: f64 = 64.0;

/// The tone map of one linear channel in f64, twin of glsl/tonemap.comp: exposure, the ACES fit
/// of Narkowicz 2015 `x (2.51 x + 0.03) / (x (2.43 x + 0.59) + 0.14)` clamped to [0, 1], the
/// sRGB transfer function, and 8-bit quantisation as `packUnorm4x8` does it.
pub fn display_value(linear: f64, exposure: f64) -> u8 {
    let x = (linear.max(0.0) * exposure).min(TONE_SATURATION);
    let aces = ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
    let srgb = if aces <= 0.0031308 { aces * 12.92 } else { 1.055 * aces.powf(1.0 / 2.4) - 0.055 };
    (srgb.clamp(0.0, 1.0) * 255.0).round() as u8
}

/// `TonemapPush` in glsl/tonemap.comp.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TonemapPush {
    /// HDR image width in pixels.
    pub width: u32,
    /// HDR image height in pixels.
    pub height: u32,
    /// Multiplier on linear radiance before the tone curve (`render.exposure`).
    pub exposure: f32,
}

/// The tone map: glsl/tonemap.comp over the HDR image into a host-readable RGBA8 buffer and a
/// non-finite pixel counter, both owned by the pass and read with `read` after the fence.
pub struct TonemapPass {
    pipeline: ComputePipeline,
    set: DescriptorSet,
    output: Buffer,
    counters: Buffer,
    width: u32,
    height: u32,
}

impl TonemapPass {
    /// The pipeline, its output and counter buffers, and one descriptor set over the frame
    /// targets' HDR image and those buffers.
    pub fn new(gpu: &Arc<Gpu>, resources: &Resources) -> GpuResult<TonemapPass> {
        let pipeline = ComputePipeline::new(gpu, "tonemap.comp")?;
        let hdr =
            resources.targets.hdr().ok_or_else(|| GpuError::MissingImages { pass: "tone map", images: "HDR image" })?;
        let extent = hdr.extent();
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let pixels = extent.width as u64 * extent.height as u64;
        let output = Buffer::new(gpu, &BufferDesc::readback("tonemapped rgba8", 4 * pixels, usage))?;
        let counters = Buffer::new(gpu, &BufferDesc::readback("tonemap counters", 16, usage))?;
        let set = pipeline.descriptor_set(&[
            resources.bind(Resource::Hdr)?,
            Resource::Tonemapped.bind(Binding::Buffer(&output)),
            Resource::TonemapCounters.bind(Binding::Buffer(&counters)),
        ])?;
        Ok(TonemapPass { pipeline, set, output, counters, width: extent.width, height: extent.height })
    }

    /// The tone-mapped image, rows top to bottom, RGBA8, and the count of non-finite pixels.
    /// Call after the submission that recorded the pass has finished.
    pub fn read(&self) -> GpuResult<(Vec<u8>, u32)> {
        let counters: Vec<u32> = self.counters.read()?;
        Ok((self.output.read::<u8>()?, counters[0]))
    }
}

impl RenderPass for TonemapPass {
    fn uses(&self, _: &FrameInputs) -> Vec<Use> {
        vec![
            read(Resource::Hdr, Access::ComputeSampledRead),
            write(Resource::TonemapCounters, Access::TransferWrite),
            write(Resource::Tonemapped, Access::ComputeWrite),
        ]
    }

    /// Zero the non-finite counter, then tone-map (which counts into it).
    fn record(&self, cmd: vk::CommandBuffer, frame: &FrameInputs) {
        // SAFETY: `cmd` is recording outside a render pass; the counter buffer is ours.
        unsafe { frame.gpu.device().cmd_fill_buffer(cmd, self.counters.raw(), 0, vk::WHOLE_SIZE, 0) };
        frame.before(cmd, &[write(Resource::TonemapCounters, Access::ComputeReadWrite)]);
        let push = TonemapPush { width: self.width, height: self.height, exposure: frame.exposure };
        self.pipeline.dispatch(cmd, &self.set, &push, [self.width, self.height, 1]);
    }
}

impl RegisteredPass for TonemapPass {
    // It binds the own HDR image, which a resize replaces.
    const REBUILT_ON: &'static [Rebuild] = &[Rebuild::Resize];

    fn build(context: &PassContext) -> Result<Option<Self>, RenderError> {
        // A host target has no HDR image of the renderer's: the host tone-maps its own.
        if context.resources.targets.hdr().is_none() {
            return Ok(None);
        }
        Ok(Some(TonemapPass::new(context.gpu, &context.resources)?))
    }
}
