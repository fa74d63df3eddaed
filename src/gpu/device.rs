//! Physical-device discovery and choice, and the logical device with one graphics+compute queue.

use super::error::{GpuError, GpuResult, Shortfall, VkContext};
use ash::vk;
use std::fmt;

/// What `translucent devices` shows about a physical device.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DeviceInfo {
    /// Position in the loader's list of physical devices; `--device` accepts it.
    pub index: usize,
    /// The name the driver reports; `--device` also matches part of it.
    pub name: String,
    /// "discrete GPU", "integrated GPU", "virtual GPU", "CPU" or "other".
    pub kind: String,
    /// The driver's name (VkPhysicalDeviceDriverProperties::driverName).
    pub driver: String,
    /// The driver's own version details (driverInfo).
    pub driver_info: String,
    /// The Vulkan version the device supports, "major.minor.patch".
    pub api_version: String,
    #[serde(skip)]
    pub(crate) api: u32,
    #[serde(skip)]
    pub(crate) device_type: vk::PhysicalDeviceType,
    #[serde(skip)]
    pub(crate) handle: vk::PhysicalDevice,
}

impl fmt::Display for DeviceInfo {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} ({}, driver {} {}, Vulkan {})",
            self.index, self.name, self.kind, self.driver, self.driver_info, self.api_version
        )
    }
}

fn version_string(v: u32) -> String {
    format!("{}.{}.{}", vk::api_version_major(v), vk::api_version_minor(v), vk::api_version_patch(v))
}

pub(crate) fn enumerate(instance: &ash::Instance) -> GpuResult<Vec<DeviceInfo>> {
    // SAFETY: plain queries on a live instance.
    let handles = unsafe { instance.enumerate_physical_devices() }.vk("vkEnumeratePhysicalDevices")?;
    Ok(handles
        .into_iter()
        .enumerate()
        .map(|(index, handle)| {
            let mut driver = vk::PhysicalDeviceDriverProperties::default();
            let mut props2 = vk::PhysicalDeviceProperties2::default().push_next(&mut driver);
            // SAFETY: `props2` chains only `driver`, a 1.2-core struct every 1.1+ loader accepts.
            unsafe { instance.get_physical_device_properties2(handle, &mut props2) };
            let props = props2.properties;
            let name = props.device_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            let kind = match props.device_type {
                vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
                vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
                vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
                vk::PhysicalDeviceType::CPU => "CPU",
                _ => "other",
            };
            DeviceInfo {
                index,
                name,
                kind: kind.to_string(),
                driver: driver.driver_name_as_c_str().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default(),
                driver_info: driver
                    .driver_info_as_c_str()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                api_version: version_string(props.api_version),
                api: props.api_version,
                device_type: props.device_type,
                handle,
            }
        })
        .collect())
}

/// `wanted` is an index or a case-insensitive part of a name. Without it: a real GPU if there
/// is one (discrete before integrated), else the CPU device (lavapipe).
pub fn select(devices: &[DeviceInfo], wanted: Option<&str>) -> GpuResult<DeviceInfo> {
    if devices.is_empty() {
        return Err(GpuError::NoDevice);
    }
    let chosen = match wanted.map(str::trim).filter(|w| !w.is_empty()) {
        Some(w) => {
            let by_index = w.parse::<usize>().ok().and_then(|i| devices.get(i));
            let lower = w.to_lowercase();
            by_index.or_else(|| devices.iter().find(|d| d.name.to_lowercase().contains(&lower))).ok_or_else(|| {
                GpuError::DeviceNotFound {
                    wanted: w.to_string(),
                    available: devices.iter().map(|d| format!("  {d}")).collect::<Vec<_>>().join("\n"),
                }
            })?
        }
        None => {
            let rank = |d: &DeviceInfo| match d.device_type {
                vk::PhysicalDeviceType::DISCRETE_GPU => 0,
                vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
                vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
                vk::PhysicalDeviceType::CPU => 3,
                _ => 4,
            };
            let usable = devices.iter().filter(|d| d.api >= vk::API_VERSION_1_3);
            usable.min_by_key(|d| rank(d)).unwrap_or(&devices[0])
        }
    };
    if chosen.api < vk::API_VERSION_1_3 {
        return Err(GpuError::DeviceUnsuitable {
            name: chosen.name.clone(),
            version: chosen.api_version.clone(),
            detail: Shortfall::Version,
        });
    }
    Ok(chosen.clone())
}

/// The first queue family that does graphics and compute, and its timestamp valid bits (0 when
/// it cannot write timestamps: then there are no GPU timings).
pub(crate) fn queue_family(instance: &ash::Instance, device: &DeviceInfo) -> GpuResult<(u32, u32)> {
    // SAFETY: plain query.
    let families = unsafe { instance.get_physical_device_queue_family_properties(device.handle) };
    families
        .iter()
        .enumerate()
        .find(|(_, f)| f.queue_flags.contains(vk::QueueFlags::GRAPHICS | vk::QueueFlags::COMPUTE))
        .map(|(i, f)| (i as u32, f.timestamp_valid_bits))
        .ok_or_else(|| GpuError::DeviceUnsuitable {
            name: device.name.clone(),
            version: device.api_version.clone(),
            detail: Shortfall::NoQueue,
        })
}

/// Optional Vulkan 1.2 features translucent relies on.
pub fn check_features(instance: &ash::Instance, device: &DeviceInfo) -> GpuResult<()> {
    let mut v12 = vk::PhysicalDeviceVulkan12Features::default();
    let mut features = vk::PhysicalDeviceFeatures2::default().push_next(&mut v12);
    // SAFETY: plain query with a 1.2-core chained struct.
    unsafe { instance.get_physical_device_features2(device.handle, &mut features) };
    if v12.shader_output_layer == vk::FALSE {
        return Err(GpuError::DeviceUnsuitable {
            name: device.name.clone(),
            version: device.api_version.clone(),
            detail: Shortfall::ShaderOutputLayer,
        });
    }
    Ok(())
}

pub(crate) fn create_logical(instance: &ash::Instance, device: &DeviceInfo, family: u32) -> GpuResult<ash::Device> {
    let priorities = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default().queue_family_index(family).queue_priorities(&priorities)];
    // The same features a host enables (`required_features`): shaderOutputLayer lets the shadow
    // pass pick each light's array layer with gl_Layer in one layered render.
    let mut features = super::features::required_features();
    let info = vk::DeviceCreateInfo::default()
        .queue_create_infos(&queues)
        .push_next(&mut features.vulkan13)
        .push_next(&mut features.vulkan12);
    // SAFETY: features requested are core in Vulkan 1.3 (`select` checked the version, and
    // `check_features` that shaderOutputLayer is supported).
    unsafe { instance.create_device(device.handle, &info, None) }.vk("vkCreateDevice")
}
