//! `translucent devices`: every Vulkan device the loader sees.

use translucent::gpu;

#[derive(clap::Args, Debug)]
pub struct Args {
    /// Print JSON instead of a table
    #[arg(long)]
    json: bool,
}

pub fn run(_gpu: &super::GpuArgs, args: &Args) -> anyhow::Result<()> {
    let devices = gpu::list_devices()?;
    if devices.is_empty() {
        return Err(gpu::GpuError::NoDevice(String::new()).into());
    }
    if args.json {
        println!("{}", serde_json::to_string_pretty(&devices)?);
    } else {
        println!("{:<5} {:<36} {:<15} {:<10} {:<8} driver info", "index", "name", "type", "driver", "vulkan");
        for d in &devices {
            println!(
                "{:<5} {:<36} {:<15} {:<10} {:<8} {}",
                d.index, d.name, d.kind, d.driver, d.api_version, d.driver_info
            );
        }
    }
    Ok(())
}
