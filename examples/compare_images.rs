//! Compares two linear images (.pfm) of the same size: prints their relative mean squared
//! error, Σ (a − b)² / Σ b² over every pixel and channel (b is the reference), and fails (exit 1)
//! when it is above `MAX`. Used by `scripts/compare-backends.sh` to check that the Embree 3 and
//! Embree 4 builds render the same images within noise.
//!
//! `cargo run --release --example compare_images -- A.pfm B.pfm [MAX]` (MAX defaults to 1e-3)

use dpm::image_io::read_pfm;
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (a, b, max) = match args.as_slice() {
        [a, b] => (a, b, Ok(1e-3)),
        [a, b, max] => (a, b, max.parse::<f64>()),
        _ => {
            eprintln!("usage: compare_images A.pfm B.pfm [MAX]");
            return ExitCode::from(2);
        }
    };
    let Ok(max) = max else {
        eprintln!("error: MAX must be a number");
        return ExitCode::from(2);
    };
    let (a, b) = match (read_pfm(Path::new(a)), read_pfm(Path::new(b))) {
        (Ok(a), Ok(b)) => (a, b),
        (Err(e), _) | (_, Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::from(2);
        }
    };
    if (a.width, a.height) != (b.width, b.height) {
        eprintln!(
            "error: {}×{} against {}×{}",
            a.width, a.height, b.width, b.height
        );
        return ExitCode::from(2);
    }
    let (mut error, mut energy) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for (x, y) in p.to_array().into_iter().zip(q.to_array()) {
            error += (f64::from(x) - f64::from(y)).powi(2);
            energy += f64::from(y).powi(2);
        }
    }
    let relative = error / energy.max(f64::MIN_POSITIVE);
    if !relative.is_finite() || relative > max {
        println!("relative MSE {relative:.3e} > {max:.0e}: FAIL");
        return ExitCode::FAILURE;
    }
    println!("relative MSE {relative:.3e} <= {max:.0e}: ok");
    ExitCode::SUCCESS
}
