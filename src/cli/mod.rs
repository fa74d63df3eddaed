//! Subcommands of the `translucent` binary, one module each.

pub mod devices;
pub mod material;
pub mod render;
pub mod sample;

use translucent::gpu::GpuOptions;

/// Options shared by every subcommand that touches the GPU.
#[derive(clap::Args, Clone, Debug, Default)]
pub struct GpuArgs {
    /// Vulkan device to use: an index from `translucent devices` or part of a device name
    #[arg(long, global = true, env = "TRANSLUCENT_DEVICE")]
    pub device: Option<String>,
    /// Enable VK_LAYER_KHRONOS_validation and report its messages (also TRANSLUCENT_VALIDATION=1)
    #[arg(long, global = true)]
    pub validation: bool,
}

impl GpuArgs {
    pub fn options(&self) -> GpuOptions {
        let env_validation =
            std::env::var("TRANSLUCENT_VALIDATION").map(|v| !v.is_empty() && v != "0").unwrap_or(false);
        GpuOptions {
            device: self.device.clone(),
            validation: self.validation || env_validation,
            ..GpuOptions::default()
        }
    }
}
