//! The trace bench's helper for the Embree backend the bench was not built with (Embree 3 and 4
//! export the same `rtc*` symbols, so one process holds one of them). `cargo bench --bench
//! trace` builds this example for the other backend and drives it; it is not meant to be run by
//! hand.
//!
//! `embree_rays SCENE RAYS...`: builds the scene, reads each ray file (`write_rays`' format),
//! prints `ready <Embree version>`, then answers each line `SET THREADS` on stdin with `WALL CPU
//! HITS`: the seconds (wall clock and all threads' CPU) of closest hits of ray set `SET` on a
//! pool of `THREADS`, exactly as the bench times its own backend. Ends at end of input.

#[path = "../benches/support/embree_side.rs"]
mod embree_side;

use dpm::world::World;
use embree_side::{cpu_seconds, embree_hits, read_rays};
use std::collections::HashMap;
use std::collections::hash_map::Entry;
use std::io::{BufRead, Write};
use std::path::Path;
use std::process::ExitCode;
use std::time::Instant;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("embree_rays: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, ray_files @ ..] = args.as_slice() else {
        return Err("usage: embree_rays SCENE RAYS...".into());
    };
    let description = dpm::scene::load(Path::new(scene)).map_err(|e| e.to_string())?;
    let world = World::new(description).map_err(|e| e.to_string())?;
    let sets = ray_files
        .iter()
        .map(|f| read_rays(Path::new(f)).map_err(|e| format!("{f}: {e}")))
        .collect::<Result<Vec<_>, _>>()?;
    let mut pools = HashMap::new();
    let mut out = std::io::stdout().lock();
    let say = |out: &mut std::io::StdoutLock, line: String| {
        writeln!(out, "{line}")
            .and_then(|_| out.flush())
            .map_err(|e| e.to_string())
    };
    say(&mut out, format!("ready {}", dpm::embree::version_string()))?;
    for line in std::io::stdin().lock().lines() {
        let line = line.map_err(|e| e.to_string())?;
        let mut words = line.split_whitespace().map(str::parse::<usize>);
        let (Some(Ok(set)), Some(Ok(threads))) = (words.next(), words.next()) else {
            return Err(format!("bad request {line:?}"));
        };
        let rays = sets.get(set).ok_or(format!("no ray set {set}"))?;
        let pool = match pools.entry(threads) {
            Entry::Occupied(pool) => pool.into_mut(),
            Entry::Vacant(slot) => {
                slot.insert(dpm::embree::thread_pool(threads).map_err(|e| e.to_string())?)
            }
        };
        let (start, cpu) = (Instant::now(), cpu_seconds());
        let hits = pool.install(|| embree_hits(&world, rays));
        let (wall, cpu) = (start.elapsed().as_secs_f64(), cpu_seconds() - cpu);
        say(&mut out, format!("{wall} {cpu} {hits}"))?;
    }
    Ok(())
}
