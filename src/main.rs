//! The `dpm` command line: parses arguments, runs one subcommand, prints its timing table and
//! maps errors to exit codes (2 for bad input, 1 for failures inside, 130 when interrupted by
//! Ctrl-C). No rendering logic here.

use clap::{Parser, Subcommand};
use dpm::render::pipeline::{self, RenderArgs};
use std::process::ExitCode;

/// Diffusion based photon mapping (Schjøth, Olsen, Sparring) on Embree 3.
///
/// Photon mapping blurs caustics; the diffusion estimate steers an anisotropic kernel along
/// the caustic's edges so they stay sharp while flat regions are smoothed.
#[derive(Parser, Debug)]
#[command(name = "dpm", version, about, long_about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a scene: photon tracing (caustic and global maps), the chosen caustic estimate,
    /// and a Whitted-style eye pass; ends with a per-phase timing table.
    Render(RenderArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    if matches!(cli.command, Command::Render(_)) {
        // Ctrl-C then stops the render cleanly, keeping any earlier output (dpm::interrupt).
        if let Err(e) = dpm::interrupt::install() {
            eprintln!("warning: {e}");
        }
    }
    match cli.command {
        Command::Render(args) => match pipeline::run(&args) {
            Ok(outcome) => {
                if let Some(e) = &outcome.estimator {
                    eprintln!("caustic estimate: {e}");
                }
                eprint!("{}", outcome.times.table());
                eprintln!("wrote {}", outcome.output.display());
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(e.exit_code() as u8)
            }
        },
    }
}
