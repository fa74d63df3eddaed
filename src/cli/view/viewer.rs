//! One window's worth of Vulkan and translucent: acquire a swapchain image, record translucent's
//! frame into it (display values, `Output::Display`) in the viewer's own command buffer,
//! submit, present. Out-of-date and suboptimal swapchains and window resizes
//! remake the swapchain and the targets at the next frame; a minimised window draws nothing.

use super::frames::{Readback, Slots, image_barrier};
use super::host::Host;
use super::present::Present;
use super::swapchain::{DEPTH_FORMAT, Surfaces};
use anyhow::{Context, Result};
use ash::vk;
use std::sync::Arc;
use std::time::Instant;
use translucent::render::target::{HostAttachment, HostSync, HostTarget};
use translucent::{FrameTimings, Gpu, GpuOptions, PreparedScene, Renderer, RendererOptions, SceneEdit, TargetDesc};

/// Frame times the viewer keeps: its summary's median is over at most this many latest frames.
pub const KEPT_FRAME_TIMES: usize = 4096;

/// Frames the viewer has in flight: the CPU records one while the device runs the other.
pub const IN_FLIGHT: usize = 2;

type Scope = (vk::PipelineStageFlags2, vk::AccessFlags2);
const COLOR_WRITE: Scope = (vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT, vk::AccessFlags2::COLOR_ATTACHMENT_WRITE);
const NOTHING: Scope = (vk::PipelineStageFlags2::NONE, vk::AccessFlags2::NONE);
const COPY_READ: Scope = (vk::PipelineStageFlags2::COPY, vk::AccessFlags2::TRANSFER_READ);
const DEPTH: Scope = (
    vk::PipelineStageFlags2::from_raw(
        vk::PipelineStageFlags2::EARLY_FRAGMENT_TESTS.as_raw() | vk::PipelineStageFlags2::LATE_FRAGMENT_TESTS.as_raw(),
    ),
    vk::AccessFlags2::from_raw(
        vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_READ.as_raw()
            | vk::AccessFlags2::DEPTH_STENCIL_ATTACHMENT_WRITE.as_raw(),
    ),
);

/// What the window shows, and what it took. Fields drop in order: translucent before the
/// viewer's Vulkan objects, the host (device, surface, instance) last.
pub struct Viewer {
    /// Holds translucent's `Gpu`: the last reference, dropped with it.
    pub renderer: Renderer,
    shot: Option<Readback>,
    slots: Slots,
    present: Present,
    surfaces: Surfaces,
    host: Host,
    /// Frames presented so far.
    pub frame: u64,
    vsync: bool,
    /// Set by a resize or an out-of-date swapchain: remake the swapchain before the next frame.
    pub stale: bool,
    /// Set when the window's surface is gone (the window destroyed under the viewer): nothing
    /// more can be presented, and the viewer closes.
    pub lost: bool,
    /// The latest frame's pass timings read back, and its wall time from the previous frame.
    pub timings: FrameTimings,
    pub last_frame: Option<Instant>,
    /// The wall time of the latest frames, at most `KEPT_FRAME_TIMES` (a viewer left open for
    /// hours keeps no more).
    pub frame_ms: std::collections::VecDeque<f64>,
    /// What changed before the latest frame (what its plan answered).
    pub last_change: Option<translucent::Change>,
    /// Rings over the lights while the user picks one.
    pub markers: Vec<super::present::Marker>,
}

impl Viewer {
    /// The viewer on `host`, drawing `scene` into a swapchain of `size`.
    pub fn new(host: Host, scene: PreparedScene, size: vk::Extent2D, vsync: bool) -> Result<Viewer> {
        // SAFETY: the host's instance, device and queue outlive the Gpu: the viewer drops the
        // renderer and the Gpu before the host (field order), and the device was made with
        // translucent's required features, as `vulkan()` declares.
        let gpu = unsafe { Gpu::from_host(host.vulkan(), &GpuOptions::default()) }?;
        let surfaces = Surfaces::new(&host, size, vsync, None)?;
        let renderer = new_renderer(&gpu, scene, surfaces.swapchain.format)?;
        let present = Present::new(&host, surfaces.swapchain.format)?;
        let slots = Slots::new(&host, IN_FLIGHT)?;
        Ok(Viewer {
            renderer,
            shot: None,
            slots,
            present,
            surfaces,
            host,
            frame: 0,
            vsync,
            stale: false,
            lost: false,
            timings: FrameTimings { passes: Vec::new() },
            last_frame: None,
            frame_ms: std::collections::VecDeque::with_capacity(KEPT_FRAME_TIMES),
            last_change: None,
            markers: Vec::new(),
        })
    }

    /// The device's name.
    pub fn device_name(&self) -> &str {
        &self.host.name
    }

    /// The swapchain's size.
    pub fn extent(&self) -> vk::Extent2D {
        self.surfaces.swapchain.extent
    }

    /// Draw `scene` (the scene prepared with another gather, error target or model) through
    /// `SceneEdit::Scene`, once no frame is in flight.
    pub fn rebuild(&mut self, scene: PreparedScene) -> Result<()> {
        self.idle();
        Ok(self.renderer.edit(SceneEdit::Scene(Box::new(scene)))?)
    }

    /// Wait until the device has finished everything submitted.
    fn idle(&self) {
        // SAFETY: plain wait on the viewer's own device.
        let _ = unsafe { self.host.device.device_wait_idle() };
    }

    /// Remake the swapchain and the targets at `size`.
    pub fn recreate(&mut self, size: vk::Extent2D) -> Result<()> {
        self.idle();
        let surfaces = Surfaces::new(&self.host, size, self.vsync, Some(&self.surfaces))?;
        self.surfaces = surfaces;
        if self.present.format() != self.surfaces.swapchain.format {
            // translucent's pipelines were made for the first format; the surface keeps it.
            anyhow::bail!("the window's swapchain format changed from {:?}", self.present.format());
        }
        self.shot = None;
        self.stale = false;
        Ok(())
    }

    /// Draw and present one frame; with `shot`, also copy the presented image to the host and
    /// answer it (RGBA8, rows top to bottom). Answers `Ok(None)` without drawing when the
    /// swapchain is out of date (`stale` is then set) or the surface is lost (`lost`).
    pub fn draw(&mut self, shot: bool) -> Result<Option<image::RgbaImage>> {
        let at = (self.frame % IN_FLIGHT as u64) as usize;
        let (fence, acquired, cmd) = {
            let slot = &self.slots.slots[at];
            (slot.fence, slot.acquired, slot.cmd)
        };
        let device = self.host.device.clone();
        // SAFETY: the fence belongs to this slot's last submission (or starts signalled).
        unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }?;
        if let Some(done) = self.slots.slots[at].recorded.take() {
            self.timings = self.renderer.read_timings(&done)?;
        }
        let swapchain = &self.surfaces.swapchain;
        // SAFETY: the semaphore's last signal was waited on by this slot's last submission.
        let acquire =
            unsafe { swapchain.loader.acquire_next_image(swapchain.handle, u64::MAX, acquired, vk::Fence::null()) };
        let index = match acquire {
            Ok((index, suboptimal)) => {
                self.stale |= suboptimal;
                index
            }
            Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => {
                self.stale = true;
                return Ok(None);
            }
            Err(vk::Result::ERROR_SURFACE_LOST_KHR) => {
                self.lost = true;
                return Ok(None);
            }
            Err(e) => return Err(e).context("vkAcquireNextImageKHR"),
        };
        // SAFETY: the slot's submission has finished (its fence), so its buffer can be reset.
        unsafe {
            device.reset_fences(&[fence])?;
            device.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty())?;
            device.begin_command_buffer(cmd, &vk::CommandBufferBeginInfo::default())?;
        }
        self.last_change = self.renderer.pending_change();
        let recorded = self.record(cmd, index, shot)?;
        self.slots.slots[at].recorded = Some(recorded);
        self.submit(cmd, fence, acquired, index)?;
        self.frame += 1;
        let now = Instant::now();
        if let Some(then) = self.last_frame.replace(now) {
            if self.frame_ms.len() == KEPT_FRAME_TIMES {
                self.frame_ms.pop_front();
            }
            self.frame_ms.push_back((now - then).as_secs_f64() * 1e3);
        }
        if !shot {
            return Ok(None);
        }
        // SAFETY: waits for the submission that copied the image.
        unsafe { device.wait_for_fences(&[fence], true, u64::MAX) }?;
        Ok(self
            .shot
            .as_ref()
            .map(|b| to_rgba(b.bytes(), self.surfaces.swapchain.extent, self.surfaces.swapchain.format)))
    }

    /// Everything one frame records into `cmd`: translucent into swapchain image `index` in
    /// display values, the rings over it while the user picks a light, and with `shot` a copy
    /// of it to the host.
    fn record(&mut self, cmd: vk::CommandBuffer, index: u32, shot: bool) -> Result<translucent::RecordedFrame> {
        let device = self.host.device.clone();
        let depth = self.surfaces.depth.image;
        let image = self.surfaces.swapchain.images[index as usize];
        let extent = self.surfaces.swapchain.extent;
        use vk::ImageLayout as L;
        // Cleared by translucent (`load: false`): the old contents never matter. The image's
        // barrier waits at colour output, where the submission waits for the acquire.
        image_barrier(&device, cmd, image, (L::UNDEFINED, L::COLOR_ATTACHMENT_OPTIMAL), COLOR_WRITE, COLOR_WRITE);
        image_barrier(&device, cmd, depth, (L::UNDEFINED, L::DEPTH_ATTACHMENT_OPTIMAL), DEPTH, DEPTH);
        let recorded = self.renderer.record_frame(cmd, Some(&self.target(index)))?;
        if !self.markers.is_empty() {
            // The rings load what translucent wrote: its writes first.
            let after = [vk::MemoryBarrier2::default()
                .src_stage_mask(COLOR_WRITE.0)
                .src_access_mask(COLOR_WRITE.1)
                .dst_stage_mask(COLOR_WRITE.0)
                .dst_access_mask(COLOR_WRITE.1 | vk::AccessFlags2::COLOR_ATTACHMENT_READ)];
            // SAFETY: `cmd` is recording outside any rendering.
            unsafe { device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&after)) };
        }
        self.present.record(cmd, self.surfaces.swapchain.view(index), extent, &self.markers);
        if shot && self.surfaces.swapchain.copyable {
            self.copy_out(cmd, image)?;
            image_barrier(&device, cmd, image, (L::TRANSFER_SRC_OPTIMAL, L::PRESENT_SRC_KHR), COPY_READ, NOTHING);
        } else {
            image_barrier(&device, cmd, image, (L::COLOR_ATTACHMENT_OPTIMAL, L::PRESENT_SRC_KHR), COLOR_WRITE, NOTHING);
        }
        // SAFETY: `cmd` is recording outside any rendering.
        unsafe { device.end_command_buffer(cmd) }?;
        Ok(recorded)
    }

    /// Swapchain image `index` and the depth image as translucent's target, cleared to the
    /// scene's background.
    fn target(&self, index: u32) -> HostTarget {
        let swapchain = &self.surfaces.swapchain;
        let (extent, format) = (swapchain.extent, swapchain.format);
        let single = vk::SampleCountFlags::TYPE_1;
        HostTarget {
            color: HostAttachment { view: swapchain.view(index), format, extent, samples: single },
            depth: HostAttachment { view: self.surfaces.depth.view, format: DEPTH_FORMAT, extent, samples: single },
            resolve: None,
            extent,
            offset: vk::Offset2D::default(),
            sync: HostSync::Attachments,
            load: false,
        }
    }

    /// Copy swapchain image `image` (in COLOR_ATTACHMENT_OPTIMAL, left in TRANSFER_SRC_OPTIMAL)
    /// into the screenshot buffer, made host-readable.
    fn copy_out(&mut self, cmd: vk::CommandBuffer, image: vk::Image) -> Result<()> {
        let extent = self.surfaces.swapchain.extent;
        let size = 4 * extent.width as usize * extent.height as usize;
        if self.shot.as_ref().is_none_or(|b| b.size != size) {
            self.shot = Some(Readback::new(&self.host, size)?);
        }
        let buffer = self.shot.as_ref().map(|b| b.buffer).unwrap_or_default();
        let device = &self.host.device;
        use vk::ImageLayout as L;
        image_barrier(
            device,
            cmd,
            image,
            (L::COLOR_ATTACHMENT_OPTIMAL, L::TRANSFER_SRC_OPTIMAL),
            COLOR_WRITE,
            COPY_READ,
        );
        let layers = vk::ImageSubresourceLayers::default().aspect_mask(vk::ImageAspectFlags::COLOR).layer_count(1);
        let region = [vk::BufferImageCopy::default().image_subresource(layers).image_extent(vk::Extent3D {
            width: extent.width,
            height: extent.height,
            depth: 1,
        })];
        let host_read = [vk::MemoryBarrier2::default()
            .src_stage_mask(vk::PipelineStageFlags2::COPY)
            .src_access_mask(vk::AccessFlags2::TRANSFER_WRITE)
            .dst_stage_mask(vk::PipelineStageFlags2::HOST)
            .dst_access_mask(vk::AccessFlags2::HOST_READ)];
        // SAFETY: `cmd` is recording outside any rendering; the buffer holds the whole image.
        unsafe {
            device.cmd_copy_image_to_buffer(cmd, image, L::TRANSFER_SRC_OPTIMAL, buffer, &region);
            device.cmd_pipeline_barrier2(cmd, &vk::DependencyInfo::default().memory_barriers(&host_read));
        }
        Ok(())
    }

    /// Submit `cmd` after the acquire, signalling `fence` and image `index`'s semaphore, and
    /// present the image.
    fn submit(&mut self, cmd: vk::CommandBuffer, fence: vk::Fence, acquired: vk::Semaphore, index: u32) -> Result<()> {
        let swapchain = &self.surfaces.swapchain;
        let drawn = swapchain.drawn[index as usize];
        let waits = [vk::SemaphoreSubmitInfo::default()
            .semaphore(acquired)
            .stage_mask(vk::PipelineStageFlags2::COLOR_ATTACHMENT_OUTPUT)];
        let signals =
            [vk::SemaphoreSubmitInfo::default().semaphore(drawn).stage_mask(vk::PipelineStageFlags2::ALL_COMMANDS)];
        let cmds = [vk::CommandBufferSubmitInfo::default().command_buffer(cmd)];
        let submit = [vk::SubmitInfo2::default()
            .wait_semaphore_infos(&waits)
            .command_buffer_infos(&cmds)
            .signal_semaphore_infos(&signals)];
        let (swapchains, indices, wait) = ([swapchain.handle], [index], [drawn]);
        let present =
            vk::PresentInfoKHR::default().wait_semaphores(&wait).swapchains(&swapchains).image_indices(&indices);
        // SAFETY: `cmd` has ended; the semaphores and fence are this frame's.
        unsafe {
            self.host.device.queue_submit2(self.host.queue, &submit, fence).context("vkQueueSubmit2")?;
            match swapchain.loader.queue_present(self.host.queue, &present) {
                Ok(suboptimal) => self.stale |= suboptimal,
                Err(vk::Result::ERROR_OUT_OF_DATE_KHR) => self.stale = true,
                Err(vk::Result::ERROR_SURFACE_LOST_KHR) => self.lost = true,
                Err(e) => return Err(e).context("vkQueuePresentKHR"),
            }
        }
        Ok(())
    }

    /// Give the renderer a scene edit (the camera, a light).
    pub fn edit(&mut self, edit: SceneEdit) -> Result<()> {
        Ok(self.renderer.edit(edit)?)
    }
}

impl Drop for Viewer {
    fn drop(&mut self) {
        // Closing mid-frame: everything submitted finishes before anything is destroyed.
        self.idle();
    }
}

/// translucent drawing display values into swapchain images of `format` (`Output::Display`).
fn new_renderer(gpu: &Arc<Gpu>, scene: PreparedScene, format: vk::Format) -> Result<Renderer> {
    let target = TargetDesc::Host { color_format: format, depth_format: DEPTH_FORMAT };
    let output = translucent::render::options::Output::Display;
    let options = RendererOptions { frames_in_flight: IN_FLIGHT, output, ..RendererOptions::default() };
    Ok(Renderer::with_options(gpu, scene, target, options)?)
}

/// The swapchain's bytes as RGBA8.
fn to_rgba(mut bytes: Vec<u8>, extent: vk::Extent2D, format: vk::Format) -> image::RgbaImage {
    if format == vk::Format::B8G8R8A8_UNORM {
        for pixel in bytes.chunks_exact_mut(4) {
            pixel.swap(0, 2);
        }
    }
    image::RgbaImage::from_raw(extent.width, extent.height, bytes).expect("the buffer holds the whole image")
}
