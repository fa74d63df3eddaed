//! The viewer's own Vulkan: the instance with the window system's surface extensions, the
//! device with the swapchain extension and translucent's required features chained in, and a
//! validation messenger that counts what it reports. translucent gets these through
//! `Gpu::from_host`, as any engine's.

use anyhow::{Context, Result, anyhow};
use ash::vk;
use raw_window_handle::{HasDisplayHandle, HasWindowHandle};
use std::ffi::{CStr, c_void};
use std::sync::atomic::{AtomicUsize, Ordering};
use translucent::gpu::{EnabledFeatures, HostVulkan, required_features};

/// Validation messages the viewer's messenger has reported (warnings and errors).
static MESSAGES: AtomicUsize = AtomicUsize::new(0);

/// Validation messages reported so far in this process.
pub fn validation_messages() -> usize {
    MESSAGES.load(Ordering::SeqCst)
}

unsafe extern "system" fn report(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _kind: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    _user: *mut c_void,
) -> vk::Bool32 {
    MESSAGES.fetch_add(1, Ordering::SeqCst);
    // SAFETY: the layer passes a valid callback data pointer with a NUL-terminated message.
    let message = unsafe { (*data).message_as_c_str() }.map(CStr::to_string_lossy).unwrap_or_default();
    eprintln!("[validation {severity:?}] {message}");
    vk::FALSE
}

/// The viewer's instance, surface and device. Dropped last: everything else is made from it.
pub struct Host {
    pub entry: ash::Entry,
    pub instance: ash::Instance,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    pub surface_loader: ash::khr::surface::Instance,
    pub surface: vk::SurfaceKHR,
    pub physical: vk::PhysicalDevice,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub family: u32,
    /// The device's name, for the window title.
    pub name: String,
}

impl Host {
    /// Vulkan for `window`: on the device whose name contains `wanted` (any device when none),
    /// with a queue that draws, computes and presents to the window.
    pub fn new(
        window: &(impl HasDisplayHandle + HasWindowHandle),
        wanted: Option<&str>,
        validation: bool,
    ) -> Result<Host> {
        // SAFETY: loading the system's Vulkan loader.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| anyhow!("no Vulkan loader ({e}): install libvulkan1 and a driver (bash scripts/setup)"))?;
        let display = window.display_handle()?.as_raw();
        let mut extensions = ash_window::enumerate_required_extensions(display)?.to_vec();
        let layers = [c"VK_LAYER_KHRONOS_validation".as_ptr()];
        if validation {
            extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        }
        let app = vk::ApplicationInfo::default().application_name(c"translucent view").api_version(vk::API_VERSION_1_3);
        let mut info = vk::InstanceCreateInfo::default().application_info(&app).enabled_extension_names(&extensions);
        if validation {
            info = info.enabled_layer_names(&layers);
        }
        // SAFETY: valid create info; destroyed in `drop`.
        let instance = unsafe { entry.create_instance(&info, None) }.context("vkCreateInstance")?;
        let debug = if validation { Some(messenger(&entry, &instance)?) } else { None };
        // SAFETY: the window outlives the surface (the viewer drops the host before the window).
        let surface =
            unsafe { ash_window::create_surface(&entry, &instance, display, window.window_handle()?.as_raw(), None) }
                .context("creating the window's Vulkan surface")?;
        let surface_loader = ash::khr::surface::Instance::new(&entry, &instance);
        let (physical, family, name) = pick_device(&instance, &surface_loader, surface, wanted)?;
        let device = create_device(&instance, physical, family)?;
        // SAFETY: queue 0 of `family` was requested.
        let queue = unsafe { device.get_device_queue(family, 0) };
        Ok(Host { entry, instance, debug, surface_loader, surface, physical, device, queue, family, name })
    }

    /// The handles `Gpu::from_host` takes.
    pub fn vulkan(&self) -> HostVulkan {
        HostVulkan {
            entry: self.entry.clone(),
            instance: self.instance.clone(),
            physical_device: self.physical,
            device: self.device.clone(),
            queue: self.queue,
            queue_family: self.family,
            enabled_features: EnabledFeatures::ALL,
        }
    }

    /// A memory type among `bits` with `flags`.
    pub fn memory_type(&self, bits: u32, flags: vk::MemoryPropertyFlags) -> Result<u32> {
        // SAFETY: plain query.
        let props = unsafe { self.instance.get_physical_device_memory_properties(self.physical) };
        (0..props.memory_type_count)
            .find(|&i| bits & (1 << i) != 0 && props.memory_types[i as usize].property_flags.contains(flags))
            .ok_or_else(|| anyhow!("no memory type with {flags:?}"))
    }
}

impl Drop for Host {
    fn drop(&mut self) {
        // SAFETY: everything made from the device is gone and the device is idle (the viewer
        // waits before dropping its parts); the surface's swapchains are destroyed.
        unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            self.surface_loader.destroy_surface(self.surface, None);
            if let Some((loader, messenger)) = &self.debug {
                loader.destroy_debug_utils_messenger(*messenger, None);
            }
            self.instance.destroy_instance(None);
        }
    }
}

fn messenger(
    entry: &ash::Entry,
    instance: &ash::Instance,
) -> Result<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)> {
    let loader = ash::ext::debug_utils::Instance::new(entry, instance);
    let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
        .message_severity(vk::DebugUtilsMessageSeverityFlagsEXT::WARNING | vk::DebugUtilsMessageSeverityFlagsEXT::ERROR)
        .message_type(vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE)
        .pfn_user_callback(Some(report));
    // SAFETY: valid create info; destroyed with the host.
    let messenger = unsafe { loader.create_debug_utils_messenger(&info, None) }
        .context("no validation layer: install vulkan-validationlayers (bash scripts/setup)")?;
    Ok((loader, messenger))
}

/// The first device (whose name contains `wanted`, when given) with a queue family that draws,
/// computes and presents to `surface`.
fn pick_device(
    instance: &ash::Instance,
    surfaces: &ash::khr::surface::Instance,
    surface: vk::SurfaceKHR,
    wanted: Option<&str>,
) -> Result<(vk::PhysicalDevice, u32, String)> {
    // SAFETY: plain queries on a live instance and surface.
    unsafe {
        for physical in instance.enumerate_physical_devices()? {
            let props = instance.get_physical_device_properties(physical);
            let name = props.device_name_as_c_str().unwrap_or_default().to_string_lossy().into_owned();
            if wanted.is_some_and(|w| !name.to_lowercase().contains(&w.to_lowercase())) {
                continue;
            }
            let families = instance.get_physical_device_queue_family_properties(physical);
            for (i, family) in families.iter().enumerate() {
                let both = vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE;
                let presents = surfaces.get_physical_device_surface_support(physical, i as u32, surface)?;
                if family.queue_flags.contains(both) && presents {
                    return Ok((physical, i as u32, name));
                }
            }
        }
    }
    Err(anyhow!(
        "no Vulkan device {}presents to this window: install mesa-vulkan-drivers (bash scripts/setup)",
        wanted.map(|w| format!("named like {w:?} ")).unwrap_or_default()
    ))
}

/// A device with the swapchain extension and translucent's required features.
fn create_device(instance: &ash::Instance, physical: vk::PhysicalDevice, family: u32) -> Result<ash::Device> {
    let priorities = [1.0];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    let extensions = [ash::khr::swapchain::NAME.as_ptr()];
    let mut features = required_features();
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .enabled_extension_names(&extensions)
        .push_next(&mut features.vulkan12)
        .push_next(&mut features.vulkan13);
    // SAFETY: valid create info; destroyed with the host.
    unsafe { instance.create_device(physical, &info, None) }.context("vkCreateDevice with VK_KHR_swapchain")
}
