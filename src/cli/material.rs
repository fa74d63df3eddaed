//! `translucent material`: placeholder until the optics issue lands.

#[derive(clap::Args, Debug)]
pub struct Args {}

pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`translucent material` is not built yet")
}
