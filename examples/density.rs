//! `dpm density` as a stand-alone program, for measuring before the subcommand is wired into
//! main: `cargo run --release --example density -- --distribution constructed -o out.png`.
//! Prints the report; exits 2 on an input error like the CLI.

use clap::Parser;

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: dpm::density::DensityArgs,
}

fn main() {
    let cli = Cli::parse();
    match dpm::density::run(&cli.args) {
        Ok(report) => print!("{report}"),
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    }
}
