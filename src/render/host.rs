//! The host's frame target at the boundary: the checks on a `HostTarget` before anything is
//! recorded into it (Vulkan cannot be asked an image view's format or size, so the host says
//! them, and what would otherwise be a validation error and, on some drivers, a crash is a
//! `RenderError`), and the hand-over of its images when it declares their states (`HostSync`).

use super::error::RenderError;
use super::target::{DeclaredImage, HostSync, HostTarget, ImageState, TargetDesc};
use crate::gpu::{Gpu, aspect_of, image_transition};
use ash::vk;

/// How the shading pass uses the host's colour image: loads or clears it and writes it.
const COLOR_USE: ImageState = ImageState {
    layout: vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
    stages: vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT,
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::COLOR_ATTACHMENT_READ.as_raw() | vk::AccessFlags2::COLOR_ATTACHMENT_WRITE.as_raw(),
    ),
};

/// How the shading pass uses the host's depth image: tests and writes it.
const DEPTH_USE: ImageState = ImageState {
    layout: vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
    stages: vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw() | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
    ),
    access: vk::AccessFlags2::from_raw(
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw(),
    ),
};

/// A declared image's states against what the frame does with it (`load`).
fn check_declared(which: &'static str, image: &DeclaredImage, load: bool) -> Result<(), RenderError> {
    use vk::ImageLayout as L;
    let reason = if image.image == vk::Image::null() {
        "the image handle is null"
    } else if load && image.entry.layout == L::UNDEFINED {
        "its entry layout is UNDEFINED but the frame loads it (load: true): its contents would be lost"
    } else if matches!(image.exit.layout, L::UNDEFINED | L::PREINITIALIZED) {
        "its exit layout is UNDEFINED or PREINITIALIZED, which no barrier may move an image to"
    } else if [image.entry, image.exit].iter().any(|s| s.stages.is_empty() && !s.access.is_empty()) {
        "a state has accesses but no stage to make them in"
    } else {
        return Ok(());
    };
    Err(RenderError::HostTargetState { which, reason })
}

/// Record the barriers that move the host's declared images from their entry states to the
/// shading pass's attachment use (nothing for `HostSync::Attachments`). Not loaded and drawn
/// whole, an image's contents are dropped (old layout UNDEFINED); a render area smaller than
/// the image keeps them, since the pixels outside it are the host's.
pub(super) fn record_entry(device: &ash::Device, cmd: vk::CommandBuffer, target: &HostTarget) {
    if let HostSync::Declared { color, depth } = target.sync {
        let whole = |size: vk::Extent2D| target.offset == vk::Offset2D::default() && target.extent == size;
        let from = |i: DeclaredImage, size| {
            if target.load || !whole(size) {
                i.entry
            } else {
                ImageState { layout: vk::ImageLayout::UNDEFINED, ..i.entry }
            }
        };
        let depth_aspect = aspect_of(target.depth.format);
        record(
            device,
            cmd,
            &[
                (color.image, vk::ImageAspectFlags::COLOR, from(color, target.color.extent), COLOR_USE),
                (depth.image, depth_aspect, from(depth, target.depth.extent), DEPTH_USE),
            ],
        );
    }
}

/// Record the barriers that move the host's declared images from the shading pass's writes to
/// their exit states (nothing for `HostSync::Attachments`).
pub(super) fn record_exit(device: &ash::Device, cmd: vk::CommandBuffer, target: &HostTarget) {
    if let HostSync::Declared { color, depth } = target.sync {
        let depth_aspect = aspect_of(target.depth.format);
        record(
            device,
            cmd,
            &[
                (color.image, vk::ImageAspectFlags::COLOR, COLOR_USE, color.exit),
                (depth.image, depth_aspect, DEPTH_USE, depth.exit),
            ],
        );
    }
}

/// One image barrier per (image, aspect, from, to), mip 0 and layer 0.
fn record(
    device: &ash::Device,
    cmd: vk::CommandBuffer,
    moves: &[(vk::Image, vk::ImageAspectFlags, ImageState, ImageState)],
) {
    let barriers: Vec<_> = moves
        .iter()
        .map(|&(image, aspect, from, to)| {
            // The view the host gives: mip 0, layer 0.
            let range = vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1);
            image_transition(image, range, (from.layout, to.layout), (from.stages, from.access), (to.stages, to.access))
        })
        .collect();
    // SAFETY: `cmd` is recording outside rendering; the host's images are alive while it is
    // (its contract) and were checked (`check_declared`).
    unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().image_memory_barriers(&barriers)) };
}

/// `target` against the formats the pipelines were made for (`desc`), its images' sizes and the
/// device's framebuffer limits: a render area of at least one pixel each way, at an offset not
/// negative (`VUID-VkRenderingInfo-pNext-06077`, `-06078`), reaching no further than either
/// image (`-06079`, `-06080`) nor than `maxFramebufferWidth/Height`
/// (`VUID-VkRenderingInfo-renderArea-07815`, `-07816`).
pub(super) fn check_target(
    gpu: &Gpu,
    desc: TargetDesc,
    samples: vk::SampleCountFlags,
    target: &HostTarget,
) -> Result<(), RenderError> {
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
    let single = vk::SampleCountFlags::TYPE_1;
    let resolve = target.resolve.map(|r| ("resolve", r, color_format, single));
    let attachments = [("colour", target.color, color_format, samples), ("depth", target.depth, depth_format, samples)];
    if resolve.is_some() && (samples == single || target.sync != HostSync::Attachments) {
        let reason = "a resolve image is for multisampled attachments, handed over in the attachment layouts";
        return Err(RenderError::HostTargetState { which: "resolve", reason });
    }
    for (which, attachment, declared, expected) in attachments.into_iter().chain(resolve) {
        if attachment.samples != expected {
            return Err(RenderError::HostTargetSamples { which, given: attachment.samples, expected });
        }
        if attachment.format != declared {
            return Err(RenderError::HostTargetFormat { which, given: attachment.format, declared });
        }
        let what = match which {
            "colour" => "the colour image",
            "depth" => "the depth image",
            _ => "the resolve image",
        };
        check_reach(target, what, attachment.extent)?;
    }
    if let HostSync::Declared { color, depth } = &target.sync {
        check_declared("colour", color, target.load)?;
        check_declared("depth", depth, target.load)?;
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
