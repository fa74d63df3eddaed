//! The checks on a host's frame target (`HostTarget`) before anything is recorded into it:
//! Vulkan cannot be asked an image view's format or size, so the host says them, and what
//! would otherwise be a validation error and, on some drivers, a crash is a `RenderError`.

use super::renderer::RenderError;
use super::shade::{HostAttachment, HostTarget, TargetDesc};
use crate::gpu::Gpu;
use ash::vk;

/// `target` against the formats the pipelines were made for (`desc`), its images' sizes and the
/// device's framebuffer limits: a render area of at least one pixel each way, within both images
/// (`VUID-VkRenderingInfo-pNext-06079`, `-06080`) and within `maxFramebufferWidth/Height`
/// (`VUID-VkRenderingInfo-renderArea-07815`).
pub(super) fn check_target(gpu: &Gpu, desc: TargetDesc, target: &HostTarget) -> Result<(), RenderError> {
    let TargetDesc::Host { color_format, depth_format } = desc else {
        return Err(RenderError::UnexpectedHostTarget);
    };
    let vk::Extent2D { width, height } = target.extent;
    if width == 0 || height == 0 {
        return Err(RenderError::HostTargetEmpty { extent: [width, height] });
    }
    for (which, attachment, declared) in [("colour", target.color, color_format), ("depth", target.depth, depth_format)]
    {
        check_attachment(which, attachment, declared, target.extent)?;
    }
    let limits = &gpu.properties().limits;
    let limit = [limits.max_framebuffer_width, limits.max_framebuffer_height];
    if width > limit[0] || height > limit[1] {
        return Err(RenderError::HostTargetTooLarge {
            extent: [width, height],
            what: "the device's maxFramebufferWidth x maxFramebufferHeight",
            limit,
        });
    }
    Ok(())
}

fn check_attachment(
    which: &'static str,
    attachment: HostAttachment,
    declared: vk::Format,
    extent: vk::Extent2D,
) -> Result<(), RenderError> {
    if attachment.format != declared {
        return Err(RenderError::HostTargetFormat { which, given: attachment.format, declared });
    }
    let image = attachment.extent;
    if extent.width > image.width || extent.height > image.height {
        let what = if which == "colour" { "the colour image" } else { "the depth image" };
        return Err(RenderError::HostTargetTooLarge {
            extent: [extent.width, extent.height],
            what,
            limit: [image.width, image.height],
        });
    }
    Ok(())
}
