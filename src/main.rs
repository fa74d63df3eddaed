//! The `translucent` command line. Each subcommand lives in `src/cli/`.

#[macro_use]
mod cli;

use clap::{Parser, Subcommand};
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "translucent", version, about = "Render translucent materials (dipole BSSRDF) on Vulkan", long_about = None)]
struct Cli {
    #[command(flatten)]
    gpu: cli::GpuArgs,
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand)]
enum Command {
    /// List Vulkan devices (name, type, driver, Vulkan version)
    Devices(cli::devices::Args),
    /// Render a scene (default: the built-in scene)
    Render(cli::render::Args),
    /// Show a material's derived dipole quantities, or list the measured presets
    Material(cli::material::Args),
    /// Place sample points on a mesh and print their statistics
    Sample(cli::sample::Args),
    /// Show what each kind of frame change would run, per pass, object and channel, and why
    Plan(cli::plan::Args),
    /// Measure what accuracy costs in time: every sampler, sample count and gather against the
    /// exact dipole integral (CSV, Markdown, a plot)
    #[cfg(feature = "study")]
    Study(Box<cli::study::Args>),
    /// Show a scene in a window, live: orbit, pan and zoom with the mouse, drag lights with
    /// Ctrl, switch the model, gather and error target with keys (m, g, e)
    #[cfg(feature = "viewer")]
    View(cli::view::Args),
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result = match cli.command {
        None => cli::render::run(&cli.gpu, &cli::render::Args::default()),
        Some(Command::Render(args)) => cli::render::run(&cli.gpu, &args),
        Some(Command::Devices(args)) => cli::devices::run(&cli.gpu, &args),
        Some(Command::Material(args)) => cli::material::run(&args),
        Some(Command::Sample(args)) => cli::sample::run(&args),
        Some(Command::Plan(args)) => cli::plan::run(&args),
        #[cfg(feature = "study")]
        Some(Command::Study(args)) => cli::study::run(&cli.gpu, &args),
        #[cfg(feature = "viewer")]
        Some(Command::View(args)) => cli::view::run(&cli.gpu, &args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        // The reader of our stdout went away (`| head`): nothing left to say, not a failure.
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe))
}
