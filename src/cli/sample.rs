//! `translucent sample`: placeholder until the sampling issue lands.

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`translucent sample` is not built yet")
}
