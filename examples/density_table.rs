//! The measurements of the constructed-distribution table (docs/guide.md, "The density experiment"): every estimate of the table on a
//! built-in distribution, each written as a PNG, and the metrics as a Markdown table.
//!
//! `cargo run --release --example density_table -- [DISTRIBUTION] [COUNT] [SIZE] [IMAGE_DIR] [FILTER]`
//! (defaults: constructed 1000000 512 docs/img; FILTER keeps the rows whose label contains it).

use clap::Parser;
use dpm::density::{DensityArgs, DensityReport, run};

#[derive(Parser)]
struct Cli {
    #[command(flatten)]
    args: DensityArgs,
}

/// Label and estimator flags of each row.
fn rows() -> Vec<(&'static str, Vec<&'static str>)> {
    let r = "0.02";
    vec![
        ("cone k=200", vec!["--estimator", "cone", "--k", "200"]),
        ("cone k=400", vec!["--estimator", "cone", "--k", "400"]),
        ("cone k=800", vec!["--estimator", "cone", "--k", "800"]),
        (
            "epanechnikov default radius",
            vec!["--estimator", "epanechnikov"],
        ),
        ("diffusion default radius", vec!["--estimator", "diffusion"]),
        (
            "epanechnikov r=0.02",
            vec!["--estimator", "epanechnikov", "--radius", r],
        ),
        (
            "diffusion r=0.02 K=0.4",
            vec![
                "--estimator",
                "diffusion",
                "--radius",
                r,
                "--diffusivity",
                "0.4",
            ],
        ),
        (
            "diffusion r=0.02 K=0.2",
            vec![
                "--estimator",
                "diffusion",
                "--radius",
                r,
                "--diffusivity",
                "0.2",
            ],
        ),
        (
            "diffusion r=0.02 K=0.1",
            vec![
                "--estimator",
                "diffusion",
                "--radius",
                r,
                "--diffusivity",
                "0.1",
            ],
        ),
        (
            "diffusion r=0.02 K=0.4 absolute",
            vec![
                "--estimator",
                "diffusion",
                "--radius",
                r,
                "--diffusivity",
                "0.4",
                "--k-units",
                "absolute",
            ],
        ),
        (
            "diffusion r=0.02 K=0.2 absolute",
            vec![
                "--estimator",
                "diffusion",
                "--radius",
                r,
                "--diffusivity",
                "0.2",
                "--k-units",
                "absolute",
            ],
        ),
        (
            "diffusion r=0.02 K=0.1 absolute",
            vec![
                "--estimator",
                "diffusion",
                "--radius",
                r,
                "--diffusivity",
                "0.1",
                "--k-units",
                "absolute",
            ],
        ),
    ]
}

fn file_label(label: &str) -> String {
    label.replace([' ', '='], "-").replace('.', "")
}

fn main() {
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| argv.get(i).cloned().unwrap_or_else(|| default.to_string());
    let (distribution, count, size, dir, filter) = (
        arg(0, "constructed"),
        arg(1, "1000000"),
        arg(2, "512"),
        arg(3, "docs/img"),
        arg(4, ""),
    );
    println!(
        "| {distribution}, {count} photons, {size}×{size} | RMSE | rel. RMSE | edge-band RMSE | flat noise | line peak | energy | seconds |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for (i, (label, flags)) in rows().into_iter().enumerate() {
        if !label.contains(filter.as_str()) {
            continue;
        }
        let out = format!("{dir}/{distribution}-{}.png", file_label(label));
        let mut list = vec![
            "density",
            "--distribution",
            &distribution,
            "--count",
            &count,
            "--width",
            &size,
            "--height",
            &size,
            "-o",
            &out,
        ];
        let truth = format!("{dir}/{distribution}-truth.png");
        if i == 0 {
            list.extend(["--truth", truth.as_str()]);
        }
        list.extend(flags);
        let args = match Cli::try_parse_from(&list) {
            Ok(cli) => cli.args,
            Err(e) => {
                eprintln!("{label}: {e}");
                continue;
            }
        };
        match run(&args) {
            Ok(report) => print_row(label, &report),
            Err(e) => eprintln!("{label}: {e}"),
        }
    }
}

fn print_row(label: &str, report: &DensityReport) {
    let Some(m) = report.metrics else { return };
    let s = report.seconds;
    println!(
        "| {label} | {:.4} | {:.4} | {:.4} | {:.4} | {:.3} | {:+.2}% | {:.1} |",
        m.rmse,
        m.relative_rmse,
        m.edge_band_rmse,
        m.flat_noise,
        m.line_peak.unwrap_or(f64::NAN),
        100.0 * m.energy_error,
        s.photons + s.prepare + s.estimate
    );
    eprintln!("{label}: {}", report.estimator);
}
