//! `Sampler`: a VkSampler destroyed on Drop.

use super::context::Gpu;
use super::error::{GpuResult, VkContext};
use ash::vk;
use std::sync::Arc;

/// A VkSampler. It holds an `Arc<Gpu>` and is destroyed on Drop; no pending submission may use it
/// then.
pub struct Sampler {
    gpu: Arc<Gpu>,
    raw: vk::Sampler,
}

impl Sampler {
    /// Clamp-to-edge sampler, linear or nearest.
    pub fn new(gpu: &Arc<Gpu>, filter: vk::Filter) -> GpuResult<Sampler> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE);
        Self::create(gpu, info)
    }

    /// A depth-compare sampler for shadow maps (`sampler2DArrayShadow`): LESS_OR_EQUAL, border
    /// white (outside the map counts as lit), linear filtering when the format supports it, so
    /// each tap is already a 2x2 percentage-closer filter.
    pub fn shadow(gpu: &Arc<Gpu>, depth_format: vk::Format) -> GpuResult<Sampler> {
        // SAFETY: plain query.
        let props =
            unsafe { gpu.instance().get_physical_device_format_properties(gpu.physical_device(), depth_format) };
        let linear = props.optimal_tiling_features.contains(vk::FormatFeatureFlags::SAMPLED_IMAGE_FILTER_LINEAR);
        let filter = if linear { vk::Filter::LINEAR } else { vk::Filter::NEAREST };
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(filter)
            .min_filter(filter)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_BORDER)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_BORDER)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .border_color(vk::BorderColor::FLOAT_OPAQUE_WHITE)
            .compare_enable(true)
            .compare_op(vk::CompareOp::LESS_OR_EQUAL);
        Self::create(gpu, info)
    }

    fn create(gpu: &Arc<Gpu>, info: vk::SamplerCreateInfo<'_>) -> GpuResult<Sampler> {
        // SAFETY: valid create info; Drop destroys it.
        let raw = unsafe { gpu.device().create_sampler(&info, None) }.vk("vkCreateSampler")?;
        Ok(Sampler { gpu: gpu.clone(), raw })
    }

    /// The Vulkan handle, as `Binding::Image` takes it.
    pub fn raw(&self) -> vk::Sampler {
        self.raw
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no pending submission uses it.
        unsafe { self.gpu.device().destroy_sampler(self.raw, None) };
    }
}
