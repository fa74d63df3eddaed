//! `RendererOptions`: what a host chooses of a renderer beyond its target, and their checks.

use super::error::RenderError;
use super::target::{DepthConvention, DepthTest, TargetDesc};
use crate::gpu::Gpu;
use ash::vk;

/// Frames a host may have in flight at once unless it chooses
/// (`RendererOptions::frames_in_flight`): each has its own timestamp queries.
pub const FRAMES_IN_FLIGHT: usize = 3;
/// The most frames in flight a renderer takes: each is a query pool, and a count past what any
/// swapchain holds is more likely a mistake than a wish.
pub const MAX_FRAMES_IN_FLIGHT: usize = 16;

/// What a host chooses of a renderer beyond its target (`Renderer::with_options`); `default()`
/// is what `Renderer::new` and `with_target` take.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RendererOptions {
    /// Frames that may be in flight at once, each with its own timestamp queries: a frame's
    /// timings can be read until this many later frames are recorded (`read_timings`).
    /// 1 to `MAX_FRAMES_IN_FLIGHT`; `FRAMES_IN_FLIGHT` (3) by default.
    pub frames_in_flight: usize,
    /// The depth test shading makes against the target's depth, and what it clears depth to;
    /// standard depth (0 near, LESS_OR_EQUAL) by default. With reversed-Z, give the renderer
    /// reversed projections (`CameraView::reversed_depth`); its first camera is reversed so.
    pub depth: DepthTest,
    /// Samples per pixel of the host's colour and depth images (MSAA): shading rasterises at
    /// that rate and resolves into `HostTarget::resolve` when given. TYPE_1 by default; above it,
    /// a host target only, and a count the device supports for colour and depth attachments
    /// (`framebufferColorSampleCounts`, `framebufferDepthSampleCounts`).
    pub samples: vk::SampleCountFlags,
    /// What the host's colour image receives: linear radiance (`Output::Linear`, the default),
    /// or display values (`Output::Display`). A host target only.
    pub output: Output,
}

/// What the shading pass writes into a host's colour image.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Output {
    /// Linear radiance, for the host's own tone map or post pass.
    #[default]
    Linear,
    /// Display sRGB in [0, 1]: the tone map's curve (exposure from the scene, the ACES fit, the
    /// sRGB transfer function) applied in the shading pass, for an 8-bit UNORM image such as a
    /// swapchain's, which then needs no pass of the host's between translucent and the present.
    Display,
}

impl Default for RendererOptions {
    fn default() -> Self {
        RendererOptions {
            frames_in_flight: FRAMES_IN_FLIGHT,
            depth: DepthTest::STANDARD,
            samples: vk::SampleCountFlags::TYPE_1,
            output: Output::Linear,
        }
    }
}

impl RendererOptions {
    /// An error naming what the options get wrong for `target` on `gpu`.
    pub(in crate::render) fn check(&self, gpu: &Gpu, target: TargetDesc) -> Result<(), RenderError> {
        let samples = self.samples;
        let limits = &gpu.properties().limits;
        let supported = limits.framebuffer_color_sample_counts & limits.framebuffer_depth_sample_counts;
        let reason = if samples.as_raw().count_ones() != 1 {
            Some("a sample count is one of the SampleCountFlags bits")
        } else if !supported.contains(samples) {
            Some("the device does not support it for both colour and depth attachments")
        } else if samples != vk::SampleCountFlags::TYPE_1 && target == TargetDesc::Own {
            Some("the renderer's own images are single-sampled: multisampling is for a host target")
        } else {
            None
        };
        if self.output == Output::Display && target == TargetDesc::Own {
            return Err(RenderError::DisplayOnOwnTarget);
        }
        if let Some(reason) = reason {
            return Err(RenderError::Samples { given: samples, supported, reason });
        }
        let max = MAX_FRAMES_IN_FLIGHT;
        if self.frames_in_flight == 0 || self.frames_in_flight > max {
            return Err(RenderError::FramesInFlight { given: self.frames_in_flight, max });
        }
        if !self.depth.is_consistent() {
            let expected = match self.depth.convention {
                DepthConvention::Standard => "LESS or LESS_OR_EQUAL",
                DepthConvention::Reversed => "GREATER or GREATER_OR_EQUAL",
            };
            let DepthTest { compare, convention } = self.depth;
            return Err(RenderError::DepthCompare { compare, convention, expected });
        }
        Ok(())
    }
}
