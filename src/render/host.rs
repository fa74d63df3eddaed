//! The checks on a host's frame target (`HostTarget`) before anything is recorded into it:
//! Vulkan cannot be asked an image view's format or size, so the host says them, and what
//! would otherwise be a validation error and, on some drivers, a crash is a `RenderError`.

use super::renderer::RenderError;
use super::shade::{HostTarget, TargetDesc};
use crate::gpu::Gpu;
use ash::vk;

/// `target` against the formats the pipelines were made for (`desc`), its images' sizes and the
/// device's framebuffer limits: a render area of at least one pixel each way, at an offset not
/// negative (`VUID-VkRenderingInfo-pNext-06077`, `-06078`), reaching no further than either
/// image (`-06079`, `-06080`) nor than `maxFramebufferWidth/Height`
/// (`VUID-VkRenderingInfo-renderArea-07815`, `-07816`).
pub(super) fn check_target(gpu: &Gpu, desc: TargetDesc, target: &HostTarget) -> Result<(), RenderError> {
    let TargetDesc::Host { color_format, depth_format } = desc else {
        return Err(RenderError::UnexpectedHostTarget);
    };
    let vk::Extent2D { width, height } = target.extent;
    if width == 0 || height == 0 {
        return Err(RenderError::HostTargetEmpty { extent: [width, height] });
    }
    let vk::Offset2D { x, y } = target.offset;
    if x < 0 || y < 0 {
        return Err(RenderError::HostTargetOffset { offset: [x, y] });
    }
    for (which, attachment, declared) in [("colour", target.color, color_format), ("depth", target.depth, depth_format)]
    {
        if attachment.format != declared {
            return Err(RenderError::HostTargetFormat { which, given: attachment.format, declared });
        }
        let what = if which == "colour" { "the colour image" } else { "the depth image" };
        check_reach(target, what, attachment.extent)?;
    }
    let limits = &gpu.properties().limits;
    let limit = vk::Extent2D { width: limits.max_framebuffer_width, height: limits.max_framebuffer_height };
    check_reach(target, "the device's maxFramebufferWidth x maxFramebufferHeight", limit)
}

/// An error unless `target`'s render area, from its offset, stays within `limit` (`what`).
fn check_reach(target: &HostTarget, what: &'static str, limit: vk::Extent2D) -> Result<(), RenderError> {
    // In u64: an offset near i32::MAX plus a large extent overflows u32.
    let reach = |offset: i32, size: u32| offset as u64 + u64::from(size);
    let (offset, extent) = (target.offset, target.extent);
    if reach(offset.x, extent.width) > u64::from(limit.width)
        || reach(offset.y, extent.height) > u64::from(limit.height)
    {
        return Err(RenderError::HostTargetTooLarge {
            extent: [extent.width, extent.height],
            offset: [offset.x, offset.y],
            what,
            limit: [limit.width, limit.height],
        });
    }
    Ok(())
}
