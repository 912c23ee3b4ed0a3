//! Time per radiance estimate of every estimate (simple, cone, Gaussian, Epanechnikov,
//! diffusion) at about 50, 200 and 400 photons per estimate, on the constructed distribution
//! with 1,000,000 photons. Queries lie in a flat region (inside the rectangle, away from its
//! edges), so every query gathers about the same number of photons: the k-NN estimates use
//! k = 50, 200, 400; the fixed-radius estimates use the radius whose measured mean photon count
//! per query there is that number (printed). The bare searches (k-nearest, radius) are timed as
//! well, to show what an estimate adds on top of its search.
//!
//! A batch of queries runs on one thread, so the figures are the cost of one estimate on one
//! core (criterion's throughput is estimates per second). The diffusion estimate's gradient
//! pass runs once per radius before its timing and is excluded (it is per map, not per query;
//! `benches/paper.rs` times it). The summary at the end uses the median of the 10 samples.
//!
//! `cargo bench --bench estimate` (a few minutes).

mod support;

use support::Rng;

use criterion::{
    Bencher, BenchmarkId, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use dpm::density::{Distribution, DistributionName};
use dpm::estimate::diffusion::compute_gradients;
use dpm::estimate::{
    EstimatorKind, EstimatorSettings, Query, RadianceEstimate, ResolvedEstimator, Scratch,
};
use dpm::photon::PhotonMap;
use glam::Vec3;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::time::{Duration, Instant};

const PHOTONS: u64 = 1_000_000;
const QUERIES: usize = 2048;
const SAMPLES: usize = 10;
const COUNTS: [usize; 3] = [50, 200, 400];

/// Points inside the constructed distribution's rectangle (centre (0.74, 0.70), half-sizes
/// 0.14 × 0.12), at least 0.04 from its edges: a flat region at the shapes' density.
fn flat_queries(n: usize) -> Vec<Query> {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    (0..n)
        .map(|_| Query {
            position: Vec3::new(
                0.74 + (rng.unit() * 2.0 - 1.0) * 0.10,
                0.70 + (rng.unit() * 2.0 - 1.0) * 0.08,
                0.0,
            ),
            normal: Vec3::Z,
        })
        .collect()
}

fn mean_count(map: &PhotonMap, queries: &[Query], radius: f32) -> f64 {
    let mut total = 0usize;
    for q in queries {
        map.tree()
            .for_each_within(q.position, radius * radius, |_, _| total += 1);
    }
    total as f64 / queries.len() as f64
}

/// The radius whose mean photon count over `queries` is about `target` (the count grows with
/// the disc's area, so a few rescalings by √(target/count) converge).
fn radius_for(map: &PhotonMap, queries: &[Query], target: usize) -> (f32, f64) {
    let mut r = 0.005f32;
    for _ in 0..4 {
        let n = mean_count(map, queries, r);
        r *= (target as f64 / n.max(1.0)).sqrt() as f32;
    }
    (r, mean_count(map, queries, r))
}

/// Per-iteration seconds of every call criterion makes; the last [`SAMPLES`] are the measured
/// samples (flat sampling: one call per sample, after the warm-up calls).
#[derive(Default)]
struct Samples(RefCell<BTreeMap<String, Vec<f64>>>);

impl Samples {
    fn time(&self, b: &mut Bencher, key: &str, mut f: impl FnMut() -> f32) {
        b.iter_custom(|iters| {
            let start = Instant::now();
            for _ in 0..iters {
                std::hint::black_box(f());
            }
            let elapsed = start.elapsed();
            self.0
                .borrow_mut()
                .entry(key.to_string())
                .or_default()
                .push(elapsed.as_secs_f64() / iters as f64);
            elapsed
        });
    }

    /// Median nanoseconds per query of `key`.
    fn ns_per_query(&self, key: &str) -> f64 {
        let all = self.0.borrow();
        let Some(v) = all.get(key) else {
            return f64::NAN;
        };
        let mut last = v[v.len().saturating_sub(SAMPLES)..].to_vec();
        last.sort_by(f64::total_cmp);
        let n = last.len();
        let m = if n % 2 == 1 {
            last[n / 2]
        } else {
            0.5 * (last[n / 2 - 1] + last[n / 2])
        };
        m * 1e9 / QUERIES as f64
    }
}

/// Runs every query once on this thread; the sum keeps the work from being optimised away.
fn batch(map: &PhotonMap, e: &dyn RadianceEstimate, queries: &[Query], s: &mut Scratch) -> f32 {
    queries
        .iter()
        .map(|q| e.irradiance(map, q, s).x)
        .sum::<f32>()
}

fn settings(estimator: EstimatorKind, k: usize, radius: Option<f32>) -> EstimatorSettings {
    EstimatorSettings {
        estimator,
        k,
        radius,
        ..EstimatorSettings::default()
    }
}

fn estimate(c: &mut Criterion) {
    let distribution = Distribution::new(DistributionName::Constructed, PHOTONS);
    let mut map = PhotonMap::build(distribution.photons(1), PHOTONS);
    let queries = flat_queries(QUERIES);
    let radii: Vec<(f32, f64)> = COUNTS
        .iter()
        .map(|&n| radius_for(&map, &queries, n))
        .collect();
    for (n, (r, count)) in COUNTS.iter().zip(&radii) {
        println!("~{n} photons: radius {r:.6} holds {count:.1} photons per query on average");
    }

    let samples = Samples::default();
    let mut scratch = Scratch::default();
    let mut group = c.benchmark_group("estimate_constructed_1M_flat");
    group
        .sample_size(SAMPLES)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(QUERIES as u64));
    for (&n, &(r, _)) in COUNTS.iter().zip(&radii) {
        let id = |name: &str| BenchmarkId::new(name, n);
        let key = |name: &str| format!("{name}/{n}");
        group.bench_function(id("knn_query_only"), |b| {
            samples.time(b, &key("knn_query_only"), || {
                let mut s = 0.0;
                for q in &queries {
                    map.tree()
                        .k_nearest(q.position, n, f32::INFINITY, &mut scratch.neighbours);
                    s += scratch.neighbours.farthest().map_or(0.0, |f| f.dist2);
                }
                s
            })
        });
        group.bench_function(id("radius_search_only"), |b| {
            samples.time(b, &key("radius_search_only"), || {
                let mut s = 0.0;
                for q in &queries {
                    map.tree()
                        .within_radius(q.position, r * r, &mut scratch.neighbours);
                    s += scratch.neighbours.len() as f32;
                }
                s
            })
        });
        for kind in [
            EstimatorKind::Simple,
            EstimatorKind::Cone,
            EstimatorKind::Gaussian,
        ] {
            let e = settings(kind, n, None).build(&map).expect("k-NN settings");
            group.bench_function(id(e.name()), |b| {
                samples.time(b, &key(e.name()), || {
                    batch(&map, e.as_ref(), &queries, &mut scratch)
                })
            });
        }
        let e = settings(EstimatorKind::Epanechnikov, n, Some(r))
            .build(&map)
            .expect("fixed-radius settings");
        group.bench_function(id(e.name()), |b| {
            samples.time(b, &key(e.name()), || {
                batch(&map, e.as_ref(), &queries, &mut scratch)
            })
        });
        let ResolvedEstimator::Diffusion(d) = settings(EstimatorKind::Diffusion, n, Some(r))
            .resolve(&map)
            .expect("diffusion settings")
        else {
            unreachable!("diffusion settings resolve to the diffusion estimate")
        };
        map.set_gradients(
            &compute_gradients(&map, d.gradient_radius()),
            d.gradient_radius(),
        );
        group.bench_function(id("diffusion"), |b| {
            samples.time(b, &key("diffusion"), || {
                batch(&map, &d, &queries, &mut scratch)
            })
        });
    }
    group.finish();

    println!();
    println!(
        "ns per estimate, one thread, medians of {SAMPLES} samples of {QUERIES} queries \
         ({PHOTONS} photons, flat region)"
    );
    println!("| estimate | ~50 photons | ~200 photons | ~400 photons |");
    println!("|---|---|---|---|");
    for name in [
        "knn_query_only",
        "simple",
        "cone",
        "gaussian",
        "radius_search_only",
        "epanechnikov",
        "diffusion",
    ] {
        let cells: Vec<String> = COUNTS
            .iter()
            .map(|n| format!("{:.0}", samples.ns_per_query(&format!("{name}/{n}"))))
            .collect();
        println!("| {name} | {} |", cells.join(" | "));
    }
    let counts: Vec<String> = radii
        .iter()
        .map(|(r, c)| format!("r = {r:.5} ({c:.0})"))
        .collect();
    println!(
        "| radius (mean photons) of the fixed-radius rows | {} |",
        counts.join(" | ")
    );
}

criterion_group!(benches, estimate);
criterion_main!(benches);
