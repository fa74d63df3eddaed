//! The Vulkan core (ash): one Vulkan concept per file.

/// How to build a GPU context.
#[derive(Clone, Debug, Default)]
pub struct GpuOptions {
    /// Device index or part of its name; `None` picks a discrete/integrated GPU, else the CPU device.
    pub device: Option<String>,
    /// Enable the Khronos validation layer and count its messages.
    pub validation: bool,
}
