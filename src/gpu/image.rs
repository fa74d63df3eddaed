//! `Image`: a 2D VkImage with its memory and a view, freed on Drop.

use super::barrier::{Access, ImageBarrier, transfer_to_host};
use super::buffer::{Buffer, BufferDesc};
use super::context::Gpu;
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use std::sync::Arc;

/// What to create: a 2D image with one mip level, one sample per texel unless set, and optimal
/// tiling, and one view over all its layers; a builder-style value like `BufferDesc`.
#[derive(Clone, Debug)]
pub struct ImageDesc {
    /// Debug name, given to the allocator and used in error messages.
    pub name: String,
    /// Width in texels; 0 is refused.
    pub width: u32,
    /// Height in texels; 0 is refused.
    pub height: u32,
    /// Texel format; a depth format gets a depth-aspect view (`aspect_of`).
    pub format: vk::Format,
    /// How the image is used; `Image::new` always adds TRANSFER_SRC so it can be read back.
    pub usage: vk::ImageUsageFlags,
    /// Layers (e.g. one per shadow-casting light); the view is a 2D array when above 1.
    pub layers: u32,
    /// Make the whole-image view a 2D array even with one layer (for `sampler2DArray*`).
    pub array_view: bool,
    /// Samples per texel (a multisampled attachment); TYPE_1 unless set.
    pub samples: vk::SampleCountFlags,
}

impl ImageDesc {
    /// One layer with a plain 2D view.
    pub fn new(name: &str, width: u32, height: u32, format: vk::Format, usage: vk::ImageUsageFlags) -> Self {
        Self {
            name: name.into(),
            width,
            height,
            format,
            usage,
            layers: 1,
            array_view: false,
            samples: vk::SampleCountFlags::TYPE_1,
        }
    }
    /// Set the number of array layers; above 1 the view is a 2D array.
    pub fn layers(mut self, layers: u32) -> Self {
        self.layers = layers;
        self
    }
    /// Samples per texel (a multisampled attachment).
    pub fn samples(mut self, samples: vk::SampleCountFlags) -> Self {
        self.samples = samples;
        self
    }
    /// A 2D-array view whatever the layer count.
    pub fn array_view(mut self) -> Self {
        self.array_view = true;
        self
    }
}

/// A 2D VkImage (possibly layered) in device-local memory from gpu_allocator, with one view over
/// all its layers. It starts in UNDEFINED layout, so its first barrier discards (`Access::Nothing`
/// before). It holds an `Arc<Gpu>` and on Drop destroys the view, then the image, then frees the
/// memory; Vulkan requires that no pending submission still uses it then.
pub struct Image {
    gpu: Arc<Gpu>,
    raw: vk::Image,
    view: vk::ImageView,
    allocation: Option<Allocation>,
    desc: ImageDesc,
}

/// Bytes per texel of the formats this crate reads back.
pub fn bytes_per_texel(format: vk::Format) -> Option<u64> {
    match format {
        vk::Format::R8G8B8A8_UNORM | vk::Format::R8G8B8A8_SRGB | vk::Format::B8G8R8A8_UNORM => Some(4),
        vk::Format::R32_SFLOAT | vk::Format::D32_SFLOAT => Some(4),
        vk::Format::D16_UNORM => Some(2),
        vk::Format::R16G16B16A16_SFLOAT => Some(8),
        vk::Format::R32G32B32A32_SFLOAT => Some(16),
        _ => None,
    }
}

/// Depth formats get the depth aspect, everything else colour.
pub fn aspect_of(format: vk::Format) -> vk::ImageAspectFlags {
    match format {
        vk::Format::D16_UNORM | vk::Format::D32_SFLOAT | vk::Format::X8_D24_UNORM_PACK32 => vk::ImageAspectFlags::DEPTH,
        vk::Format::D24_UNORM_S8_UINT | vk::Format::D32_SFLOAT_S8_UINT | vk::Format::D16_UNORM_S8_UINT => {
            vk::ImageAspectFlags::DEPTH
        }
        _ => vk::ImageAspectFlags::COLOR,
    }
}

impl Image {
    /// Create the image, allocate and bind its memory, and create its view. Fails on an empty
    /// extent or layer count.
    pub fn new(gpu: &Arc<Gpu>, desc: &ImageDesc) -> GpuResult<Image> {
        if desc.width == 0 || desc.height == 0 || desc.layers == 0 {
            return Err(GpuError::EmptyImage {
                name: desc.name.clone(),
                extent: [desc.width, desc.height, desc.layers],
            });
        }
        let device = gpu.device();
        let info = vk::ImageCreateInfo::default()
            .image_type(vk::ImageType::TYPE_2D)
            .format(desc.format)
            .extent(vk::Extent3D { width: desc.width, height: desc.height, depth: 1 })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(desc.samples)
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage | vk::ImageUsageFlags::TRANSFER_SRC)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid create info; destroyed in Drop or below on failure.
        let raw = unsafe { device.create_image(&info, None) }.vk("vkCreateImage")?;
        // SAFETY: `raw` was just created on this device and is not yet bound or destroyed.
        let requirements = unsafe { device.get_image_memory_requirements(raw) };
        let allocation = match gpu.allocator().allocate(&AllocationCreateDesc {
            name: &desc.name,
            requirements,
            location: MemoryLocation::GpuOnly,
            linear: false,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        }) {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: `raw` was created above on this device, has no memory bound and was never
                // used by a command, and nothing else holds the handle.
                unsafe { device.destroy_image(raw, None) };
                return Err(GpuError::Alloc { what: desc.name.clone(), source });
            }
        };
        let mut image = Image {
            gpu: gpu.clone(),
            raw,
            view: vk::ImageView::null(),
            allocation: Some(allocation),
            desc: desc.clone(),
        };
        let a = image.allocation.as_ref().unwrap();
        // SAFETY: the allocation satisfies the image's requirements; on error Drop cleans up.
        unsafe { device.bind_image_memory(raw, a.memory(), a.offset()) }.vk("vkBindImageMemory")?;
        let view_type = if desc.layers > 1 || desc.array_view {
            vk::ImageViewType::TYPE_2D_ARRAY
        } else {
            vk::ImageViewType::TYPE_2D
        };
        let view_info =
            vk::ImageViewCreateInfo::default().image(raw).view_type(view_type).format(desc.format).subresource_range(
                vk::ImageSubresourceRange::default()
                    .aspect_mask(aspect_of(desc.format))
                    .level_count(1)
                    .layer_count(desc.layers),
            );
        // SAFETY: `raw` is bound to memory and the view's format, aspect and layers match its
        // create info; Drop destroys the view (on error here `view` stays null and Drop skips it).
        image.view = unsafe { device.create_image_view(&view_info, None) }.vk("vkCreateImageView")?;
        Ok(image)
    }

    /// The Vulkan image handle, for barriers, clears and copies.
    pub fn raw(&self) -> vk::Image {
        self.raw
    }
    /// The view over every layer (2D, or 2D array when layered or `array_view`), for attachments
    /// and descriptors.
    pub fn view(&self) -> vk::ImageView {
        self.view
    }
    /// The description it was created from.
    pub fn desc(&self) -> &ImageDesc {
        &self.desc
    }
    /// Width and height, as render areas and viewports take them.
    pub fn extent(&self) -> vk::Extent2D {
        vk::Extent2D { width: self.desc.width, height: self.desc.height }
    }

    /// Copy layer 0 into host memory: tightly packed rows of texels as the format stores them.
    /// `previous` is the last access to the image (its layout follows); it is left in
    /// TRANSFER_SRC_OPTIMAL.
    pub fn read(&self, previous: Access) -> GpuResult<Vec<u8>> {
        let bytes_per_texel = bytes_per_texel(self.desc.format).ok_or(GpuError::ReadbackFormat(self.desc.format))?;
        let size = self.desc.width as u64 * self.desc.height as u64 * bytes_per_texel;
        let staging =
            Buffer::new(&self.gpu, &BufferDesc::readback("image readback", size, vk::BufferUsageFlags::TRANSFER_DST))?;
        let device = self.gpu.device();
        let aspect = aspect_of(self.desc.format);
        self.gpu.one_shot("image readback", |cmd| {
            ImageBarrier {
                image: self.raw,
                aspect,
                previous: &[previous],
                next: &[Access::TransferRead],
                discard: false,
            }
            .record(device, cmd);
            let region = [vk::BufferImageCopy::default()
                .image_subresource(vk::ImageSubresourceLayers::default().aspect_mask(aspect).layer_count(1))
                .image_extent(vk::Extent3D { width: self.desc.width, height: self.desc.height, depth: 1 })];
            // SAFETY: the staging buffer holds exactly one tightly packed layer.
            unsafe {
                device.cmd_copy_image_to_buffer(
                    cmd,
                    self.raw,
                    vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                    staging.raw(),
                    &region,
                )
            };
            transfer_to_host(device, cmd);
        })?;
        staging.read::<u8>()
    }
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: all submissions wait on their fence, so the image is idle.
        unsafe {
            if self.view != vk::ImageView::null() {
                self.gpu.device().destroy_image_view(self.view, None);
            }
            self.gpu.device().destroy_image(self.raw, None);
        }
        if let Some(a) = self.allocation.take()
            && let Err(e) = self.gpu.allocator().free(a)
        {
            log::error!("freeing image {:?}: {e}", self.desc.name);
        }
    }
}
