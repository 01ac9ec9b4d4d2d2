//! The `lobelight` command line (see README.md and the contract in DESIGN notes §12).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use lobelight::gpu::{BackendChoice, Gpu};
use lobelight::{Result, info, scene};

#[derive(Parser)]
#[command(
    name = "lobelight",
    version,
    about = "Global illumination on splats with Gaussian lobes, on the GPU"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Splats, lights, materials, bounds, grid and memory of a scene, and the device in use.
    Info {
        scene: PathBuf,
        /// Print one JSON object on stdout.
        #[arg(long)]
        json: bool,
        /// Build the grid with the CPU mirror instead of the GPU.
        #[arg(long)]
        cpu: bool,
        /// Graphics API (default: WGPU_BACKEND, else Vulkan, else GL).
        #[arg(long, value_enum, default_value_t = BackendChoice::Auto)]
        backend: BackendChoice,
    },
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Info {
            scene,
            json,
            cpu,
            backend,
        } => {
            let scene = scene::load(&scene)?;
            let gpu = if cpu { None } else { Some(Gpu::new(backend)?) };
            let info = info::info(&scene, gpu.as_ref())?;
            if json {
                println!(
                    "{}",
                    serde_json::to_string_pretty(&info)
                        .map_err(|e| lobelight::Error::Invalid(e.to_string()))?
                );
            } else {
                println!("{info}");
            }
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("error")).init();
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("lobelight: {e}");
            ExitCode::FAILURE
        }
    }
}
