//! Photon tracing against Embree alone, on the shipped scenes: the caustic map of
//! `scenes/torus-knot.toml`, and the caustic and global maps of `scenes/cornell-box.toml`.
//!
//! The tracer side times [`trace_photons`] (every path until the target is stored, the photons
//! kept as traced; not the kd-tree, nor the power encoding the map build does as it orders the
//! photons). Two Embree sides time closest-hit queries only:
//! - "embree emission": the first rays of the same paths (the same lights, the same aim at the
//!   specular objects, the same random numbers), as many rays as the tracer casts;
//! - "embree replay": exactly the rays the tracer casts, bounces included, replayed in order.
//!
//! The ratio of the tracer's rays per second to Embree's shows what everything that is not
//! Embree costs. Against emission rays it also carries the difference between first rays and
//! bounce rays (rays leaving a surface, inside glass); against the replay it does not.
//! All run on 1 and 2 threads (rayon pools with flush-to-zero, as the renderer uses). Beside
//! the wall-clock 2-thread speedup, the table gives the speedup on two free cores: one
//! thread's CPU seconds over half of two threads' (all the process's threads, from
//! `/proc/self/task/*/schedstat`), which the machine's other load does not move. The replay
//! ratio is given by CPU seconds as well, for the same reason.
//!
//! Both Embree backends, side by side in one run: Embree 3 and Embree 4 export the same `rtc*`
//! symbols, so one process cannot hold both. The backend the bench is built with (Embree 3 by
//! default) runs in process as above; for the other, the bench builds `examples/embree_rays.rs`
//! with the other feature set (`cargo build --release --example embree_rays [--features
//! embree4]`, the same release profile) and drives it over a pipe: it loads the same scene and
//! the very rays the bench replays, and times the same closest-hit loop on the same pools, one
//! request per timing, so its rounds interleave with the bench's own and the machine's load
//! falls on both backends alike. A second table gives both backends' Embree rays/s and the
//! tracer's ratio to each. When Embree 4 is not fetched (`scripts/fetch-embree4.sh`) the bench
//! says so and leaves that table out.
//!
//! `cargo bench --bench trace`. Criterion prints each figure; then each case runs a few rounds
//! that time every side back to back, and a table of their medians, the ratios and the
//! 2-thread speedups follows at the end. On a shared machine compare those ratios, not
//! absolute times across runs.

#[path = "support/embree_side.rs"]
mod embree_side;
#[path = "support/other_backend.rs"]
mod other_backend;

use criterion::{BenchmarkId, Criterion, Throughput};
use dpm::photon::tracer::{MapKind, TracedPhotons, emission_rays, path_rays, trace_photons};
use dpm::world::World;
use embree_side::{cpu_seconds, embree_hits, write_rays};
use indicatif::ProgressBar;
use other_backend::Helper;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const SEED: u64 = 7;
const THREADS: [usize; 2] = [1, 2];

struct Case {
    name: &'static str,
    scene: &'static str,
    kind: MapKind,
    target: usize,
}

const CASES: [Case; 3] = [
    Case {
        name: "torus-knot caustic",
        scene: "scenes/torus-knot.toml",
        kind: MapKind::Caustic,
        target: 100_000,
    },
    Case {
        name: "cornell-box caustic",
        scene: "scenes/cornell-box.toml",
        kind: MapKind::Caustic,
        target: 100_000,
    },
    Case {
        name: "cornell-box global",
        scene: "scenes/cornell-box.toml",
        kind: MapKind::Global { with_direct: true },
        target: 200_000,
    },
];

/// Which side of the comparison a timing belongs to.
#[derive(Clone, Copy)]
enum Side {
    Tracer = 0,
    Emission = 1,
    Replay = 2,
    /// The other backend, in the helper process.
    OtherEmission = 3,
    OtherReplay = 4,
}

/// Rounds of the closing table: each round times every side on 1 and 2 threads back to back,
/// so that a change in the machine's load falls on all of them alike.
const ROUNDS: usize = 9;

fn world(scene: &str) -> World {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(scene);
    let description = dpm::scene::load(&path).expect("shipped scene loads");
    World::new(description).expect("Embree builds the scene")
}

fn pool(threads: usize) -> rayon::ThreadPool {
    dpm::embree::thread_pool(threads).expect("rayon pool")
}

fn trace(world: &World, case: &Case) -> TracedPhotons {
    trace_photons(
        world,
        case.kind,
        case.target,
        None,
        SEED,
        &ProgressBar::hidden(),
    )
}

/// One case: what the tracer stores and casts (measured once, untimed), and the seconds of
/// each interleaved round by side and thread count.
struct CaseFigures {
    /// `seconds[side][threads index][round]`.
    seconds: [[Vec<f64>; 2]; 5],
    /// The same rounds' CPU seconds, all threads of the process together.
    cpu: [[Vec<f64>; 2]; 5],
    /// The other backend's Embree version, when its helper ran every round.
    other: Option<String>,
    stored: u64,
    rays: u64,
    /// Emission rays: the first rays of as many paths as the tracer casts rays (fewer only
    /// when a path carries no flux and casts nothing).
    emission_rays: u64,
    /// Replayed rays: those of the paths the map keeps (not those traced past the target).
    replay_rays: u64,
}

/// The other backend's helper for one case, loaded with the case's rays (`None`, said why, when
/// it cannot run).
fn other_helper(
    helper: Option<&Path>,
    case: &Case,
    rays: [&[(glam::Vec3, glam::Vec3)]; 2],
) -> Option<(Helper, tempfile::TempDir)> {
    let executable = helper?;
    let dir = tempfile::tempdir().ok()?;
    let files: Vec<PathBuf> = ["emission.rays", "replay.rays"]
        .iter()
        .map(|name| dir.path().join(name))
        .collect();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join(case.scene);
    let spawned = files
        .iter()
        .zip(rays)
        .try_for_each(|(file, rays)| write_rays(file, rays).map_err(|e| e.to_string()))
        .and_then(|_| Helper::spawn(executable, &scene, &files));
    match spawned {
        Ok(helper) => Some((helper, dir)),
        Err(e) => {
            eprintln!("trace bench: {}: other backend left out: {e}", case.name);
            None
        }
    }
}

fn bench_case(
    c: &mut Criterion,
    case: &Case,
    helper: Option<&Path>,
    all_figures: &mut Vec<CaseFigures>,
) {
    let world = world(case.scene);
    let first = pool(1).install(|| trace(&world, case));
    assert_eq!(first.len(), case.target, "{}", case.name);
    let emission = emission_rays(&world, case.kind, SEED, 0..first.rays);
    assert!(!emission.is_empty(), "{}: no emission rays", case.name);
    let replay = path_rays(&world, case.kind, SEED, 0..first.counts.emitted);
    let mut figures = CaseFigures {
        seconds: Default::default(),
        cpu: Default::default(),
        stored: first.len() as u64,
        rays: first.rays,
        emission_rays: emission.len() as u64,
        replay_rays: replay.len() as u64,
        other: None,
    };
    drop(first);

    let mut group = c.benchmark_group(case.name);
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3));
    for threads in THREADS {
        let pool = pool(threads);
        group.throughput(Throughput::Elements(case.target as u64));
        group.bench_function(BenchmarkId::new("tracer photons", threads), |b| {
            b.iter_custom(|iters| {
                let start = Instant::now();
                for _ in 0..iters {
                    black_box(pool.install(|| trace(&world, case)));
                }
                start.elapsed()
            })
        });
        for (name, rays) in [
            ("embree emission rays", &emission),
            ("embree replay rays", &replay),
        ] {
            group.throughput(Throughput::Elements(rays.len() as u64));
            group.bench_function(BenchmarkId::new(name, threads), |b| {
                b.iter_custom(|iters| {
                    let start = Instant::now();
                    for _ in 0..iters {
                        black_box(pool.install(|| embree_hits(&world, rays)));
                    }
                    start.elapsed()
                })
            });
        }
    }
    group.finish();

    let mut other = other_helper(helper, case, [&emission, &replay]);
    let hits = [&emission, &replay].map(|rays| pool(2).install(|| embree_hits(&world, rays)));
    let pools = THREADS.map(pool);
    for _ in 0..ROUNDS {
        for (t, pool) in pools.iter().enumerate() {
            let tracer = seconds_of(|| pool.install(|| trace(&world, case)));
            let emitted = seconds_of(|| pool.install(|| embree_hits(&world, &emission)));
            let replayed = seconds_of(|| pool.install(|| embree_hits(&world, &replay)));
            for (side, (seconds, cpu)) in [
                (Side::Tracer, tracer),
                (Side::Emission, emitted),
                (Side::Replay, replayed),
            ] {
                figures.seconds[side as usize][t].push(seconds);
                figures.cpu[side as usize][t].push(cpu);
            }
            let Some((helper, _)) = other.as_mut() else {
                continue;
            };
            for (set, side) in [(0, Side::OtherEmission), (1, Side::OtherReplay)] {
                match helper.time(set, THREADS[t]) {
                    Ok((seconds, cpu, other_hits)) => {
                        if other_hits != hits[set] {
                            eprintln!(
                                "trace bench: {}: {} hits {other_hits} of ray set {set}, {} {}",
                                case.name,
                                helper.version,
                                dpm::embree::version_string(),
                                hits[set]
                            );
                        }
                        figures.seconds[side as usize][t].push(seconds);
                        figures.cpu[side as usize][t].push(cpu);
                    }
                    Err(e) => {
                        eprintln!("trace bench: {}: other backend stopped: {e}", case.name);
                        other = None;
                        break;
                    }
                }
            }
        }
    }
    figures.other = other.map(|(helper, _)| helper.version.clone());
    all_figures.push(figures);
}

/// Wall-clock and CPU seconds of one call.
fn seconds_of<R>(f: impl FnOnce() -> R) -> (f64, f64) {
    let (start, cpu) = (Instant::now(), cpu_seconds());
    black_box(f());
    (start.elapsed().as_secs_f64(), cpu_seconds() - cpu)
}

fn median(samples: &[f64]) -> f64 {
    let mut v = samples.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n == 0 {
        return f64::NAN;
    }
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Per round: `na / a` (one side's count over its seconds) over `nb / b`; the median of those.
fn per_round_ratio(a: &[f64], na: u64, b: &[f64], nb: u64) -> f64 {
    let per_round: Vec<f64> = (a.iter().zip(b))
        .map(|(sa, sb)| (na as f64 / sa) / (nb as f64 / sb))
        .collect();
    median(&per_round)
}

fn print_table(all_figures: &[CaseFigures]) {
    eprintln!();
    eprintln!(
        "trace bench: medians of {ROUNDS} interleaved rounds, in millions per second; \
         ratio = tracer rays/s / Embree rays/s (median of the per-round ratios; \
         by CPU: the replay ratio from CPU seconds)"
    );
    eprintln!(
        "{:<20} {:>3} {:>9} {:>9} {:>9} {:>6} {:>9} {:>6} {:>6}",
        "case", "thr", "photons", "tracer", "emission", "ratio", "replay", "ratio", "by CPU"
    );
    for (case, figures) in CASES.iter().zip(all_figures) {
        let seconds = |side: Side, t: usize| &figures.seconds[side as usize][t];
        let cpu = |side: Side, t: usize| &figures.cpu[side as usize][t];
        let ratio = |(a, na): (Side, u64), (b, nb): (Side, u64), (ta, tb): (usize, usize)| {
            per_round_ratio(seconds(a, ta), na, seconds(b, tb), nb)
        };
        // The same by CPU seconds: time the thread spent off the core, waiting on the
        // machine's other load, drops out.
        let cpu_ratio = |(a, na): (Side, u64), (b, nb): (Side, u64), t: usize| {
            per_round_ratio(cpu(a, t), na, cpu(b, t), nb)
        };
        let tracer = (Side::Tracer, figures.rays);
        let emission = (Side::Emission, figures.emission_rays);
        let replay = (Side::Replay, figures.replay_rays);
        for (t, threads) in THREADS.iter().enumerate() {
            let rate = |(side, n): (Side, u64)| n as f64 / median(seconds(side, t)) / 1e6;
            eprintln!(
                "{:<20} {:>3} {:>9.3} {:>9.3} {:>9.3} {:>6.2} {:>9.3} {:>6.2} {:>6.2}",
                case.name,
                threads,
                rate((Side::Tracer, figures.stored)),
                rate(tracer),
                rate(emission),
                ratio(tracer, emission, (t, t)),
                rate(replay),
                ratio(tracer, replay, (t, t)),
                cpu_ratio(tracer, replay, t),
            );
        }
        let speedup = |side| ratio(side, side, (1, 0));
        // On two free cores: one thread's CPU time over half of two threads' (medians). It
        // leaves out the machine's other load, which the wall-clock speedup carries.
        let free_cores = |side: Side| median(cpu(side, 0)) / (0.5 * median(cpu(side, 1)));
        eprintln!(
            "{:<20}     2-thread speedup: tracer {:.2}, emission {:.2}, replay {:.2}; \
             on two free cores (CPU): tracer {:.2}, replay {:.2}; rays per stored photon {:.2}",
            "",
            speedup(tracer),
            speedup(emission),
            speedup(replay),
            free_cores(Side::Tracer),
            free_cores(Side::Replay),
            figures.rays as f64 / figures.stored as f64
        );
    }
}

fn main() {
    let mut criterion = Criterion::default().configure_from_args();
    let helper = other_backend::build()
        .inspect_err(|e| eprintln!("trace bench: the other Embree backend is left out: {e}"))
        .ok();
    let mut all_figures = Vec::new();
    for case in &CASES {
        bench_case(&mut criterion, case, helper.as_deref(), &mut all_figures);
    }
    criterion.final_summary();
    if all_figures.len() == CASES.len() {
        print_table(&all_figures);
        print_backends_table(&all_figures);
    }
}

/// Both backends side by side: each one's Embree rays/s and the tracer's ratio to each, for the
/// cases whose helper ran every round.
fn print_backends_table(all_figures: &[CaseFigures]) {
    let Some(other) = all_figures.iter().find_map(|f| f.other.clone()) else {
        return;
    };
    let own = dpm::embree::version_string();
    eprintln!();
    eprintln!(
        "trace bench: both Embree backends, {own} (A, in process) and {other} (B, helper \
         process); medians of {ROUNDS} interleaved rounds, in millions of rays per second; \
         ratio = tracer rays/s / that backend's replay rays/s (median of the per-round ratios, \
         and from CPU seconds); B/A = replay rays/s of B over A"
    );
    eprintln!(
        "{:<20} {:>3} {:>9} {:>9} {:>9} {:>6} {:>6} {:>9} {:>9} {:>6} {:>6} {:>6} {:>6}",
        "case",
        "thr",
        "tracer",
        "A emiss.",
        "A replay",
        "ratio",
        "by CPU",
        "B emiss.",
        "B replay",
        "ratio",
        "by CPU",
        "B/A",
        "by CPU"
    );
    for (case, figures) in CASES.iter().zip(all_figures) {
        if figures.other.is_none() {
            continue;
        }
        let seconds = |side: Side, t: usize| &figures.seconds[side as usize][t];
        let cpu = |side: Side, t: usize| &figures.cpu[side as usize][t];
        let (tracer, replay) = (figures.rays, figures.replay_rays);
        for (t, threads) in THREADS.iter().enumerate() {
            let rate = |side: Side, n: u64| n as f64 / median(seconds(side, t)) / 1e6;
            let ratio = |a: Side, na: u64, b: Side, nb: u64| {
                (
                    per_round_ratio(seconds(a, t), na, seconds(b, t), nb),
                    per_round_ratio(cpu(a, t), na, cpu(b, t), nb),
                )
            };
            let own = ratio(Side::Tracer, tracer, Side::Replay, replay);
            let other = ratio(Side::Tracer, tracer, Side::OtherReplay, replay);
            let b_over_a = ratio(Side::OtherReplay, replay, Side::Replay, replay);
            eprintln!(
                "{:<20} {:>3} {:>9.3} {:>9.3} {:>9.3} {:>6.2} {:>6.2} {:>9.3} {:>9.3} {:>6.2} {:>6.2} {:>6.2} {:>6.2}",
                case.name,
                threads,
                rate(Side::Tracer, tracer),
                rate(Side::Emission, figures.emission_rays),
                rate(Side::Replay, replay),
                own.0,
                own.1,
                rate(Side::OtherEmission, figures.emission_rays),
                rate(Side::OtherReplay, replay),
                other.0,
                other.1,
                b_over_a.0,
                b_over_a.1,
            );
        }
    }
}
