//! The cost of what one final-gather ray reads where it lands: the nearest agreeing point of
//! the precomputed irradiance table (`--irradiance-stride 4`, the integrator's lookup with its
//! fallback to the full estimate) against one k-NN global estimate (constant kernel,
//! k = `--global-k`'s default 100, as pass 0 runs it: no cap), on the Cornell box's global map
//! of 200,000 stored photons (direct ones included, as final gathering traces it). The table's
//! precompute, the per-pass phase it adds, is timed too (on every thread).
//!
//! Queries are the photons of a second, independently traced map (their positions and normals):
//! points on the box's surfaces where light lands, visited in a shuffled order as gather rays
//! visit them. A batch of queries runs on one thread, so the per-query figures are the cost on
//! one core. The summary at the end gives the medians of the 10 samples and their ratio.
//!
//! The same for an eye hit on a sparse global map shown directly: the split table of
//! [`ShownIrradiance`] (its two nearest sites, with the fallback) against the k-NN estimate, on
//! the torus knot's lone global map (the floor lit through the knot: 100,000 paths, about 900
//! photons), the queries the photons of a second such map.
//!
//! `cargo bench --bench gather` (about a minute).

mod support;

use criterion::measurement::WallTime;
use criterion::{
    Bencher, BenchmarkGroup, Criterion, SamplingMode, Throughput, criterion_group, criterion_main,
};
use dpm::estimate::precomputed::{DEFAULT_STRIDE, ShownIrradiance};
use dpm::estimate::settings::k_equivalent_radius;
use dpm::estimate::{
    KnnEstimate, PrecomputedIrradiance, Query, RadialKernel, RadianceEstimate, Scratch,
};
use dpm::photon::PhotonMap;
use dpm::photon::tracer::{MapKind, trace_map, trace_map_within};
use dpm::world::World;
use glam::Vec3;
use indicatif::ProgressBar;
use std::cell::RefCell;
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{Duration, Instant};
use support::Rng;

const PHOTONS: usize = 200_000;
const GLOBAL_K: usize = 100;
const QUERIES: usize = 4096;
const SAMPLES: usize = 10;

fn cornell_global_map(world: &World, seed: u64) -> PhotonMap {
    let kind = MapKind::Global { with_direct: true };
    trace_map(world, kind, PHOTONS, seed, &ProgressBar::hidden()).0
}

/// Per-iteration seconds of every call criterion makes (flat sampling: the last [`SAMPLES`]
/// are the measured ones).
#[derive(Default)]
struct Samples(RefCell<BTreeMap<&'static str, Vec<f64>>>);

impl Samples {
    fn time(&self, b: &mut Bencher, key: &'static str, mut f: impl FnMut() -> f32) {
        b.iter_custom(|iters| {
            let start = Instant::now();
            for _ in 0..iters {
                std::hint::black_box(f());
            }
            let elapsed = start.elapsed();
            self.0
                .borrow_mut()
                .entry(key)
                .or_default()
                .push(elapsed.as_secs_f64() / iters as f64);
            elapsed
        });
    }

    fn median(&self, key: &str) -> f64 {
        let all = self.0.borrow();
        let v = &all[key];
        let mut last = v[v.len().saturating_sub(SAMPLES)..].to_vec();
        last.sort_by(f64::total_cmp);
        let n = last.len();
        if n % 2 == 1 {
            last[n / 2]
        } else {
            0.5 * (last[n / 2 - 1] + last[n / 2])
        }
    }
}

/// A group with the flat sampling whose samples [`Samples`] keeps.
fn group_of<'a>(c: &'a mut Criterion, name: &str) -> BenchmarkGroup<'a, WallTime> {
    let mut group = c.benchmark_group(name);
    group
        .sample_size(SAMPLES)
        .sampling_mode(SamplingMode::Flat)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3));
    group.throughput(Throughput::Elements(1));
    group
}

/// The per-query medians of the estimate and the lookup over `n` queries, their ratio, and
/// the table's per-pass build (`build`, on every thread).
fn print_medians(samples: &Samples, n: usize, lookup: &str, build: &str) {
    let per_query = |key| samples.median(key) / n as f64 * 1e9;
    let (e, l) = (per_query("estimate"), per_query("lookup"));
    println!("  k-NN estimate (k = {GLOBAL_K}): {e:.0} ns per query (median)");
    println!(
        "  {:<26} {l:.0} ns per query (median), {:.3} of the estimate",
        format!("{lookup}:"),
        l / e
    );
    println!(
        "  {:<26} {:.2} ms per pass",
        format!("{build} (all threads):"),
        samples.median(build) * 1e3
    );
}

/// Times the k-NN estimate ("estimate") and `lookup` with its fallback to the estimate
/// ("lookup") over all `queries`; returns how many lookups fell back.
fn estimate_against_lookup(
    group: &mut BenchmarkGroup<'_, WallTime>,
    samples: &Samples,
    queries: &[Query],
    (map, estimate): (&PhotonMap, &KnnEstimate),
    lookup_name: &str,
    lookup: impl Fn(&Query, &mut Scratch) -> Option<Vec3>,
) -> usize {
    let mut scratch = Scratch::default();
    let fallbacks = queries
        .iter()
        .filter(|q| lookup(q, &mut scratch).is_none())
        .count();
    group.throughput(Throughput::Elements(queries.len() as u64));
    let scratch = RefCell::new(scratch);
    group.bench_function("knn_estimate_k100", |b| {
        samples.time(b, "estimate", || {
            let s = &mut scratch.borrow_mut();
            queries
                .iter()
                .map(|q| estimate.irradiance(map, q, s).x)
                .sum()
        })
    });
    group.bench_function(lookup_name, |b| {
        samples.time(b, "lookup", || {
            let s = &mut scratch.borrow_mut();
            queries
                .iter()
                .map(|q| {
                    lookup(q, s)
                        .unwrap_or_else(|| estimate.irradiance(map, q, s))
                        .x
                })
                .sum()
        })
    });
    fallbacks
}

fn gather(c: &mut Criterion) {
    dpm::embree::enable_flush_to_zero();
    let description = dpm::scene::load(Path::new("scenes/cornell-box.toml")).expect("scene");
    let world = World::new(description).expect("Embree world");
    let map = cornell_global_map(&world, 1);
    let others = cornell_global_map(&world, 2);
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let queries: Vec<Query> = (0..QUERIES)
        .map(|_| {
            let slot =
                ((rng.unit() as f64 * others.len() as f64) as u32).min(others.len() as u32 - 1);
            let p = others.photon(slot);
            Query {
                position: p.position(),
                normal: p.normal(),
            }
        })
        .collect();
    let reach = k_equivalent_radius(&map, GLOBAL_K);
    let estimate = KnnEstimate::new(RadialKernel::Constant, GLOBAL_K, None);
    let samples = Samples::default();

    let mut group = group_of(c, "gather");
    let build = || {
        PrecomputedIrradiance::build(
            &map,
            &estimate,
            DEFAULT_STRIDE,
            reach,
            &ProgressBar::hidden(),
        )
    };
    group.bench_function("precompute_table", |b| {
        samples.time(b, "precompute", || build().len() as f32)
    });
    let table = build();
    let fallbacks = estimate_against_lookup(
        &mut group,
        &samples,
        &queries,
        (&map, &estimate),
        "precomputed_lookup",
        |q, s| table.lookup(q, s),
    );
    group.finish();

    println!(
        "\nCornell box global map, {} photons; table of one photon in {DEFAULT_STRIDE}: {} points, \
         {} heap bytes; {fallbacks} of {QUERIES} lookups fell back to the estimate",
        map.len(),
        table.len(),
        table.heap_bytes()
    );
    print_medians(&samples, QUERIES, "precomputed lookup", "precompute");
}

/// The knot's lone global map as a render's pass traces it by default.
fn knot_sparse_map(world: &World, seed: u64) -> PhotonMap {
    let kind = MapKind::Global { with_direct: false };
    trace_map_within(
        world,
        kind,
        10_000,
        Some(100_000),
        seed,
        &ProgressBar::hidden(),
    )
    .0
}

fn shown(c: &mut Criterion) {
    dpm::embree::enable_flush_to_zero();
    let description = dpm::scene::load(Path::new("scenes/torus-knot.toml")).expect("scene");
    let world = World::new(description).expect("Embree world");
    let map = knot_sparse_map(&world, 1);
    let others = knot_sparse_map(&world, 2);
    let queries: Vec<Query> = (0..others.len() as u32)
        .map(|slot| {
            let p = others.photon(slot);
            Query {
                position: p.position(),
                normal: p.normal(),
            }
        })
        .collect();
    let estimate = KnnEstimate::new(RadialKernel::Constant, GLOBAL_K, None);
    let samples = Samples::default();
    let mut group = group_of(c, "shown");
    let build = || ShownIrradiance::build(&map, &estimate, &ProgressBar::hidden());
    group.bench_function("build_table", |b| {
        samples.time(b, "build", || build().len() as f32)
    });
    let table = build();
    let fallbacks = estimate_against_lookup(
        &mut group,
        &samples,
        &queries,
        (&map, &estimate),
        "table_lookup",
        |q, s| table.lookup(q, s),
    );
    group.finish();

    let n = queries.len();
    println!(
        "\nTorus knot's lone global map, {} photons; split table of {} sites; {fallbacks} of {n} \
         lookups fell back to the estimate",
        map.len(),
        table.len()
    );
    print_medians(&samples, n, "shown-map lookup", "build");
}

criterion_group!(benches, gather, shown);
criterion_main!(benches);
