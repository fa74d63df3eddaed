//! `translucent devices`: every Vulkan device the loader sees.

use translucent::gpu;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,
}

pub fn run(gpu_args: &super::GpuArgs, args: &Args) -> anyhow::Result<()> {
    let mut devices = gpu::list_devices()?;
    if devices.is_empty() {
        return Err(gpu::GpuError::NoDevice.into());
    }
    // `--device` (or TRANSLUCENT_DEVICE) narrows the list to the device it picks, with the
    // same error as every other command when nothing matches.
    if let Some(wanted) = &gpu_args.device {
        devices = vec![gpu::select_device(&devices, Some(wanted))?];
    }
    if args.json {
        out!("{}", serde_json::to_string_pretty(&devices)?);
    } else {
        out!("{:<5} {:<36} {:<15} {:<10} {:<8} driver info", "index", "name", "type", "driver", "vulkan");
        for d in &devices {
            out!(
                "{:<5} {:<36} {:<15} {:<10} {:<8} {}",
                d.index,
                d.name,
                d.kind,
                d.driver,
                d.api_version,
                d.driver_info
            );
        }
    }
    Ok(())
}
