//! Errors of the GPU core, each saying what to do about it.

use ash::vk;

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "could not load the Vulkan loader (libvulkan.so.1): {0}\n  install it and a driver: \
         `apt-get install libvulkan1 mesa-vulkan-drivers` on Debian/Ubuntu (or run scripts/setup)"
    )]
    LoaderMissing(String),
    #[error(
        "no Vulkan device found{0}\n  install a driver: `apt-get install mesa-vulkan-drivers` gives \
         lavapipe, a CPU implementation (or run scripts/setup); check VK_ICD_FILENAMES/VK_DRIVER_FILES"
    )]
    NoDevice(String),
    #[error("no Vulkan device matches --device {wanted:?}; available devices:\n{available}")]
    DeviceNotFound { wanted: String, available: String },
    #[error("device {name:?} supports Vulkan {version}, translucent needs Vulkan 1.3{detail}")]
    DeviceUnsuitable { name: String, version: String, detail: String },
    #[error(
        "validation was requested but VK_LAYER_KHRONOS_validation is not installed\n  install it: \
         `apt-get install vulkan-validationlayers` (or run scripts/setup)"
    )]
    ValidationLayerMissing,
    #[error("{what} failed: {result}")]
    Vk { what: &'static str, result: vk::Result },
    #[error("GPU memory allocation for {what:?} failed: {source}")]
    Alloc { what: String, source: gpu_allocator::AllocationError },
    #[error("GPU work {what:?} did not finish within {seconds} s (device hung or far too much work)")]
    Timeout { what: String, seconds: f64 },
    #[error("no shader named {0:?} is embedded (shaders are compiled from glsl/ by build.rs)")]
    UnknownShader(String),
    #[error("{what} is {value}, more than this device allows ({limit}, its {name})")]
    Limit { what: String, value: u64, limit: u64, name: &'static str },
    #[error("{0}")]
    Invalid(String),
}

pub type GpuResult<T> = Result<T, GpuError>;

/// Attach a description of the failed call to a raw `vk::Result`.
pub(crate) trait VkContext<T> {
    fn vk(self, what: &'static str) -> GpuResult<T>;
}

impl<T> VkContext<T> for Result<T, vk::Result> {
    fn vk(self, what: &'static str) -> GpuResult<T> {
        self.map_err(|result| GpuError::Vk { what, result })
    }
}
