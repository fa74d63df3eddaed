//! `translucent render`. Until the renderer lands this runs the smoke pass: it proves the device
//! works end to end and prints the device and the GPU time.

use anyhow::Context;
use std::sync::Arc;
use translucent::gpu::Gpu;
use translucent::render::smoke;

#[derive(clap::Args, Debug, Default)]
pub struct Args {
    /// Elements in the smoke dispatch
    #[arg(long, default_value_t = 1 << 20)]
    pub count: u32,
}

pub fn run(gpu_args: &super::GpuArgs, args: &Args) -> anyhow::Result<()> {
    let count = if args.count == 0 { 1 << 20 } else { args.count };
    let gpu: Arc<Gpu> = Gpu::new(&gpu_args.options())?;
    println!("device: {}", gpu.info());
    let input: Vec<f32> = (0..count).map(|i| (i % 1000) as f32 * 0.5).collect();
    let result = smoke::run(&gpu, &input).context("smoke dispatch")?;
    let expected = smoke::expected(&input);
    let wrong = result
        .output
        .iter()
        .zip(&expected)
        .filter(|(a, b)| a != b)
        .count();
    anyhow::ensure!(
        wrong == 0,
        "smoke dispatch: {wrong} of {count} values are wrong"
    );
    println!(
        "smoke compute: {count} values correct, GPU time {:.3} ms",
        result.gpu_ms
    );
    let counters = gpu.validation();
    drop(gpu);
    anyhow::ensure!(
        counters.total() == 0,
        "{} Vulkan validation messages:\n{}",
        counters.total(),
        counters.messages().join("\n")
    );
    Ok(())
}
