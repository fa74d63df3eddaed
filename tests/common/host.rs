//! A minimal host for `TargetDesc::Host` renderers on the tests' own `Gpu`: its colour and depth
//! images, the barrier that puts them in the layouts the contract names, a command buffer it
//! submits itself without waiting, and readback of its colour image.

use ash::vk;
use std::sync::Arc;
use translucent::gpu::{Access, Gpu, Image, ImageBarrier, ImageDesc, aspect_of};
use translucent::{HostAttachment, HostSync, HostTarget, TargetDesc};

/// The host's formats in these tests.
pub const COLOR: vk::Format = vk::Format::R16G16B16A16_SFLOAT;
pub const DEPTH: vk::Format = vk::Format::D32_SFLOAT;

/// The target description of a renderer drawing into `HostImages`.
pub fn desc() -> TargetDesc {
    TargetDesc::Host { color_format: COLOR, depth_format: DEPTH }
}

/// A host's colour and depth images.
pub struct HostImages {
    pub color: Image,
    pub depth: Image,
}

impl HostImages {
    /// Colour (of `color_format`) and depth images of `width` x `height`.
    pub fn new(gpu: &Arc<Gpu>, width: u32, height: u32, color_format: vk::Format) -> HostImages {
        Self::multisampled(gpu, width, height, color_format, vk::SampleCountFlags::TYPE_1)
    }

    /// As `new`, with `samples` per pixel.
    pub fn multisampled(
        gpu: &Arc<Gpu>,
        width: u32,
        height: u32,
        color_format: vk::Format,
        samples: vk::SampleCountFlags,
    ) -> HostImages {
        let image = |name, format, usage| {
            Image::new(gpu, &ImageDesc::new(name, width, height, format, usage).samples(samples)).unwrap()
        };
        let color = image("host colour", color_format, vk::ImageUsageFlags::COLOR_ATTACHMENT);
        let depth = image("host depth", DEPTH, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT);
        HostImages { color, depth }
    }

    /// The `HostTarget` over both images, drawing `extent` (cleared first).
    pub fn target(&self, extent: vk::Extent2D) -> HostTarget {
        let attachment = |image: &Image| HostAttachment {
            view: image.view(),
            format: image.desc().format,
            extent: image.extent(),
            samples: image.desc().samples,
        };
        HostTarget {
            color: attachment(&self.color),
            depth: attachment(&self.depth),
            extent,
            offset: vk::Offset2D::default(),
            resolve: None,
            sync: HostSync::Attachments,
            load: false,
        }
    }

    /// The target over the whole images.
    pub fn whole(&self) -> HostTarget {
        self.target(self.color.extent())
    }

    /// Record the move of both images into the attachment layouts (contents discarded), as a
    /// host does before its first drawing.
    pub fn to_attachments(&self, gpu: &Gpu, cmd: vk::CommandBuffer) {
        for (image, access) in
            [(&self.color, Access::ColorAttachmentWrite), (&self.depth, Access::DepthAttachmentReadWrite)]
        {
            let barrier = ImageBarrier {
                image: image.raw(),
                aspect: aspect_of(image.desc().format),
                previous: &[Access::Nothing],
                next: &[access],
                discard: true,
            };
            barrier.record(gpu.device(), cmd);
        }
    }

    /// Record the host's own clear of both whole images (colour to `color`, depth to `depth`),
    /// in the attachment layouts (after `to_attachments`), as its drawing before translucent's.
    pub fn clear(&self, gpu: &Gpu, cmd: vk::CommandBuffer, color: [f32; 4], depth: f32) {
        let colors = [vk::RenderingAttachmentInfo::default()
            .image_view(self.color.view())
            .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { color: vk::ClearColorValue { float32: color } })];
        let depth = vk::RenderingAttachmentInfo::default()
            .image_view(self.depth.view())
            .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
            .load_op(vk::AttachmentLoadOp::CLEAR)
            .store_op(vk::AttachmentStoreOp::STORE)
            .clear_value(vk::ClearValue { depth_stencil: vk::ClearDepthStencilValue { depth, stencil: 0 } });
        let area = vk::Rect2D { offset: vk::Offset2D::default(), extent: self.color.extent() };
        let info = vk::RenderingInfo::default()
            .render_area(area)
            .layer_count(1)
            .color_attachments(&colors)
            .depth_attachment(&depth);
        // SAFETY: `cmd` is recording outside rendering; both images are in the layouts named.
        unsafe {
            gpu.device().cmd_begin_rendering(cmd, &info);
            gpu.device().cmd_end_rendering(cmd);
        }
    }

    /// The colour image's texels (after a finished frame that drew into it).
    pub fn read_color(&self) -> Vec<u8> {
        self.color.read(Access::ColorAttachmentWrite).unwrap()
    }
}

/// A command buffer the host records and submits itself, with the fence of its submission.
pub struct HostCommands {
    gpu: Arc<Gpu>,
    pool: vk::CommandPool,
    pub cmd: vk::CommandBuffer,
    pub fence: vk::Fence,
}

impl HostCommands {
    /// A command buffer in the recording state.
    pub fn begin(gpu: &Arc<Gpu>) -> HostCommands {
        let device = gpu.device();
        let info = vk::CommandPoolCreateInfo::default().queue_family_index(gpu.queue_family());
        // SAFETY: plain creations on a live device; destroyed in Drop.
        unsafe {
            let pool = device.create_command_pool(&info, None).unwrap();
            let alloc = vk::CommandBufferAllocateInfo::default().command_pool(pool).command_buffer_count(1);
            let cmd = device.allocate_command_buffers(&alloc).unwrap()[0];
            device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default()).unwrap();
            let fence = device.create_fence(&vk::FenceCreateInfo::default(), None).unwrap();
            HostCommands { gpu: gpu.clone(), pool, cmd, fence }
        }
    }

    /// End and submit on the `Gpu`'s queue, signalling `fence`; no wait.
    pub fn submit(&self) {
        let device = self.gpu.device();
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(self.cmd)];
        let submit = [vk::SubmitInfo2::default().command_buffer_infos(&cmds)];
        // SAFETY: `cmd` is recording; the queue is locked while submitting.
        unsafe {
            device.end_command_buffer(self.cmd).unwrap();
            device.queue_submit2(*self.gpu.queue(), &submit, self.fence).unwrap();
        }
    }

    /// Whether the submission has finished (without waiting).
    pub fn finished(&self) -> bool {
        // SAFETY: a query on our own fence.
        unsafe { self.gpu.device().get_fence_status(self.fence) }.unwrap()
    }

    /// Wait for the submission.
    pub fn wait(&self) {
        // SAFETY: waiting on our own fence, after `submit`.
        unsafe { self.gpu.device().wait_for_fences(&[self.fence], true, u64::MAX) }.unwrap();
    }
}

impl Drop for HostCommands {
    fn drop(&mut self) {
        let device = self.gpu.device();
        // SAFETY: waited for (or never submitted) before the pool goes.
        unsafe {
            let _ = device.queue_wait_idle(*self.gpu.queue());
            device.destroy_fence(self.fence, None);
            device.destroy_command_pool(self.pool, None);
        }
    }
}
