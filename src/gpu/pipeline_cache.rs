//! The pipeline cache every pipeline of a `Gpu` is created through (`vkCreatePipelineCache`).
//! A host saves it (`Gpu::pipeline_cache_data`) and seeds a later run with it
//! (`Gpu::seed_pipeline_cache`), so the driver skips the shader compilation it did before.
//! Lavapipe (Mesa 22.3) keeps nothing past the 32-byte header, so there it saves nothing.
//!
//! Free functions over the device and the cache handle, below `context` (whose `impl Gpu`
//! wraps them): this module needs no `Gpu`.

use super::error::{CacheRefusal, GpuError, GpuResult};
use ash::vk;
use std::sync::Mutex;

/// Bytes of `VkPipelineCacheHeaderVersionOne`: header size, version, vendor, device, UUID.
const HEADER_BYTES: usize = 32;

/// An empty pipeline cache on `device`.
pub(super) fn create(device: &ash::Device) -> GpuResult<vk::PipelineCache> {
    // SAFETY: a plain create call on a live device.
    unsafe { device.create_pipeline_cache(&vk::PipelineCacheCreateInfo::default(), None) }
        .map_err(|result| GpuError::Vk { what: "vkCreatePipelineCache", result })
}

/// Why `data` cannot seed a cache on a device with `properties`, if it cannot: too short, not
/// header version one, or made by another vendor, device or driver build (pipelineCacheUUID).
fn refusal(data: &[u8], properties: &vk::PhysicalDeviceProperties) -> Option<CacheRefusal> {
    if data.len() < HEADER_BYTES {
        return Some(CacheRefusal::TooShort { bytes: data.len() });
    }
    let word = |i: usize| u32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let (size, version, vendor, device) = (word(0), word(1), word(2), word(3));
    if (size as usize) < HEADER_BYTES || version != vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32 {
        return Some(CacheRefusal::NotACache { header_bytes: size, version });
    }
    if vendor != properties.vendor_id || device != properties.device_id {
        return Some(CacheRefusal::OtherDevice {
            vendor,
            device,
            this_vendor: properties.vendor_id,
            this_device: properties.device_id,
        });
    }
    (data[16..32] != properties.pipeline_cache_uuid).then_some(CacheRefusal::OtherDriver)
}

/// The contents of `cache` (`vkGetPipelineCacheData`), read under its lock.
///
/// # Safety
/// `cache` holds a pipeline cache created on `device` (by [`create`]), and both are live.
pub(super) unsafe fn data(device: &ash::Device, cache: &Mutex<vk::PipelineCache>) -> GpuResult<Vec<u8>> {
    let cache = cache.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the caller's contract makes the cache and device live; the lock keeps merges out.
    unsafe { device.get_pipeline_cache_data(*cache) }
        .map_err(|result| GpuError::Vk { what: "vkGetPipelineCacheData", result })
}

/// Merge `data` into `cache`, after checking its header against `properties` (the device's):
/// refused data leaves the cache as it was.
///
/// # Safety
/// `cache` holds a pipeline cache created on `device` (by [`create`]), both are live, and
/// `properties` are those of `device`'s physical device.
pub(super) unsafe fn seed(
    device: &ash::Device,
    properties: &vk::PhysicalDeviceProperties,
    cache: &Mutex<vk::PipelineCache>,
    data: &[u8],
) -> GpuResult<()> {
    if let Some(why) = refusal(data, properties) {
        return Err(GpuError::PipelineCacheRefused(why));
    }
    let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
    // SAFETY: `data` outlives the call; the header was checked against this device.
    let source = unsafe { device.create_pipeline_cache(&info, None) }
        .map_err(|result| GpuError::Vk { what: "vkCreatePipelineCache", result })?;
    let cache = cache.lock().unwrap_or_else(|e| e.into_inner());
    // SAFETY: the lock gives the merge's destination the external synchronisation it needs; the
    // caller's contract makes it a live cache of `device`.
    let merged = unsafe { device.merge_pipeline_caches(*cache, &[source]) };
    // SAFETY: the source cache was used by the merge alone, which has returned.
    unsafe { device.destroy_pipeline_cache(source, None) };
    merged.map_err(|result| GpuError::Vk { what: "vkMergePipelineCaches", result })
}
