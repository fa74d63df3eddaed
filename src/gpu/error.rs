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
    LoaderMissing(ash::LoadingError),
    /// The loader lists no device.
    #[error(
        "no Vulkan device found\n  install a driver: `apt-get install mesa-vulkan-drivers` gives \
         lavapipe, a CPU implementation (or run scripts/setup); check VK_ICD_FILENAMES/VK_DRIVER_FILES"
    )]
    NoDevice,
    /// The loader found no driver (`vkCreateInstance` answered VK_ERROR_INCOMPATIBLE_DRIVER).
    #[error(
        "no Vulkan device found (the Vulkan loader found no driver)\n  install a driver: `apt-get install \
         mesa-vulkan-drivers` gives lavapipe, a CPU implementation (or run scripts/setup); check \
         VK_ICD_FILENAMES/VK_DRIVER_FILES"
    )]
    NoDriver,
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
        /// What else is missing, appended to "needs Vulkan 1.3".
        detail: Shortfall,
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
    /// `Gpu::seed_pipeline_cache` was given data that cannot seed this device's cache; the cache
    /// stays as it was.
    #[error("pipeline cache data refused: {0}")]
    PipelineCacheRefused(CacheRefusal),
    /// An embedded shader's bytes are not SPIR-V words (a build problem); the cause is the source.
    #[error("embedded shader {shader} is not SPIR-V")]
    NotSpirv {
        /// The shader's path under `glsl/`.
        shader: String,
        /// What reading its words found.
        source: std::io::Error,
    },
    /// An embedded shader's SPIR-V could not be reflected; the cause is the source.
    #[error("reflecting shader {shader}")]
    Reflection {
        /// The shader's path under `glsl/`.
        shader: String,
        /// What the reflection found.
        source: rspirv_reflect::ReflectError,
    },
    /// A shader declares a binding in a descriptor set other than 0.
    #[error("reflecting shader {shader}: uses descriptor set {set}; only set 0 is supported")]
    DescriptorSetNumber {
        /// The shader's path under `glsl/`.
        shader: String,
        /// The set it uses.
        set: u32,
    },
    /// A shader declares a binding of a descriptor type no pass binds.
    #[error("reflecting shader {shader}: binding {binding} has unsupported descriptor type {descriptor_type:?}")]
    DescriptorType {
        /// The shader's path under `glsl/`.
        shader: String,
        /// The binding number.
        binding: u32,
        /// Its descriptor type.
        descriptor_type: rspirv_reflect::DescriptorType,
    },
    /// Two stages of one pipeline give one binding different GLSL names.
    #[error("binding {binding} is `{first}` in one stage and `{second}` in another")]
    StageBindingNames {
        /// The binding number.
        binding: usize,
        /// Its name in the earlier stage.
        first: String,
        /// Its name in the later stage.
        second: String,
    },
    /// Two stages of one pipeline give one binding different descriptor types.
    #[error("binding {binding} is {first:?} in one stage and {second:?} in another")]
    StageBindingTypes {
        /// The binding number.
        binding: usize,
        /// Its type in the earlier stage.
        first: vk::DescriptorType,
        /// Its type in the later stage.
        second: vk::DescriptorType,
    },
    /// A shader's push-constant block is not a whole number of words, or larger than the device
    /// allows.
    #[error(
        "push-constant block of {bytes} bytes is not allowed: it must be a multiple of 4 bytes and at most \
         {limit} (this device's maxPushConstantsSize)"
    )]
    PushConstants {
        /// The block's size.
        bytes: u32,
        /// `maxPushConstantsSize`.
        limit: u32,
    },
    /// A descriptor set given fewer resources than the shader declares bindings.
    #[error("{shader}: the shader declares binding {binding}, only {given} resources were given")]
    MissingBinding {
        /// The shader (or vertex + fragment pair) the set is for.
        shader: String,
        /// The first declared binding without a resource.
        binding: usize,
        /// How many resources were given.
        given: usize,
    },
    /// A descriptor set gives a binding a buffer where the shader declares an image, or the
    /// other way round.
    #[error("binding {binding}: expected {expected:?}")]
    BindingType {
        /// The binding number.
        binding: usize,
        /// The descriptor type the shader declares there.
        expected: vk::DescriptorType,
    },
    /// A buffer of 0 bytes.
    #[error("buffer {name:?} has size 0")]
    EmptyBuffer {
        /// The buffer's debug name.
        name: String,
    },
    /// `Buffer::write` past the buffer's end.
    #[error("write of {bytes} bytes at {offset} overflows buffer {name:?} of {size} bytes")]
    WriteOverflow {
        /// The buffer's debug name.
        name: String,
        /// Where the write starts, in bytes.
        offset: u64,
        /// How many bytes were written.
        bytes: u64,
        /// The buffer's size in bytes.
        size: u64,
    },
    /// `Buffer::read` as items whose size does not divide the buffer's.
    #[error("buffer {name:?} of {size} bytes is not a whole number of items of {item} bytes")]
    ReadItems {
        /// The buffer's debug name.
        name: String,
        /// The buffer's size in bytes.
        size: u64,
        /// The item's size in bytes.
        item: u64,
    },
    /// An image with no texel: a zero width, height or layer count.
    #[error("image {name:?} has an empty extent {}x{}x{}", extent[0], extent[1], extent[2])]
    EmptyImage {
        /// The image's debug name.
        name: String,
        /// Its width, height and layers.
        extent: [u32; 3],
    },
    /// `Image::read` of a format it cannot read back.
    #[error("reading back {0:?} images is not supported")]
    ReadbackFormat(vk::Format),
    /// A `GpuTimer` on a device whose queue writes no timestamps (`timestampValidBits` 0).
    #[error("device {device} cannot write timestamps on its queue")]
    NoTimestamps {
        /// The device's name.
        device: String,
    },
    /// `Gpu::from_host` with a physical device its instance does not list.
    #[error("the host's physical device is not one of its instance's")]
    ForeignPhysicalDevice,
    /// A pass made over frame targets without the renderer's own images it reads (a host
    /// target's renderer has none).
    #[error("the {pass} needs the renderer's own {images}")]
    MissingImages {
        /// The pass.
        pass: &'static str,
        /// The images it needs.
        images: &'static str,
    },
    /// A binding asked of a renderer's shared resources for a resource they do not hold (a
    /// pass's own, or a camera image of a host target).
    #[error("`{resource}` is not a shared resource of this renderer")]
    NotShared {
        /// The resource's GLSL name.
        resource: &'static str,
    },
}

/// What a device lacks besides (or instead of) Vulkan 1.3 ([`GpuError::DeviceUnsuitable`]); its
/// Display continues "translucent needs Vulkan 1.3".
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Shortfall {
    /// Only the Vulkan version falls short.
    #[error("")]
    Version,
    /// No queue family does graphics and compute.
    #[error(" and a queue that does graphics and compute; it has none")]
    NoQueue,
    /// The device does not support `shaderOutputLayer`.
    #[error(" and the shaderOutputLayer feature (layered shadow maps); it lacks it")]
    ShaderOutputLayer,
    /// A host's device created without these required features (`HostVulkan::enabled_features`).
    #[error(
        " with the {} {} enabled at device creation; the host's device was created without {} (chain \
         translucent::gpu::required_features() into VkDeviceCreateInfo)",
        .0.join(", "),
        if .0.len() == 1 { "feature" } else { "features" },
        if .0.len() == 1 { "it" } else { "them" }
    )]
    FeaturesNotEnabled(Vec<&'static str>),
    /// A host's instance created for a Vulkan version older than 1.3: this 1.3 command cannot be
    /// loaded on its device.
    #[error(
        " through an instance created with apiVersion 1.3 or later; {} is not available on the host's device \
         (its instance asked for an older version)",
        .0.to_string_lossy()
    )]
    InstanceVersion(&'static std::ffi::CStr),
    /// A host's queue family that does not do graphics and compute.
    #[error(" and a queue that does graphics and compute; the host's queue family {0} does not")]
    HostQueue(u32),
    /// A host's queue family index past the device's families.
    #[error(
        " and a queue that does graphics and compute; the host's queue family {given} does not exist (the device has \
         {families} {}, 0 to {})",
        if *families == 1 { "family" } else { "families" },
        families.saturating_sub(1)
    )]
    NoSuchQueueFamily {
        /// The family index the host gave.
        given: u32,
        /// How many families the device has.
        families: u32,
    },
}

/// Why `Gpu::seed_pipeline_cache` refused its data (`VkPipelineCacheHeaderVersionOne` read from
/// its first 32 bytes).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum CacheRefusal {
    /// Fewer bytes than the header.
    #[error("{bytes} bytes, shorter than its 32-byte header")]
    TooShort {
        /// How many bytes were given.
        bytes: usize,
    },
    /// A header size below 32 bytes, or a header version other than one.
    #[error("header of {header_bytes} bytes, version {version}: not a Vulkan pipeline cache")]
    NotACache {
        /// The header's size field.
        header_bytes: u32,
        /// The header's version field.
        version: u32,
    },
    /// Made on another vendor's or another model's device.
    #[error("made by vendor {vendor:#x} device {device:#x}, this is vendor {this_vendor:#x} device {this_device:#x}")]
    OtherDevice {
        /// The header's vendor ID.
        vendor: u32,
        /// The header's device ID.
        device: u32,
        /// This device's vendor ID.
        this_vendor: u32,
        /// This device's device ID.
        this_device: u32,
    },
    /// Made by another driver build: the header's pipelineCacheUUID is not this device's.
    #[error("made by another driver build (pipelineCacheUUID)")]
    OtherDriver,
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
