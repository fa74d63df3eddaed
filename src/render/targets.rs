//! `FrameTargets`: the images a frame renders into and reads between passes: the shadow-map
//! array, and the camera's own HDR, depth and (pixel gather) surface images. They live apart from
//! the passes that write them, in the registry (`graph::Resources`), so a pass that reads one
//! binds it by name like any scene buffer.

use super::resource::Resource;
use crate::gpu::{Access, Binding, Gpu, GpuResult, Hazards, Image, ImageBarrier, ImageDesc, Sampler};
use ash::vk;
use std::sync::Arc;

/// Format of the shadow maps: 16-bit depth, sampled through a compare sampler.
pub const SHADOW_FORMAT: vk::Format = vk::Format::D16_UNORM;
/// Format of the own HDR target: linear radiance, RGBA32F. With the pixel gather its alpha holds
/// the factor gather_pixel.comp multiplies exitance by; otherwise 1.
pub const HDR_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Pixel gather only: world position and translucent object of each pixel.
pub const SURFACE_FORMAT: vk::Format = vk::Format::R32G32B32A32_SFLOAT;
/// Format of the own camera depth.
pub const CAMERA_DEPTH_FORMAT: vk::Format = vk::Format::D32_SFLOAT;

/// The camera's own images (a renderer with its own target).
pub struct CameraTargets {
    /// Linear radiance; sampled by the tone map, a storage image for the pixel gather.
    pub hdr: Image,
    /// Depth of the camera's view.
    pub depth: Image,
    /// Pixel gather only: each pixel's world position and object.
    pub surface: Option<Image>,
}

impl CameraTargets {
    /// The images at `[width, height]`; `surface` for the pixel gather.
    pub fn new(gpu: &Arc<Gpu>, [width, height]: [u32; 2], surface: bool) -> GpuResult<CameraTargets> {
        use vk::ImageUsageFlags as U;
        let image = |name, format, usage| Image::new(gpu, &ImageDesc::new(name, width, height, format, usage));
        Ok(CameraTargets {
            // STORAGE: the pixel gather adds its exitance in place.
            hdr: image("hdr radiance", HDR_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED | U::STORAGE)?,
            depth: image("camera depth", CAMERA_DEPTH_FORMAT, U::DEPTH_STENCIL_ATTACHMENT)?,
            surface: surface.then(|| image("surface", SURFACE_FORMAT, U::COLOR_ATTACHMENT | U::SAMPLED)).transpose()?,
        })
    }
}

/// The frame's images: shadow maps always, camera images for an own target.
pub struct FrameTargets {
    /// One D16 layer per shadow map (at least one, so it always binds).
    pub shadow_maps: Image,
    shadow_sampler: Sampler,
    /// Nearest-texel sampler for compute reads of the camera images.
    nearest: Sampler,
    /// The camera's own images; `None` for a host target.
    pub camera: Option<CameraTargets>,
}

impl FrameTargets {
    /// `layers` shadow maps of `map_size`^2 texels, cleared to the far plane (everything lit)
    /// so that passes sampling them are valid even when no frame renders them, and the camera
    /// images when `camera` gives their size and whether a surface image is needed.
    pub fn new(
        gpu: &Arc<Gpu>,
        map_size: u32,
        layers: u32,
        camera: Option<([u32; 2], bool)>,
    ) -> GpuResult<FrameTargets> {
        use vk::ImageUsageFlags as U;
        let usage = U::DEPTH_STENCIL_ATTACHMENT | U::SAMPLED | U::TRANSFER_DST;
        let desc = ImageDesc::new("shadow maps", map_size, map_size, SHADOW_FORMAT, usage).layers(layers.max(1));
        let shadow_maps = Image::new(gpu, &desc.array_view())?;
        clear_to_far(gpu, &shadow_maps)?;
        Ok(FrameTargets {
            shadow_maps,
            shadow_sampler: Sampler::shadow(gpu, SHADOW_FORMAT)?,
            nearest: Sampler::new(gpu, vk::Filter::NEAREST)?,
            camera: camera.map(|(size, surface)| CameraTargets::new(gpu, size, surface)).transpose()?,
        })
    }

    /// Register every image with `hazards` in the state its creation left it.
    pub fn track(&self, hazards: &mut Hazards<Resource>) {
        let depth = vk::ImageAspectFlags::DEPTH;
        hazards.image(Resource::ShadowMaps, self.shadow_maps.raw(), depth, Access::ComputeSampledRead);
        self.track_camera(hazards);
    }

    /// Register the camera images with `hazards`, new (after `CameraTargets::new`).
    pub fn track_camera(&self, hazards: &mut Hazards<Resource>) {
        let depth = vk::ImageAspectFlags::DEPTH;
        if let Some(c) = &self.camera {
            let color = vk::ImageAspectFlags::COLOR;
            hazards.image(Resource::Hdr, c.hdr.raw(), color, Access::Nothing);
            hazards.image(Resource::CameraDepth, c.depth.raw(), depth, Access::Nothing);
            if let Some(s) = &c.surface {
                hazards.image(Resource::Surface, s.raw(), color, Access::Nothing);
            }
        }
    }

    /// The own HDR image, if any.
    pub fn hdr(&self) -> Option<&Image> {
        self.camera.as_ref().map(|c| &c.hdr)
    }

    /// The pixel gather's surface image, if any.
    pub fn surface(&self) -> Option<&Image> {
        self.camera.as_ref().and_then(|c| c.surface.as_ref())
    }

    /// A target image as a descriptor binding, in the layout its shader reads it in: the shadow
    /// maps with their compare sampler, the HDR and surface images sampled (nearest), or the HDR
    /// image as a storage image (`Resource::Hdr` bound by the pixel gather, `storage_hdr`).
    pub fn binding(&self, resource: Resource) -> Option<Binding<'_>> {
        let sampled = |image: &Image, sampler: &Sampler| Binding::Image {
            view: image.view(),
            layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
            sampler: sampler.raw(),
        };
        match resource {
            Resource::ShadowMaps => Some(sampled(&self.shadow_maps, &self.shadow_sampler)),
            Resource::Hdr => self.hdr().map(|i| sampled(i, &self.nearest)),
            Resource::Surface => self.surface().map(|i| sampled(i, &self.nearest)),
            _ => None,
        }
    }

    /// The HDR image as a storage image (GENERAL), as the pixel gather adds into it.
    pub fn storage_hdr(&self) -> Option<Binding<'_>> {
        self.hdr().map(|i| Binding::Image {
            view: i.view(),
            layout: vk::ImageLayout::GENERAL,
            sampler: vk::Sampler::null(),
        })
    }
}

/// Clear every layer of `maps` to depth 1 and leave it readable by fragment and compute shaders
/// (one submission, waited for).
fn clear_to_far(gpu: &Arc<Gpu>, maps: &Image) -> GpuResult<()> {
    let device = gpu.device();
    let depth = vk::ImageAspectFlags::DEPTH;
    let readers = [Access::FragmentSampledRead, Access::ComputeSampledRead];
    gpu.one_shot("shadow map init", |cmd| {
        ImageBarrier::new(maps.raw(), depth, &[Access::Nothing], &[Access::TransferWrite]).record(device, cmd);
        let range = [vk::ImageSubresourceRange::default()
            .aspect_mask(depth)
            .level_count(1)
            .layer_count(vk::REMAINING_ARRAY_LAYERS)];
        let far = vk::ClearDepthStencilValue { depth: 1.0, stencil: 0 };
        // SAFETY: the image is in TRANSFER_DST_OPTIMAL and has TRANSFER_DST usage.
        unsafe {
            device.cmd_clear_depth_stencil_image(cmd, maps.raw(), vk::ImageLayout::TRANSFER_DST_OPTIMAL, &far, &range)
        };
        ImageBarrier::new(maps.raw(), depth, &[Access::TransferWrite], &readers).record(device, cmd);
    })
}
