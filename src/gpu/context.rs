//! `Gpu`: the instance, device, queue and memory allocator every pass works through.
//!
//! Nothing global: a `Gpu` is either built here (and destroys what it built) or wrapped around
//! the instance, device and queue of a host engine (`Gpu::from_host`), which it never destroys.

use super::GpuOptions;
use super::debug::ValidationCounters;
use super::device::{self, DeviceInfo};
use super::error::{GpuError, GpuResult, Shortfall, VkContext};
use super::features::EnabledFeatures;
use super::instance::{self, OwnedInstance};
use super::pipeline_cache;
use ash::vk;
use gpu_allocator::vulkan::{Allocator, AllocatorCreateDesc};
use std::mem::ManuallyDrop;
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Duration;

/// The instance, physical and logical device, the one graphics+compute queue and the gpu_allocator
/// allocator that every buffer, image and pipeline is made through. Built by `Gpu::new` (then it
/// owns and destroys the instance and device) or wrapped around a host's by `Gpu::from_host` (then
/// it destroys neither).
///
/// Shared as `Arc<Gpu>`: every object made from it holds a clone, so the `Gpu` drops last.
///
/// **Drop calls `vkDeviceWaitIdle`**, once, when the last `Arc` goes: on a host's device that
/// waits for the host's work on every queue too. Then it frees the allocator's memory, and
/// destroys the device and the instance when it owns them (never a host's).
pub struct Gpu {
    entry: ash::Entry,
    instance: ash::Instance,
    /// `Some` when this `Gpu` created the instance and must destroy it.
    owned_instance: Option<OwnedInstance>,
    device: ash::Device,
    owns_device: bool,
    info: DeviceInfo,
    queue: Mutex<vk::Queue>,
    queue_family: u32,
    timestamp_valid_bits: u32,
    timestamp_period_ns: f64,
    properties: vk::PhysicalDeviceProperties,
    allocator: ManuallyDrop<Mutex<Allocator>>,
    counters: Arc<ValidationCounters>,
    recorded: super::RecordCounter,
    timeout: Duration,
    /// Every pipeline is created through it (`pipeline_cache.rs`); locked for merges.
    pub(super) pipeline_cache: Mutex<vk::PipelineCache>,
}

/// Vulkan objects owned by a host engine, for `Gpu::from_host`.
pub struct HostVulkan {
    /// The loader the host's instance was created with.
    pub entry: ash::Entry,
    /// Created with `apiVersion` 1.3 or later.
    pub instance: ash::Instance,
    /// The physical device `device` was created on.
    pub physical_device: vk::PhysicalDevice,
    /// Created with the features of `required_features` enabled (chain them into its
    /// `VkDeviceCreateInfo`), and declared so in `enabled_features`.
    pub device: ash::Device,
    /// A queue that supports graphics and compute. Submissions from `Gpu` lock an internal mutex;
    /// the host must not submit to the same queue concurrently.
    pub queue: vk::Queue,
    /// The family `queue` belongs to.
    pub queue_family: u32,
    /// Which of the required features the host enabled when it created `device` (Vulkan cannot
    /// be asked afterwards); `from_host` refuses a device that lacks one.
    pub enabled_features: EnabledFeatures,
}

impl Gpu {
    /// Load Vulkan, create an instance (with validation if asked), choose a device, and create
    /// a logical device with one graphics+compute queue.
    pub fn new(options: &GpuOptions) -> GpuResult<Arc<Gpu>> {
        let entry = instance::load_entry()?;
        let counters = Arc::new(ValidationCounters::default());
        let mut owned = instance::create_instance(&entry, options.validation, options.sync_validation, &counters)?;
        // From here on, destroy the instance if anything fails.
        let built = (|| {
            let devices = device::enumerate(&owned.instance)?;
            let info = device::select(&devices, options.device.as_deref())?;
            let (family, _) = device::queue_family(&owned.instance, &info)?;
            device::check_features(&owned.instance, &info)?;
            let device = device::create_logical(&owned.instance, &info, family)?;
            Ok::<_, GpuError>((info, family, device))
        })();
        let (info, family, device) = match built {
            Ok(v) => v,
            Err(e) => {
                // SAFETY: nothing created from the instance survives the closure above.
                unsafe { owned.destroy() };
                return Err(e);
            }
        };
        // SAFETY: queue 0 of `family` was requested in create_logical.
        let queue = unsafe { device.get_device_queue(family, 0) };
        let instance = owned.instance.clone();
        let parts = HostVulkan {
            entry,
            instance,
            physical_device: info.handle,
            device,
            queue,
            queue_family: family,
            enabled_features: EnabledFeatures::ALL,
        };
        Self::assemble(parts, Some(owned), counters, options)
    }

    /// Wrap Vulkan objects a host engine owns. Nothing of theirs is destroyed on Drop; only what
    /// this `Gpu` allocates (memory, buffers, pipelines) is freed.
    ///
    /// Checks, before anything is made, and answers `DeviceUnsuitable` naming what is missing:
    /// the device's Vulkan version (1.3), the instance's (its 1.3 commands must be loadable),
    /// the features declared in `enabled_features` and their support, and the queue family's
    /// graphics and compute capability.
    ///
    /// ```no_run
    /// use translucent::ash::{self, vk};
    /// use translucent::{EnabledFeatures, Gpu, GpuOptions, HostVulkan};
    /// # fn engine() -> (ash::Entry, ash::Instance, vk::PhysicalDevice, ash::Device, vk::Queue, u32) {
    /// #     unimplemented!()
    /// # }
    /// # fn main() -> Result<(), Box<dyn std::error::Error>> {
    /// // The engine's own objects: its device was created from a Vulkan 1.3 instance with
    /// // `translucent::required_features()` chained into its VkDeviceCreateInfo.
    /// let (entry, instance, physical_device, device, queue, queue_family) = engine();
    /// let enabled_features = EnabledFeatures::ALL;
    /// let host = HostVulkan { entry, instance, physical_device, device, queue, queue_family, enabled_features };
    /// // SAFETY: the engine's instance, device and queue outlive the Gpu and all made from it, and
    /// // it enabled the features it declares.
    /// let gpu = unsafe { Gpu::from_host(host, &GpuOptions::default()) }?;
    /// # Ok(()) }
    /// ```
    ///
    /// # Safety
    /// The host's instance, device and queue must outlive the returned `Gpu` and everything made
    /// from it, and `enabled_features` must say truly what the device was created with.
    pub unsafe fn from_host(host: HostVulkan, options: &GpuOptions) -> GpuResult<Arc<Gpu>> {
        let devices = device::enumerate(&host.instance)?;
        let info =
            devices.into_iter().find(|d| d.handle == host.physical_device).ok_or(GpuError::ForeignPhysicalDevice)?;
        let unsuitable = |detail: Shortfall| GpuError::DeviceUnsuitable {
            name: info.name.clone(),
            version: info.api_version.clone(),
            detail,
        };
        if info.api < vk::API_VERSION_1_3 {
            return Err(unsuitable(Shortfall::Version));
        }
        device::check_features(&host.instance, &info)?;
        let f = host.enabled_features;
        // Every missing feature in one error: a host fixes its device creation once.
        let missing: Vec<&'static str> = [
            (f.dynamic_rendering, "dynamicRendering"),
            (f.synchronization2, "synchronization2"),
            (f.shader_output_layer, "shaderOutputLayer"),
        ]
        .into_iter()
        .filter_map(|(enabled, name)| (!enabled).then_some(name))
        .collect();
        if !missing.is_empty() {
            return Err(unsuitable(Shortfall::FeaturesNotEnabled(missing)));
        }
        // A device of an instance created for Vulkan 1.2 has no 1.3 commands, whatever the
        // hardware supports; ash would abort on the first call.
        for command in [c"vkCmdPipelineBarrier2", c"vkCmdBeginRendering", c"vkQueueSubmit2", c"vkCmdWriteTimestamp2"] {
            // SAFETY: a plain lookup on the host's live device.
            let found =
                unsafe { (host.instance.fp_v1_0().get_device_proc_addr)(host.device.handle(), command.as_ptr()) };
            if found.is_none() {
                return Err(unsuitable(Shortfall::InstanceVersion(command)));
            }
        }
        // SAFETY: plain query.
        let families = unsafe { host.instance.get_physical_device_queue_family_properties(info.handle) };
        let Some(family) = families.get(host.queue_family as usize) else {
            let families = families.len() as u32;
            return Err(unsuitable(Shortfall::NoSuchQueueFamily { given: host.queue_family, families }));
        };
        if !family.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE) {
            return Err(unsuitable(Shortfall::HostQueue(host.queue_family)));
        }
        let counters = Arc::new(ValidationCounters::default());
        Self::assemble(HostVulkan { physical_device: info.handle, ..host }, None, counters, options)
    }

    /// The `Gpu` over `parts`; with `owned_instance` it owns (and destroys) the instance and
    /// the device, without it they are the host's.
    fn assemble(
        parts: HostVulkan,
        owned_instance: Option<OwnedInstance>,
        counters: Arc<ValidationCounters>,
        options: &GpuOptions,
    ) -> GpuResult<Arc<Gpu>> {
        let HostVulkan { entry, instance, physical_device: physical, device, queue, queue_family, .. } = parts;
        let owns_device = owned_instance.is_some();
        let info = device::enumerate(&instance)?.into_iter().find(|d| d.handle == physical).unwrap();
        // SAFETY: plain queries.
        let properties = unsafe { instance.get_physical_device_properties(physical) };
        // SAFETY: plain query on `physical`, a physical device of the live `instance`.
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let timestamp_valid_bits = families.get(queue_family as usize).map(|f| f.timestamp_valid_bits).unwrap_or(0);
        let allocator = Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: physical,
            debug_settings: Default::default(),
            buffer_device_address: false,
            allocation_sizes: Default::default(),
        });
        let allocator = match allocator {
            Ok(a) => a,
            Err(source) => {
                // SAFETY: nothing else was created from this device or instance.
                unsafe { abandon(&device, owned_instance) };
                return Err(GpuError::Alloc { what: "allocator".into(), source });
            }
        };
        let pipeline_cache = match pipeline_cache::create(&device) {
            Ok(c) => c,
            Err(e) => {
                drop(allocator);
                // SAFETY: nothing else was created from this device or instance but the
                // allocator, which is gone.
                unsafe { abandon(&device, owned_instance) };
                return Err(e);
            }
        };
        Ok(Arc::new(Gpu {
            pipeline_cache: Mutex::new(pipeline_cache),
            entry,
            instance,
            owned_instance,
            device,
            owns_device,
            info,
            queue: Mutex::new(queue),
            queue_family,
            timestamp_valid_bits,
            timestamp_period_ns: properties.limits.timestamp_period as f64,
            properties,
            allocator: ManuallyDrop::new(Mutex::new(allocator)),
            counters,
            recorded: Default::default(),
            timeout: options.timeout,
        }))
    }

    /// The Vulkan loader's entry points (ours, or the host's).
    pub fn entry(&self) -> &ash::Entry {
        &self.entry
    }
    /// The Vulkan instance (ours, or the host's), for physical-device queries.
    pub fn instance(&self) -> &ash::Instance {
        &self.instance
    }
    /// The logical device every object is created on and every command is recorded through.
    pub fn device(&self) -> &ash::Device {
        &self.device
    }
    /// The physical device in use, for format, feature and memory queries.
    pub fn physical_device(&self) -> vk::PhysicalDevice {
        self.info.handle
    }
    /// Name, type, driver and Vulkan version of the device in use.
    pub fn info(&self) -> &DeviceInfo {
        &self.info
    }
    /// The physical device's properties, read once; its `limits` bound push-constant sizes,
    /// dispatches and images.
    pub fn properties(&self) -> &vk::PhysicalDeviceProperties {
        &self.properties
    }
    /// The family of the queue in use; command pools are created for it.
    pub fn queue_family(&self) -> u32 {
        self.queue_family
    }
    /// The queue, locked: Vulkan requires external synchronisation of vkQueueSubmit. A caller
    /// of `Gpu::new` that records frames into its own command buffers submits them here; a host
    /// (`from_host`) may too, and must hold this lock whenever it submits to the same queue
    /// from another thread while translucent may submit (docs/GPU.md, "queue use").
    pub fn queue(&self) -> MutexGuard<'_, vk::Queue> {
        self.queue.lock().unwrap_or_else(|p| p.into_inner())
    }
    /// Block until the queue has finished everything submitted to it (`vkQueueWaitIdle`).
    pub(crate) fn wait_queue_idle(&self) -> GpuResult<()> {
        let queue = self.queue();
        // SAFETY: the queue is externally synchronised by the guard.
        unsafe { self.device.queue_wait_idle(*queue) }.vk("vkQueueWaitIdle")
    }
    pub(crate) fn allocator(&self) -> MutexGuard<'_, Allocator> {
        self.allocator.lock().unwrap_or_else(|p| p.into_inner())
    }
    /// Validation messages counted so far (all zero when validation is off). The counters
    /// outlive the `Gpu`, so messages sent while the device is destroyed (leaks) are counted.
    pub fn validation(&self) -> Arc<ValidationCounters> {
        self.counters.clone()
    }
    /// Dispatches and draws recorded through this device's pipelines, per shader.
    pub fn recorded(&self) -> super::RecordCounts {
        self.recorded.snapshot()
    }
    /// Count one command recorded by `shader`'s pipeline (the pipelines call it).
    pub(super) fn count_recorded(&self, shader: &str) {
        self.recorded.add(shader)
    }
    /// Whether this `Gpu` created its instance with the validation layer and messenger
    /// (`GpuOptions::validation`). Always false over a host's instance, whatever layers the host
    /// enabled.
    pub fn validation_enabled(&self) -> bool {
        self.owned_instance.as_ref().is_some_and(|o| o.debug.is_some())
    }
    /// Nanoseconds per timestamp tick, and how many low bits of a timestamp are valid.
    pub fn timestamp_info(&self) -> (f64, u32) {
        (self.timestamp_period_ns, self.timestamp_valid_bits)
    }
    /// How long a submission may run before `one_shot` gives up.
    pub fn timeout(&self) -> Duration {
        self.timeout
    }
    /// The pipeline cache's contents (`vkGetPipelineCacheData`), to save and pass to
    /// [`Gpu::seed_pipeline_cache`] in a later run on the same device and driver.
    pub fn pipeline_cache_data(&self) -> GpuResult<Vec<u8>> {
        // SAFETY: the cache was created on this `Gpu`'s device by `assemble`, and both live as
        // long as `self`.
        unsafe { pipeline_cache::data(&self.device, &self.pipeline_cache) }
    }

    /// Merge `data` (from [`Gpu::pipeline_cache_data`] of an earlier run) into this `Gpu`'s
    /// pipeline cache, so that pipelines created afterwards reuse what it holds. Data from
    /// another device or driver build, or not a pipeline cache, is refused with
    /// [`GpuError::PipelineCacheRefused`] saying which, and the cache stays as it was.
    pub fn seed_pipeline_cache(&self, data: &[u8]) -> GpuResult<()> {
        // SAFETY: the cache was created on this `Gpu`'s device by `assemble`, both live as long
        // as `self`, and `properties` were read from its physical device.
        unsafe { pipeline_cache::seed(&self.device, &self.properties, &self.pipeline_cache, data) }
    }
    /// Bytes of device memory in use and reserved by the allocator.
    pub fn memory_usage(&self) -> (u64, u64) {
        let report = self.allocator().generate_report();
        (report.total_allocated_bytes, report.total_capacity_bytes)
    }
}

/// Destroy what `Gpu::assemble` was given to own when it fails: with `owned_instance` (ours),
/// the device and the instance; without, nothing (they are the host's).
///
/// # Safety
/// Nothing created from `device` or the instance may remain.
unsafe fn abandon(device: &ash::Device, owned_instance: Option<OwnedInstance>) {
    if let Some(mut owned) = owned_instance {
        // SAFETY: the caller's contract.
        unsafe {
            device.destroy_device(None);
            owned.destroy();
        }
    }
}

impl Drop for Gpu {
    fn drop(&mut self) {
        // SAFETY: every Buffer/Image/Pipeline holds an Arc<Gpu>, so all of them are gone; the
        // allocator frees its memory blocks before the device that owns them is destroyed, and
        // the messenger goes just before the instance (OwnedInstance::destroy).
        unsafe {
            let _ = self.device.device_wait_idle();
            let cache = *self.pipeline_cache.get_mut().unwrap_or_else(|e| e.into_inner());
            self.device.destroy_pipeline_cache(cache, None);
            ManuallyDrop::drop(&mut self.allocator);
            if self.owns_device {
                self.device.destroy_device(None);
            }
            if let Some(owned) = self.owned_instance.as_mut() {
                owned.destroy();
            }
        }
    }
}
