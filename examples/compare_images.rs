//! Compares two linear images (.pfm or .exr) of the same size: prints their relative mean
//! squared error, Σ (a − b)² / Σ b² over every pixel and channel (b is the reference), and
//! fails (exit 1) when it is above `MAX`. Used by `scripts/compare-backends.sh` to check that
//! the Embree 3 and Embree 4 builds render the same images within noise.
//!
//! With `--per-pixel` it bounds every value instead: the largest |a − b| / max(|a|, |b|) over
//! every pixel and channel must be at most `MAX`. `deploy/slurm/test-local-cluster.sh` checks
//! a merged render against one run of the same passes with it (1e-6: the passes summed in
//! another order round differently, nothing more).
//!
//! `cargo run --release --example compare_images -- A B [MAX] [--per-pixel]` (MAX defaults to
//! 1e-3)

use dpm::image_io::{Image, read_image};
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let per_pixel = args.iter().any(|a| a == "--per-pixel");
    args.retain(|a| a != "--per-pixel");
    let (a, b, max) = match args.as_slice() {
        [a, b] => (a, b, Ok(1e-3)),
        [a, b, max] => (a, b, max.parse::<f64>()),
        _ => {
            eprintln!("usage: compare_images A B [MAX] [--per-pixel]");
            return ExitCode::from(2);
        }
    };
    let Ok(max) = max else {
        eprintln!("error: MAX must be a number");
        return ExitCode::from(2);
    };
    let (a, b) = match (read_image(Path::new(a)), read_image(Path::new(b))) {
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
    let (name, error) = if per_pixel {
        (
            "largest per-pixel relative difference",
            per_pixel_error(&a, &b),
        )
    } else {
        ("relative MSE", relative_mse(&a, &b))
    };
    if !error.is_finite() || error > max {
        println!("{name} {error:.3e} > {max:.0e}: FAIL");
        return ExitCode::FAILURE;
    }
    println!("{name} {error:.3e} <= {max:.0e}: ok");
    ExitCode::SUCCESS
}

/// Every (a, b) value pair, pixel by pixel and channel by channel.
fn values<'a>(a: &'a Image, b: &'a Image) -> impl Iterator<Item = (f64, f64)> + 'a {
    a.pixels.iter().zip(&b.pixels).flat_map(|(p, q)| {
        p.to_array()
            .into_iter()
            .zip(q.to_array())
            .map(|(x, y)| (f64::from(x), f64::from(y)))
    })
}

fn relative_mse(a: &Image, b: &Image) -> f64 {
    let (mut error, mut energy) = (0.0f64, 0.0f64);
    for (x, y) in values(a, b) {
        error += (x - y).powi(2);
        energy += y.powi(2);
    }
    error / energy.max(f64::MIN_POSITIVE)
}

fn per_pixel_error(a: &Image, b: &Image) -> f64 {
    values(a, b)
        .map(|(x, y)| (x - y).abs() / x.abs().max(y.abs()).max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max)
}
