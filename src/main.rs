//! The `dpm` command line: parses arguments, runs one subcommand, prints its timing table and
//! maps errors to exit codes (2 for bad input, 1 for failures inside, 130 when interrupted by
//! Ctrl-C). No rendering logic here.

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};
use dpm::density::DensityArgs;
use dpm::render::pipeline::{self, RenderArgs};
use dpm::tradeoff::TradeoffArgs;
use dpm::tradeoff::reference::ReferenceArgs;
use std::process::ExitCode;

/// Diffusion based photon mapping (Schjøth, Olsen, Sparring) on Embree.
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
    Render(Box<RenderArgs>),
    /// Estimate a 2-D photon distribution (photons in the plane z = 0) on a grid: from a CSV
    /// file, or from a built-in distribution whose exact density is known, in which case the
    /// error against it is reported (the paper's Figures 4-6).
    Density(DensityArgs),
    /// Sweep photon counts and each estimate's parameters (cone: k; Epanechnikov: radius;
    /// diffusion: radius and K) on the constructed distribution or a scene, time every run
    /// and measure its error; writes a CSV and an error-against-time plot (SVG) and prints
    /// each estimate's Pareto front.
    Tradeoff(TradeoffArgs),
    /// Combine films of disjoint pass ranges of one render (`dpm render --film`, from any
    /// runs or machines) into one film and image; refuses overlapping passes and films of
    /// another scene, seed or setting, and names the passes still missing.
    Merge(dpm::render::merge::MergeArgs),
    /// Render a scene's reference caustic image (many more photons, a smaller radius) to a
    /// cache file, or report the cached one when the scene and settings are unchanged.
    Reference(ReferenceArgs),
    /// Read a scene (TOML or pbrt) without rendering: every error, warning and note it
    /// meets, each with its file:line(:column), then what would be rendered. Exits 0 when
    /// the scene would render, 2 otherwise.
    Check(CheckArgs),
}

#[derive(clap::Args, Debug)]
struct CheckArgs {
    /// The scene file (.toml or .pbrt).
    scene: std::path::PathBuf,
    /// Count what `dpm render --strict` refuses (materials dpm approximates) as errors.
    #[arg(long)]
    strict: bool,
    /// Read a pbrt scene without an `Integrator` line as pbrt does (`path`, maxdepth 5), as
    /// `dpm render --pbrt-default-integrator` would.
    #[arg(long)]
    pbrt_default_integrator: bool,
}

/// The parsed command line. `--version` also names the Embree library in use, which takes a
/// device to ask, so only then is one made.
fn parse() -> Cli {
    let mut command = Cli::command();
    if std::env::args_os().any(|a| a == "--version" || a == "-V") {
        let version = format!(
            "{} ({})",
            env!("CARGO_PKG_VERSION"),
            dpm::embree::version_string()
        );
        command = command.version(String::leak(version) as &str);
    }
    Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit())
}

fn main() -> ExitCode {
    let cli = parse();
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
                let memory = [
                    outcome
                        .caustic_bytes_per_photon
                        .map(|b| format!("caustic map {b:.1} bytes/photon")),
                    outcome.volume_maps.map(|(photons, bytes)| {
                        let per = bytes as f64 / photons.max(1) as f64;
                        format!("volume maps {per:.1} bytes/photon ({photons} photons)")
                    }),
                    outcome
                        .media_bytes
                        .map(|b| format!("media grids {:.1} MiB", b as f64 / (1 << 20) as f64)),
                    dpm::resident_memory::peak_resident_bytes()
                        .map(|b| format!("peak resident {:.0} MiB", b as f64 / (1 << 20) as f64)),
                ];
                let memory: Vec<String> = memory.into_iter().flatten().collect();
                if !memory.is_empty() {
                    eprintln!("memory: {}", memory.join(", "));
                }
                if let Some(note) = &outcome.budget_note {
                    eprintln!("note: {note}");
                }
                let passes = outcome.film.passes();
                eprintln!(
                    "wrote {} ({} pass{}: {passes})",
                    outcome.output.display(),
                    passes.count(),
                    if passes.count() == 1 { "" } else { "es" }
                );
                if outcome.interrupted {
                    eprintln!(
                        "interrupted: the output holds the {} complete pass{}",
                        passes.count(),
                        if passes.count() == 1 { "" } else { "es" }
                    );
                    return ExitCode::from(130);
                }
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(e.exit_code() as u8)
            }
        },
        Command::Density(args) => match dpm::density::run(&args) {
            Ok(report) => {
                print!("{report}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                // Every density error is about its input: the photons, flags or output path.
                ExitCode::from(2)
            }
        },
        Command::Tradeoff(args) => match dpm::tradeoff::run(&args) {
            Ok(outcome) => {
                print!("{}", outcome.table);
                eprintln!(
                    "{} runs in {:.1} s; wrote {} and {}",
                    outcome.rows.len(),
                    outcome.seconds,
                    outcome.csv.display(),
                    outcome.svg.display()
                );
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(e.exit_code())
            }
        },
        Command::Merge(args) => match dpm::render::merge::run(&args) {
            Ok(outcome) => {
                if let Some(missing) = outcome.missing_text() {
                    eprintln!("warning: {missing}");
                }
                eprintln!(
                    "merged {} films: {} passes ({}); wrote {}",
                    args.films.len(),
                    outcome.film.passes().count(),
                    outcome.film.passes(),
                    args.output.display()
                );
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(e.exit_code() as u8)
            }
        },
        Command::Check(args) => {
            let options = dpm::scene::LoadOptions {
                strict: args.strict,
                pbrt_default_integrator: args.pbrt_default_integrator,
            };
            let report = dpm::scene::check::check(&args.scene, &options);
            print!("{}", report.text());
            if report.renders() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(2)
            }
        }
        Command::Reference(args) => match dpm::tradeoff::reference::run(&args) {
            Ok(line) => {
                println!("{line}");
                ExitCode::SUCCESS
            }
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::from(e.exit_code())
            }
        },
    }
}
