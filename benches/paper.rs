//! The timing experiment of the paper's Section 4.3 on the constructed distribution: 1,000,000
//! photons estimated on a 512×512 grid, Jensen's cone filter with k = 400 against the diffusion
//! estimate at its defaults (resolved exactly as `dpm density` resolves them, default radius
//! included). The paper reports the diffusion estimate at 63 s against 45 s for the cone filter
//! (1.4×), 12 s of the 63 being the gradient map.
//!
//! What is timed: the photon map (generation and kd-tree build) is made once and excluded from
//! every figure, as the paper's timings exclude photon tracing. The cone total is the per-pixel
//! loop; the diffusion total is the gradient pass plus its per-pixel loop. Both loops run on a
//! rayon pool of 2 threads (the machine's cores); the cone loop is also run on 1 thread for the
//! parallel speedup, and the two images must be identical (determinism). The summary printed at
//! the end uses the median of criterion's 10 measured samples of each, in wall seconds and in
//! the process's CPU seconds (all threads), which shows on a shared machine what wall time
//! cannot: whether two threads do more work than one, and what the image would take on two
//! free cores.
//!
//! `cargo bench --bench paper` (a few minutes on two cores).

#[path = "support/samples.rs"]
mod samples;

use criterion::{Criterion, SamplingMode, criterion_group, criterion_main};
use dpm::density::{Distribution, DistributionName, Extent, Grid, grid};
use dpm::estimate::diffusion::compute_gradients;
use dpm::estimate::{EstimatorKind, EstimatorSettings, RadianceEstimate, ResolvedEstimator};
use dpm::photon::PhotonMap;
use indicatif::ProgressBar;
use rayon::ThreadPool;
use samples::{SAMPLES, Samples, load_average, pool};
use std::time::Duration;

const PHOTONS: u64 = 1_000_000;
const SIZE: usize = 512;
const SEED: u64 = 1;

fn evaluate(
    pool: &ThreadPool,
    grid: &Grid,
    map: &PhotonMap,
    e: &dyn RadianceEstimate,
) -> Vec<glam::Vec3> {
    pool.install(|| grid::evaluate(grid, map, e, &ProgressBar::hidden()))
}

fn paper(c: &mut Criterion) {
    let distribution = Distribution::new(DistributionName::Constructed, PHOTONS);
    let photons = distribution.photons(SEED);
    let mut map = PhotonMap::build(photons, PHOTONS);
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
    .expect("cone settings");
    let ResolvedEstimator::Diffusion(diffusion) = EstimatorSettings::default()
        .resolve(&map)
        .expect("default settings")
    else {
        panic!("the default estimator is the diffusion estimate");
    };
    println!("cone:      {cone}");
    println!("diffusion: {}", ResolvedEstimator::Diffusion(diffusion));
    let cone = cone.into_boxed();
    let (one, two) = (pool(1), pool(2));
    let load_before = load_average();

    let (cone2, cone1, gradients, estimate) = (
        Samples::default(),
        Samples::default(),
        Samples::default(),
        Samples::default(),
    );
    let mut group = c.benchmark_group("paper_constructed_1M_512");
    group
        .sample_size(SAMPLES)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(10));
    group.bench_function("cone_k400_2_threads", |b| {
        cone2.time(b, || {
            std::hint::black_box(evaluate(&two, &grid, &map, cone.as_ref()));
        })
    });
    group.bench_function("cone_k400_1_thread", |b| {
        cone1.time(b, || {
            std::hint::black_box(evaluate(&one, &grid, &map, cone.as_ref()));
        })
    });
    let radius = diffusion.gradient_radius();
    group.bench_function("diffusion_gradient_pass_2_threads", |b| {
        gradients.time(b, || {
            std::hint::black_box(two.install(|| compute_gradients(&map, radius)));
        })
    });
    map.set_gradients(&two.install(|| compute_gradients(&map, radius)), radius);
    group.bench_function("diffusion_estimate_2_threads", |b| {
        estimate.time(b, || {
            std::hint::black_box(evaluate(&two, &grid, &map, &diffusion));
        })
    });
    group.finish();

    // Same image whatever the thread count.
    let (a, b) = (
        evaluate(&one, &grid, &map, cone.as_ref()),
        evaluate(&two, &grid, &map, cone.as_ref()),
    );
    assert!(
        a.iter()
            .zip(&b)
            .all(|(x, y)| x.to_array().map(f32::to_bits) == y.to_array().map(f32::to_bits)),
        "the cone image differs between 1 and 2 threads"
    );

    let cone_total = cone2.median();
    let (g, e) = (gradients.median(), estimate.median());
    let diffusion_total = g + e;
    let (cone_cpu, g_cpu, e_cpu) = (
        cone2.median_cpu(),
        gradients.median_cpu(),
        estimate.median_cpu(),
    );
    let diffusion_cpu = g_cpu + e_cpu;
    println!();
    println!(
        "Section 4.3 on the constructed distribution: {PHOTONS} photons, {SIZE}x{SIZE}, \
         medians of {SAMPLES} samples, photon map build excluded; CPU = user + system seconds \
         of all threads"
    );
    println!("| measurement | wall seconds | CPU seconds |");
    println!("|---|---|---|");
    println!("| cone k=400, 2 threads | {cone_total:.3} | {cone_cpu:.2} |");
    println!("| diffusion gradient pass, 2 threads | {g:.3} | {g_cpu:.2} |");
    println!("| diffusion estimate, 2 threads | {e:.3} | {e_cpu:.2} |");
    println!(
        "| diffusion total (gradient + estimate) | {diffusion_total:.3} | {diffusion_cpu:.2} |"
    );
    println!(
        "| gradient share of diffusion | {:.1}% | {:.1}% |",
        100.0 * g / diffusion_total,
        100.0 * g_cpu / diffusion_cpu
    );
    println!(
        "| diffusion / cone (paper: 63 s / 45 s = 1.40) | {:.2} | {:.2} |",
        diffusion_total / cone_total,
        diffusion_cpu / cone_cpu
    );
    println!(
        "| cone k=400, 1 thread | {:.3} | {:.2} |",
        cone1.median(),
        cone1.median_cpu()
    );
    println!(
        "| cone speedup 1 → 2 threads, wall (target ≥ 1.8×) | {:.2}× | |",
        cone1.median() / cone_total
    );
    let (cpu1, cpu2) = (cone1.median_cpu(), cone2.median_cpu());
    println!(
        "| cone speedup on 2 free cores (1-thread CPU / half the 2-thread CPU) | {:.2}× | |",
        cpu1 / (0.5 * cpu2)
    );
    println!(
        "| cone on 2 free cores (half the 2-thread CPU; target ≤ 1.5 s) | {:.3} | |",
        0.5 * cpu2
    );
    println!(
        "| load average (1, 5, 15 min) before / after | {load_before} / {} | |",
        load_average()
    );
}

criterion_group!(benches, paper);
criterion_main!(benches);
