//! Times the gradient pass alone on the paper's constructed distribution (1M photons, the
//! default diffusion radius `dpm density` resolves) on one thread: the best and median of N
//! passes, and a checksum of the gradients so two versions can be compared for identical
//! output. Used to compare versions of the pass side by side (BENCHMARKS.md, "The gradient
//! pass").
//!
//! `cargo run --release --example gradient_timing -- PASSES`

use dpm::density::{Distribution, DistributionName};
use dpm::estimate::diffusion::compute_gradients;
use dpm::estimate::{EstimatorSettings, ResolvedEstimator};
use dpm::photon::PhotonMap;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    let passes = match std::env::args().nth(1).map(|p| p.parse::<usize>()) {
        Some(Ok(p)) if p > 0 => p,
        _ => {
            eprintln!("usage: gradient_timing PASSES");
            return ExitCode::from(2);
        }
    };
    const PHOTONS: u64 = 1_000_000;
    let photons = Distribution::new(DistributionName::Constructed, PHOTONS).photons(1);
    let map = PhotonMap::build(photons, PHOTONS);
    let Ok(ResolvedEstimator::Diffusion(diffusion)) = EstimatorSettings::default().resolve(&map)
    else {
        eprintln!("the default estimator must resolve to the diffusion estimate");
        return ExitCode::FAILURE;
    };
    let radius = diffusion.gradient_radius();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a rayon pool");
    let mut times = Vec::with_capacity(passes);
    let mut checksum = 0u64;
    for _ in 0..passes {
        let start = Instant::now();
        let gradients = pool.install(|| compute_gradients(&map, radius));
        times.push(start.elapsed().as_secs_f64());
        checksum = gradients.iter().fold(0u64, |h, g| {
            g.to_array()
                .iter()
                .fold(h, |h, c| h.rotate_left(5) ^ u64::from(c.to_bits()))
        });
    }

    times.sort_by(f64::total_cmp);
    println!(
        "gradient radius {radius}: best {:.3} s, median {:.3} s over {passes} passes; checksum {checksum:016x}",
        times[0],
        times[passes / 2]
    );
    ExitCode::SUCCESS
}
