//! What the diffusion estimate costs where discs hold many photons (issue 16's targets):
//!
//! 1. The constructed distribution (1M photons, 512×512, seed 1) at r = 0.02, where a disc
//!    holds about 1,300 photons over the background and far more on the shapes: the gradient
//!    pass plus the per-pixel loop against Jensen's cone filter at k = 400 (target ≤ 2×).
//! 2. The gradient pass on 1M photons of a concentrated caustic (60% of them in a Gaussian spot
//!    of σ = 0.01, the rest spread over the unit square, like a glass ball's focus on a floor)
//!    against 1M evenly spread ones, each at the radii `dpm` resolves for it by default
//!    (target ≤ 2×), and the concentrated map at the spread map's radii too.
//!
//! Everything on a rayon pool of 2 threads; medians of 10 criterion samples, wall and CPU.
//! The photon maps are built once, outside the timings.
//!
//! `cargo bench --bench diffusion_cost` (about 3 minutes on two cores).

#[path = "support/samples.rs"]
mod samples;
mod support;

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use dpm::density::{Distribution, DistributionName, Extent, Grid, grid};
use dpm::estimate::{
    DiffusionEstimate, EstimatorKind, EstimatorSettings, RadianceEstimate, ResolvedEstimator,
};
use dpm::photon::{Photon, PhotonMap};
use glam::Vec3;
use indicatif::ProgressBar;
use samples::{SAMPLES, Samples, load_average, pool};
use std::time::Duration;
use support::Rng;

const PHOTONS: u64 = 1_000_000;
const SIZE: usize = 512;

fn diffusion(map: &PhotonMap, radius: Option<f32>) -> DiffusionEstimate {
    let settings = EstimatorSettings {
        radius,
        ..EstimatorSettings::default()
    };
    match settings.resolve(map).expect("diffusion settings") {
        ResolvedEstimator::Diffusion(d) => d,
        _ => unreachable!("the default estimator is the diffusion estimate"),
    }
}

/// `count` photons on the plane z = 0: `spot` of them in a Gaussian spot of σ = 0.01 at the
/// centre, the rest uniform over the unit square; total power 1.
fn caustic(count: usize, spot: f64, seed: u64) -> Vec<Photon> {
    let mut rng = Rng(seed);
    let power = Vec3::splat(1.0 / count as f32);
    (0..count)
        .map(|i| {
            let (x, y) = if (i as f64) < spot * count as f64 {
                // Box–Muller.
                let (u, v) = (rng.unit().max(1e-7), rng.unit());
                let r = 0.01 * (-2.0 * u.ln()).sqrt();
                let t = std::f32::consts::TAU * v;
                (0.5 + r * t.cos(), 0.5 + r * t.sin())
            } else {
                (rng.unit(), rng.unit())
            };
            Photon::new(Vec3::new(x, y, 0.0), power, -Vec3::Z, Vec3::Z)
        })
        .collect()
}

fn cost(c: &mut Criterion) {
    let two = pool(2);
    let load_before = load_average();
    let mut group = c.benchmark_group("diffusion_cost");
    group
        .sample_size(SAMPLES)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(8));

    // 1. r = 0.02 on the constructed distribution.
    let distribution = Distribution::new(DistributionName::Constructed, PHOTONS);
    let mut map = PhotonMap::build(distribution.photons(1), PHOTONS);
    let grid = Grid {
        width: SIZE,
        height: SIZE,
        extent: Extent::UNIT,
    };
    let cone = EstimatorSettings {
        estimator: EstimatorKind::Cone,
        ..EstimatorSettings::default()
    }
    .resolve(&map)
    .expect("cone settings")
    .into_boxed();
    let wide = diffusion(&map, Some(0.02));
    println!("diffusion: {}", ResolvedEstimator::Diffusion(wide));
    let evaluate = |map: &PhotonMap, e: &dyn RadianceEstimate| {
        two.install(|| grid::evaluate(&grid, map, e, &ProgressBar::hidden()))
    };
    let (cone_s, gradient_s, estimate_s) =
        (Samples::default(), Samples::default(), Samples::default());
    group.bench_function("cone_k400", |b| {
        cone_s.time(b, || {
            std::hint::black_box(evaluate(&map, cone.as_ref()));
        })
    });
    group.bench_function("diffusion_r002_gradient_pass", |b| {
        gradient_s.time(b, || two.install(|| wide.gradient_pass(&mut map)))
    });
    wide.prepare(&mut map);
    let sites = map.gradients().map_or(0, |g| g.sites());
    group.bench_function("diffusion_r002_estimate", |b| {
        estimate_s.time(b, || {
            std::hint::black_box(evaluate(&map, &wide));
        })
    });
    drop(map);

    // 2. Concentrated against spread.
    let mut spread = PhotonMap::build(caustic(PHOTONS as usize, 0.0, 7), PHOTONS);
    let mut focused = PhotonMap::build(caustic(PHOTONS as usize, 0.6, 7), PHOTONS);
    let (own_spread, own_focused) = (diffusion(&spread, None), diffusion(&focused, None));
    let at_spread = diffusion(&focused, Some(own_spread.params().radius));
    let (spread_s, focused_s, focused_at_spread_s) =
        (Samples::default(), Samples::default(), Samples::default());
    group.bench_function("gradient_pass_spread", |b| {
        spread_s.time(b, || two.install(|| own_spread.gradient_pass(&mut spread)))
    });
    group.bench_function("gradient_pass_concentrated", |b| {
        focused_s.time(b, || {
            two.install(|| own_focused.gradient_pass(&mut focused))
        })
    });
    let focused_sites = focused.gradients().map_or(0, |g| g.sites());
    group.bench_function("gradient_pass_concentrated_at_spread_radius", |b| {
        focused_at_spread_s.time(b, || two.install(|| at_spread.gradient_pass(&mut focused)))
    });
    group.finish();

    let row = |name: &str, s: &Samples| {
        println!("| {name} | {:.3} | {:.2} |", s.median(), s.median_cpu());
    };
    println!();
    println!("| measurement (2 threads, medians of {SAMPLES}) | wall s | CPU s |");
    println!("|---|---|---|");
    row("cone k=400, constructed 1M, 512²", &cone_s);
    row("diffusion r=0.02: gradient pass", &gradient_s);
    row("diffusion r=0.02: per-pixel loop", &estimate_s);
    let total = gradient_s.median() + estimate_s.median();
    let total_cpu = gradient_s.median_cpu() + estimate_s.median_cpu();
    println!(
        "| **diffusion r=0.02 / cone k=400** (target ≤ 2) | **{:.2}** | **{:.2}** |",
        total / cone_s.median(),
        total_cpu / cone_s.median_cpu()
    );
    println!("| gradient sites at r=0.02 | {sites} of {PHOTONS} | |");
    println!(
        "| radii resolved: spread r={:.4}, concentrated r={:.4} | | |",
        own_spread.params().radius,
        own_focused.params().radius
    );
    row("gradient pass, spread caustic", &spread_s);
    row("gradient pass, concentrated caustic", &focused_s);
    row(
        "gradient pass, concentrated caustic at the spread radii",
        &focused_at_spread_s,
    );
    println!(
        "| **concentrated / spread** (target ≤ 2) | **{:.2}** | **{:.2}** |",
        focused_s.median() / spread_s.median(),
        focused_s.median_cpu() / spread_s.median_cpu()
    );
    println!(
        "| concentrated at the spread radii / spread | {:.2} | {:.2} |",
        focused_at_spread_s.median() / spread_s.median(),
        focused_at_spread_s.median_cpu() / spread_s.median_cpu()
    );
    println!("| concentrated map's gradient sites | {focused_sites} of {PHOTONS} | |");
    println!(
        "| load average before / after | {load_before} / {} | |",
        load_average()
    );
}

criterion_group!(benches, cost);
criterion_main!(benches);
