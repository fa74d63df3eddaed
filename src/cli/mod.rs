//! Subcommands of the `translucent` binary, one module each.

/// `println!` that returns the write error instead of panicking, so a closed stdout
/// (`translucent devices | head -1`) ends the command quietly (see `main`).
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)?
    }};
}

pub mod devices;
pub mod material;
pub mod plan;
pub mod progress;
pub mod render;
pub mod sample;
#[cfg(feature = "study")]
pub mod study;
#[cfg(feature = "viewer")]
pub mod view;

use translucent::gpu::GpuOptions;

/// A parser that accepts one of `names` (listed in `--help` and in errors) and turns it into a
/// library type through its `FromStr`, so the library needs no command-line derive.
pub fn one_of<T>(names: &[&'static str]) -> impl clap::builder::TypedValueParser<Value = T>
where
    T: std::str::FromStr<Err = String> + Clone + Send + Sync + 'static,
{
    use clap::builder::TypedValueParser;
    clap::builder::PossibleValuesParser::new(names.to_vec()).map(|s| s.parse::<T>().expect("a listed name parses"))
}

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

/// On SIGINT or SIGTERM, remove the hidden temporary files of `outputs` (a write cut short
/// leaves none behind) and exit with 130. The destinations themselves are never touched.
pub fn remove_on_interrupt(outputs: &[&std::path::PathBuf]) -> anyhow::Result<()> {
    let temporaries: Vec<std::path::PathBuf> =
        outputs.iter().map(|p| translucent::output::temporary_path(p)).collect::<Result<_, _>>()?;
    // Only one handler per process; a second command in the same process keeps the first.
    let _ = ctrlc::set_handler(move || {
        for t in &temporaries {
            let _ = std::fs::remove_file(t);
        }
        eprintln!("interrupted: no output written");
        std::process::exit(130);
    });
    Ok(())
}

/// Attaches a transport kernel to every object whose material asks for one
/// (`material.model = "transport"`), read from the cache folder `dir` (default: the truth's)
/// or walked there with a progress bar.
pub fn attach_kernels(
    prepared: &mut translucent::scene::build::PreparedScene,
    dir: Option<&std::path::Path>,
) -> anyhow::Result<()> {
    use translucent::reference::{rte_mesh::KernelSettings, transport_cache, truth};
    let Some(first) = prepared.objects.iter().find(|o| o.wants_transport()).map(|o| o.name.clone()) else {
        return Ok(());
    };
    let dir = dir.map_or_else(truth::default_cache_dir, std::path::Path::to_path_buf);
    let bar = progress::bar(0).with_message(first).with_style(
        indicatif::ProgressStyle::with_template("transport kernel of {msg}: {bar:30} {pos}/{len} patches, {elapsed}")
            .expect("a valid template"),
    );
    let names: Vec<String> = prepared.objects.iter().map(|o| o.name.clone()).collect();
    // The length first: a log writes the first draw, which should not read 0/0.
    let result = transport_cache::attach(&mut prepared.objects, &KernelSettings::default(), &dir, &|i, done, of| {
        bar.set_length(of as u64);
        bar.set_position(done as u64);
        bar.set_message(names[i].clone());
    });
    bar.finish_and_clear();
    use anyhow::Context as _;
    result.map(drop).context("material.model = \"transport\": walking the transport kernel inside the mesh")
}
