//! The Vulkan core (ash), one Vulkan concept per file: instance (loader, validation), debug
//! (messenger and message counts), features (what a device must enable), device (choice and
//! logical device), pipeline_cache (the cache every pipeline is created through), context
//! (`Gpu`), buffer, image, sampler, descriptor, pipeline, command (one-shot submission), barrier,
//! hazard (barriers derived from declared accesses), timer, shaders.
//!
//! Every Vulkan object is owned by a Rust value that destroys it on Drop and holds an
//! `Arc<Gpu>`, so the device always outlives what was made from it.

mod barrier;
mod buffer;
mod command;
mod context;
mod counter;
mod debug;
mod descriptor;
mod device;
mod error;
mod features;
mod hazard;
mod image;
mod instance;
mod pipeline;
mod pipeline_cache;
mod sampler;
pub mod shaders;
pub use shaders::ShaderInterface;
mod timer;

pub(crate) use barrier::image_transition;
pub use barrier::{Access, ImageBarrier, memory_barrier};
pub use buffer::{Buffer, BufferDesc};
pub use context::{Gpu, HostVulkan};
pub use counter::{RecordCounter, RecordCounts};
pub use debug::ValidationCounters;
pub use descriptor::{Binding, BindingKind, DescriptorSet, Named};
pub use device::{DeviceInfo, select as select_device};
pub use error::{CacheRefusal, GpuError, GpuResult, Shortfall};
pub use features::{EnabledFeatures, RequiredFeatures, required_features};
pub use gpu_allocator::MemoryLocation;
pub use hazard::{Hazards, Use};
pub use image::{Image, ImageDesc, aspect_of};
pub use pipeline::{ComputePipeline, GraphicsDesc, GraphicsPipeline};
pub use sampler::Sampler;
pub use timer::{GpuTimer, median};

use std::time::Duration;

/// How to build a `Gpu`.
#[derive(Clone, Debug)]
pub struct GpuOptions {
    /// Device index or part of its name; `None` picks a discrete/integrated GPU, else the CPU device.
    pub device: Option<String>,
    /// Enable the Khronos validation layer and count its messages.
    pub validation: bool,
    /// With `validation`, also the layer's synchronisation validation (`validate_sync`): every
    /// missing or too-weak barrier is a message. Slow; for tests of the barriers.
    pub sync_validation: bool,
    /// How long one submission may run before it is reported as hung.
    pub timeout: Duration,
}

impl Default for GpuOptions {
    fn default() -> Self {
        Self { device: None, validation: false, sync_validation: false, timeout: Duration::from_secs(120) }
    }
}

/// Every Vulkan device visible to the loader, without creating a logical device.
pub fn list_devices() -> GpuResult<Vec<DeviceInfo>> {
    let entry = instance::load_entry()?;
    let counters = std::sync::Arc::new(ValidationCounters::default());
    let mut owned = instance::create_instance(&entry, false, false, &counters)?;
    let devices = device::enumerate(&owned.instance);
    // SAFETY: nothing was created from this instance.
    unsafe { owned.destroy() };
    devices
}
