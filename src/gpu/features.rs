//! The device features translucent needs: what `device` enables on a device it creates, and
//! what a host enables on its own (`Gpu::from_host`). A leaf below `device` and `context`.

use ash::vk;

/// The device features translucent needs, as the host enabled them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EnabledFeatures {
    /// Vulkan 1.3 `dynamicRendering`: every raster pass renders without render-pass objects.
    pub dynamic_rendering: bool,
    /// Vulkan 1.3 `synchronization2`: every barrier and timestamp.
    pub synchronization2: bool,
    /// Vulkan 1.2 `shaderOutputLayer`: the shadow pass picks each light's layer with gl_Layer.
    pub shader_output_layer: bool,
}

impl EnabledFeatures {
    /// All of them, as `required_features` enables them.
    pub const ALL: EnabledFeatures =
        EnabledFeatures { dynamic_rendering: true, synchronization2: true, shader_output_layer: true };
}

/// The feature structs a host chains into its `VkDeviceCreateInfo` (`push_next` both) so that
/// translucent can run on its device.
pub struct RequiredFeatures {
    /// `shaderOutputLayer`.
    pub vulkan12: vk::PhysicalDeviceVulkan12Features<'static>,
    /// `dynamicRendering`, `synchronization2`.
    pub vulkan13: vk::PhysicalDeviceVulkan13Features<'static>,
}

/// The features translucent needs, to chain into a host's device creation.
pub fn required_features() -> RequiredFeatures {
    RequiredFeatures {
        vulkan12: vk::PhysicalDeviceVulkan12Features::default().shader_output_layer(true),
        vulkan13: vk::PhysicalDeviceVulkan13Features::default().dynamic_rendering(true).synchronization2(true),
    }
}
