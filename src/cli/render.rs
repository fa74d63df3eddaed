//! `translucent render`.

#[derive(clap::Args, Debug, Default)]
pub struct Args {}

pub fn run(_gpu: &super::GpuArgs, _args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("not built yet")
}
