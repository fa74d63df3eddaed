//! Errors of the GPU core, each saying what to do about it.

use ash::vk;

/// What went wrong in the GPU core. Each message says what to do about it: which package to
/// install, which device or setting to change.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    /// The Vulkan loader (libvulkan.so.1) could not be loaded; holds the loading error.
    #[error(
        "could not load the Vulkan loader (libvulkan.so.1): {0}\n  install it and a driver: \
         `apt-get install libvulkan1 mesa-vulkan-drivers` on Debian/Ubuntu (or run scripts/setup)"
    )]
    LoaderMissing(String),
    /// The loader lists no device, or found no driver; holds detail appended to the message (may be
    /// empty).
    #[error(
        "no Vulkan device found{0}\n  install a driver: `apt-get install mesa-vulkan-drivers` gives \
         lavapipe, a CPU implementation (or run scripts/setup); check VK_ICD_FILENAMES/VK_DRIVER_FILES"
    )]
    NoDevice(String),
    /// `GpuOptions::device` (`--device`) matches no device by index or by name.
    #[error("no Vulkan device matches --device {wanted:?}; available devices:\n{available}")]
    DeviceNotFound {
        /// The index or part of a name that was asked for.
        wanted: String,
        /// One line per device the loader lists, to choose from.
        available: String,
    },
    /// The device lacks something translucent needs: Vulkan 1.3, the shaderOutputLayer feature, a
    /// graphics+compute queue, or (for a host's device) an enabled feature or 1.3 entry points.
    #[error("device {name:?} supports Vulkan {version}, translucent needs Vulkan 1.3{detail}")]
    DeviceUnsuitable {
        /// The device's name.
        name: String,
        /// The Vulkan version it supports.
        version: String,
        /// What else is missing, appended to "needs Vulkan 1.3"; empty when only the version falls
        /// short.
        detail: String,
    },
    /// Validation was asked for (`GpuOptions::validation`) but VK_LAYER_KHRONOS_validation is not
    /// installed.
    #[error(
        "validation was requested but VK_LAYER_KHRONOS_validation is not installed\n  install it: \
         `apt-get install vulkan-validationlayers` (or run scripts/setup)"
    )]
    ValidationLayerMissing,
    /// A Vulkan call returned an error.
    #[error("{what} failed: {result}")]
    Vk {
        /// The Vulkan call that failed, e.g. "vkCreateBuffer".
        what: &'static str,
        /// The VkResult it returned.
        result: vk::Result,
    },
    /// gpu_allocator could not provide memory (or could not be created).
    #[error("GPU memory allocation for {what:?} failed: {source}")]
    Alloc {
        /// The debug name of the buffer or image the memory was for ("allocator" for the allocator
        /// itself).
        what: String,
        /// The allocator's error.
        source: gpu_allocator::AllocationError,
    },
    /// A `Gpu::one_shot` submission did not finish within the timeout; `one_shot` waits for the
    /// device to go idle before returning it, since its command pool must not be destroyed while
    /// the work is pending.
    #[error("GPU work {what:?} did not finish within {seconds} s (device hung or far too much work)")]
    Timeout {
        /// The work, as named to `Gpu::one_shot`.
        what: String,
        /// The timeout that ran out (`GpuOptions::timeout`), in seconds.
        seconds: f64,
    },
    /// No embedded shader has this path under `glsl/`.
    #[error("no shader named {0:?} is embedded (shaders are compiled from glsl/ by build.rs)")]
    UnknownShader(String),
    /// A request exceeds a device limit (a dispatch needing more workgroups than
    /// maxComputeWorkGroupCount allows).
    #[error("{what} is {value}, more than this device allows ({limit}, its {name})")]
    Limit {
        /// What was too large, in the caller's words.
        what: String,
        /// How large it was.
        value: u64,
        /// The most the device allows.
        limit: u64,
        /// The limit's name, in Vulkan's terms.
        name: &'static str,
    },
    /// A descriptor set gives binding `binding` a resource meant for another GLSL name than the
    /// shader declares there (two bindings swapped, or a shader edited without its pass).
    #[error("{shader} binding {binding} is `{declared}` in the GLSL, but the pass binds `{given}` there")]
    BindingMismatch {
        /// The shader (or vertex + fragment pair) the set is for.
        shader: String,
        /// The binding number.
        binding: u32,
        /// The name the GLSL gives that binding (its block or variable name).
        declared: String,
        /// The name of the resource the pass gave for it.
        given: String,
    },
    /// A caller's mistake or malformed input, described in the message: an empty buffer or image, a
    /// write past a buffer's end, a shader interface that does not fit, a device without
    /// timestamps.
    #[error("{0}")]
    Invalid(String),
}

/// The result of every fallible call in the GPU core.
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
