//! Times `trace_map` (photon tracing and the map build, what a render runs) on one thread: the
//! best of N passes, with the paths emitted. Used to compare two versions of the tracer side by
//! side: build this example on both commits and run them in turn (BENCHMARKS.md, "Photon
//! tracing against raw Embree").
//!
//! `cargo run --release --example trace_map_timing -- SCENE caustic|global PHOTONS PASSES`

use dpm::photon::tracer::{MapKind, trace_map};
use dpm::world::World;
use indicatif::ProgressBar;
use std::path::Path;
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, kind, photons, passes] = args.as_slice() else {
        eprintln!("usage: trace_map_timing SCENE caustic|global PHOTONS PASSES");
        return ExitCode::from(2);
    };
    let kind = match kind.as_str() {
        "caustic" => MapKind::Caustic,
        "global" => MapKind::Global { with_direct: true },
        other => {
            eprintln!("map kind must be caustic or global, got {other:?}");
            return ExitCode::from(2);
        }
    };
    let (Ok(photons), Ok(passes)) = (photons.parse::<usize>(), passes.parse::<usize>()) else {
        eprintln!("PHOTONS and PASSES must be whole numbers");
        return ExitCode::from(2);
    };
    let description = match dpm::scene::load(Path::new(scene)) {
        Ok(d) => d,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let world = match World::new(description) {
        Ok(w) => w,
        Err(e) => {
            eprintln!("{e}");
            return ExitCode::FAILURE;
        }
    };
    let pool = dpm::embree::thread_pool(1).expect("rayon pool");
    let mut best = f64::MAX;
    let mut emitted = 0;
    for _ in 0..passes.max(1) {
        let start = std::time::Instant::now();
        let (map, counts) =
            pool.install(|| trace_map(&world, kind, photons, 7, &ProgressBar::hidden()));
        best = best.min(start.elapsed().as_secs_f64());
        emitted = counts.emitted;
        std::hint::black_box(map);
    }
    println!(
        "{best:.4} s per map (best of {passes}), {:.3} M photons/s, {emitted} paths",
        photons as f64 / best / 1e6
    );
    ExitCode::SUCCESS
}
