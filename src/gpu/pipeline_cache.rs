//! The pipeline cache every pipeline of a `Gpu` is created through (`vkCreatePipelineCache`).
//! A host saves it (`Gpu::pipeline_cache_data`) and seeds a later run with it
//! (`Gpu::seed_pipeline_cache`), so the driver skips the shader compilation it did before.
//! Lavapipe (Mesa 22.3) keeps nothing past the 32-byte header, so there it saves nothing.

use super::context::Gpu;
use super::error::{GpuError, GpuResult};
use ash::vk;

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
fn refusal(data: &[u8], properties: &vk::PhysicalDeviceProperties) -> Option<String> {
    if data.len() < HEADER_BYTES {
        return Some(format!("{} bytes, shorter than its 32-byte header", data.len()));
    }
    let word = |i: usize| u32::from_le_bytes(data[4 * i..4 * i + 4].try_into().unwrap());
    let (size, version, vendor, device) = (word(0), word(1), word(2), word(3));
    if (size as usize) < HEADER_BYTES || version != vk::PipelineCacheHeaderVersion::ONE.as_raw() as u32 {
        return Some(format!("header of {size} bytes, version {version}: not a Vulkan pipeline cache"));
    }
    if vendor != properties.vendor_id || device != properties.device_id {
        return Some(format!(
            "made by vendor {vendor:#x} device {device:#x}, this is vendor {:#x} device {:#x}",
            properties.vendor_id, properties.device_id
        ));
    }
    (data[16..32] != properties.pipeline_cache_uuid).then(|| "made by another driver build (pipelineCacheUUID)".into())
}

impl Gpu {
    /// The pipeline cache's contents (`vkGetPipelineCacheData`), to save and pass to
    /// [`Gpu::seed_pipeline_cache`] in a later run on the same device and driver.
    pub fn pipeline_cache_data(&self) -> GpuResult<Vec<u8>> {
        let cache = self.pipeline_cache.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: the cache is live and the lock keeps merges out.
        unsafe { self.device().get_pipeline_cache_data(*cache) }
            .map_err(|result| GpuError::Vk { what: "vkGetPipelineCacheData", result })
    }

    /// Merge `data` (from [`Gpu::pipeline_cache_data`] of an earlier run) into this `Gpu`'s
    /// pipeline cache, so that pipelines created afterwards reuse what it holds. Data from
    /// another device or driver build, or not a pipeline cache, is refused with an error saying
    /// which, and the cache stays as it was.
    pub fn seed_pipeline_cache(&self, data: &[u8]) -> GpuResult<()> {
        if let Some(why) = refusal(data, self.properties()) {
            return Err(GpuError::Invalid(format!("pipeline cache data refused: {why}")));
        }
        let info = vk::PipelineCacheCreateInfo::default().initial_data(data);
        // SAFETY: `data` outlives the call; the header was checked against this device.
        let source = unsafe { self.device().create_pipeline_cache(&info, None) }
            .map_err(|result| GpuError::Vk { what: "vkCreatePipelineCache", result })?;
        let cache = self.pipeline_cache.lock().unwrap_or_else(|e| e.into_inner());
        // SAFETY: the lock gives the merge's destination the external synchronisation it needs.
        let merged = unsafe { self.device().merge_pipeline_caches(*cache, &[source]) };
        // SAFETY: the source cache was used by the merge alone, which has returned.
        unsafe { self.device().destroy_pipeline_cache(source, None) };
        merged.map_err(|result| GpuError::Vk { what: "vkMergePipelineCaches", result })
    }
}
