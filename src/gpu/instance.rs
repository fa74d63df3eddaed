//! The Vulkan loader and instance, with the validation layer and debug messenger when asked.

use super::debug::{DebugMessenger, ValidationCounters};
use super::error::{GpuError, GpuResult, VkContext};
use ash::vk;
use std::ffi::CStr;
use std::sync::Arc;

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Load `libvulkan.so.1` at run time, so a missing loader is an error, not a link failure.
pub(crate) fn load_entry() -> GpuResult<ash::Entry> {
    // SAFETY: loading the system Vulkan loader runs its initialisers; nothing else is assumed.
    unsafe { ash::Entry::load() }.map_err(GpuError::LoaderMissing)
}

/// An instance we created (and so destroy), with its messenger if validation is on.
pub(crate) struct OwnedInstance {
    pub(crate) instance: ash::Instance,
    pub(crate) debug: Option<DebugMessenger>,
}

pub(crate) fn create_instance(
    entry: &ash::Entry,
    validation: bool,
    sync_validation: bool,
    counters: &Arc<ValidationCounters>,
) -> GpuResult<OwnedInstance> {
    let mut layers = Vec::new();
    let mut extensions = Vec::new();
    if validation {
        // SAFETY: plain enumeration query.
        let available =
            unsafe { entry.enumerate_instance_layer_properties() }.vk("vkEnumerateInstanceLayerProperties")?;
        let found = available.iter().any(|l| l.layer_name_as_c_str().map(|n| n == VALIDATION_LAYER).unwrap_or(false));
        if !found {
            return Err(GpuError::ValidationLayerMissing);
        }
        layers.push(VALIDATION_LAYER.as_ptr());
        extensions.push(ash::ext::debug_utils::NAME.as_ptr());
        if sync_validation {
            // The layer itself provides the extension that carries its feature switches.
            extensions.push(ash::ext::validation_features::NAME.as_ptr());
        }
    }
    let app = vk::ApplicationInfo::default()
        .application_name(c"translucent")
        .engine_name(c"translucent")
        .api_version(vk::API_VERSION_1_3);
    // Chained so messages from vkCreateInstance/vkDestroyInstance themselves are counted too.
    let mut debug_info = DebugMessenger::create_info(counters);
    let mut info = vk::InstanceCreateInfo::default()
        .application_info(&app)
        .enabled_layer_names(&layers)
        .enabled_extension_names(&extensions);
    let enabled = [vk::ValidationFeatureEnableEXT::SYNCHRONIZATION_VALIDATION];
    let mut features = vk::ValidationFeaturesEXT::default().enabled_validation_features(&enabled);
    if validation {
        info = info.push_next(&mut debug_info);
        if sync_validation {
            info = info.push_next(&mut features);
        }
    }
    // SAFETY: every pointer in `info` refers to locals that outlive the call.
    let instance = match unsafe { entry.create_instance(&info, None) } {
        Ok(i) => i,
        Err(vk::Result::ERROR_INCOMPATIBLE_DRIVER) => {
            return Err(GpuError::NoDriver);
        }
        Err(result) => {
            return Err(GpuError::Vk { what: "vkCreateInstance", result });
        }
    };
    let debug = if validation {
        match DebugMessenger::new(entry, &instance, counters.clone()) {
            Ok(d) => Some(d),
            Err(result) => {
                // SAFETY: nothing was created from this instance yet.
                unsafe { instance.destroy_instance(None) };
                return Err(GpuError::Vk { what: "vkCreateDebugUtilsMessengerEXT", result });
            }
        }
    } else {
        None
    };
    Ok(OwnedInstance { instance, debug })
}

impl OwnedInstance {
    /// # Safety
    /// Every object created from the instance must already be destroyed.
    pub(crate) unsafe fn destroy(&mut self) {
        if let Some(debug) = self.debug.take() {
            // SAFETY: `take` makes this the only call for the messenger, and the instance is still
            // alive (destroyed just below).
            unsafe { debug.destroy() };
        }
        // SAFETY: the caller's contract: every object made from the instance is gone, and the
        // messenger went just above.
        unsafe { self.instance.destroy_instance(None) };
    }
}
