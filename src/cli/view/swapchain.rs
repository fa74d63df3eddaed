//! The window's swapchain and a depth image at its size: translucent draws into the swapchain
//! image itself as a `HostTarget` (`Output::Display`), with that depth. Both are remade together
//! when the window's size changes or the swapchain goes out of date.

use super::host::Host;
use anyhow::{Context, Result, anyhow};
use ash::vk;

/// The depth image's format.
pub const DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The swapchain, its images' views, and one "drawn" semaphore per image (a present waits on
/// the one of its image, so no semaphore is signalled again before its present has waited).
pub struct Swapchain {
    device: ash::Device,
    pub loader: ash::khr::swapchain::Device,
    pub handle: vk::SwapchainKHR,
    pub images: Vec<vk::Image>,
    views: Vec<vk::ImageView>,
    pub drawn: Vec<vk::Semaphore>,
    pub format: vk::Format,
    pub extent: vk::Extent2D,
    /// Whether its images can be copied from (the screenshot of what was presented).
    pub copyable: bool,
}

impl Swapchain {
    /// A swapchain of `size` (clamped to what the surface allows), replacing `old` if given.
    /// Without `vsync` it presents as soon as a frame is done (mailbox or immediate where the
    /// surface has them), so the window shows what the renderer can do.
    pub fn new(host: &Host, size: vk::Extent2D, vsync: bool, old: vk::SwapchainKHR) -> Result<Swapchain> {
        let (surfaces, surface, physical) = (&host.surface_loader, host.surface, host.physical);
        // SAFETY: plain queries on a live surface.
        let (caps, formats, modes) = unsafe {
            (
                surfaces.get_physical_device_surface_capabilities(physical, surface)?,
                surfaces.get_physical_device_surface_formats(physical, surface)?,
                surfaces.get_physical_device_surface_present_modes(physical, surface)?,
            )
        };
        let format = [vk::Format::B8G8R8A8_UNORM, vk::Format::R8G8B8A8_UNORM]
            .into_iter()
            .find_map(|f| formats.iter().find(|s| s.format == f && s.color_space == vk::ColorSpaceKHR::SRGB_NONLINEAR))
            .ok_or_else(|| anyhow!("the window offers no 8-bit UNORM sRGB-nonlinear format: {formats:?}"))?;
        let mode = [vk::PresentModeKHR::MAILBOX, vk::PresentModeKHR::IMMEDIATE]
            .into_iter()
            .find(|m| !vsync && modes.contains(m))
            .unwrap_or(vk::PresentModeKHR::FIFO);
        let extent = if caps.current_extent.width == u32::MAX {
            vk::Extent2D {
                width: size.width.clamp(caps.min_image_extent.width, caps.max_image_extent.width),
                height: size.height.clamp(caps.min_image_extent.height, caps.max_image_extent.height),
            }
        } else {
            caps.current_extent
        };
        let count = if caps.max_image_count == 0 {
            caps.min_image_count + 1
        } else {
            (caps.min_image_count + 1).min(caps.max_image_count)
        };
        // The screenshot copies from the image it presents.
        let usage =
            vk::ImageUsageFlags::COLOR_ATTACHMENT | (caps.supported_usage_flags & vk::ImageUsageFlags::TRANSFER_SRC);
        let info = vk::SwapchainCreateInfoKHR::default()
            .surface(surface)
            .min_image_count(count)
            .image_format(format.format)
            .image_color_space(format.color_space)
            .image_extent(extent)
            .image_array_layers(1)
            .image_usage(usage)
            .image_sharing_mode(vk::SharingMode::EXCLUSIVE)
            .pre_transform(caps.current_transform)
            .composite_alpha(vk::CompositeAlphaFlagsKHR::OPAQUE)
            .present_mode(mode)
            .clipped(true)
            .old_swapchain(old);
        let loader = ash::khr::swapchain::Device::new(&host.instance, &host.device);
        // SAFETY: valid create info; destroyed in `drop`, after the device is idle.
        let handle = unsafe { loader.create_swapchain(&info, None) }.context("vkCreateSwapchainKHR")?;
        let mut swapchain = Swapchain {
            device: host.device.clone(),
            loader,
            handle,
            images: Vec::new(),
            views: Vec::new(),
            drawn: Vec::new(),
            format: format.format,
            extent,
            copyable: usage.contains(vk::ImageUsageFlags::TRANSFER_SRC),
        };
        // SAFETY: the swapchain is live; views and semaphores are destroyed in `drop`.
        unsafe {
            swapchain.images = swapchain.loader.get_swapchain_images(handle)?;
            for &image in &swapchain.images {
                swapchain.views.push(
                    host.device
                        .create_image_view(&view_info(image, format.format, vk::ImageAspectFlags::COLOR), None)?,
                );
                swapchain.drawn.push(host.device.create_semaphore(&vk::SemaphoreCreateInfo::default(), None)?);
            }
        }
        Ok(swapchain)
    }

    /// Image `index`'s view.
    pub fn view(&self, index: u32) -> vk::ImageView {
        self.views[index as usize]
    }
}

impl Drop for Swapchain {
    fn drop(&mut self) {
        // SAFETY: the viewer waits for the device to be idle before it drops a swapchain.
        unsafe {
            for (&view, &semaphore) in self.views.iter().zip(&self.drawn) {
                self.device.destroy_image_view(view, None);
                self.device.destroy_semaphore(semaphore, None);
            }
            self.loader.destroy_swapchain(self.handle, None);
        }
    }
}

/// A 2D view of mip 0, layer 0.
pub fn view_info(
    image: vk::Image,
    format: vk::Format,
    aspect: vk::ImageAspectFlags,
) -> vk::ImageViewCreateInfo<'static> {
    vk::ImageViewCreateInfo::default()
        .image(image)
        .view_type(vk::ImageViewType::TYPE_2D)
        .format(format)
        .subresource_range(vk::ImageSubresourceRange::default().aspect_mask(aspect).level_count(1).layer_count(1))
}

/// One device-local image with its memory and view.
pub struct Image {
    device: ash::Device,
    pub image: vk::Image,
    memory: vk::DeviceMemory,
    pub view: vk::ImageView,
}

impl Image {
    pub fn new(host: &Host, format: vk::Format, extent: vk::Extent2D, usage: vk::ImageUsageFlags) -> Result<Image> {
        let aspect = if format == DEPTH_FORMAT { vk::ImageAspectFlags::DEPTH } else { vk::ImageAspectFlags::COLOR };
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(format)
            .extent(vk::Extent3D { width: extent.width, height: extent.height, depth: 1 })
            .mip_levels(1)
            .array_layers(1)
            .samples(vk::SampleCountFlags::TYPE_1)
            .usage(usage);
        let device = &host.device;
        // SAFETY: valid create infos; everything is destroyed in `drop`.
        unsafe {
            let image = device.create_image(&info, None)?;
            let req = device.get_image_memory_requirements(image);
            let kind = host.memory_type(req.memory_type_bits, vk::MemoryPropertyFlags::DEVICE_LOCAL)?;
            let allocate = vk::MemoryAllocateInfo::default().allocation_size(req.size).memory_type_index(kind);
            let memory = device.allocate_memory(&allocate, None)?;
            device.bind_image_memory(image, memory, 0)?;
            let view = device.create_image_view(&view_info(image, format, aspect), None)?;
            Ok(Image { device: device.clone(), image, memory, view })
        }
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: the viewer waits for the device to be idle before it drops an image.
        unsafe {
            self.device.destroy_image_view(self.view, None);
            self.device.destroy_image(self.image, None);
            self.device.free_memory(self.memory, None);
        }
    }
}

/// The swapchain and the depth image translucent draws with, of one size.
pub struct Surfaces {
    pub depth: Image,
    pub swapchain: Swapchain,
}

impl Surfaces {
    pub fn new(host: &Host, size: vk::Extent2D, vsync: bool, old: Option<&Surfaces>) -> Result<Surfaces> {
        let old = old.map_or(vk::SwapchainKHR::null(), |s| s.swapchain.handle);
        let swapchain = Swapchain::new(host, size, vsync, old)?;
        let extent = swapchain.extent;
        let depth = Image::new(host, DEPTH_FORMAT, extent, vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT)?;
        Ok(Surfaces { depth, swapchain })
    }
}
