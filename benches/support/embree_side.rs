//! The Embree side of the trace bench, shared by `benches/trace.rs` (the backend the bench was
//! built with, in process) and `examples/embree_rays.rs` (the other backend, in a helper
//! process): the same closest-hit loop, the same CPU clock, and the rays handed between them.

use dpm::world::World;
use glam::Vec3;
use rayon::prelude::*;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

/// Rays per rayon task on the Embree side: big enough that scheduling is noise.
pub const RAY_CHUNK: usize = 4096;

/// Closest hits of `rays`, in parallel chunks; returns how many hit (so nothing is optimised
/// away).
pub fn embree_hits(world: &World, rays: &[(Vec3, Vec3)]) -> usize {
    rays.par_chunks(RAY_CHUNK)
        .map(|chunk| {
            chunk
                .iter()
                .filter(|(o, d)| world.closest_hit_distance(*o, *d).is_some())
                .count()
        })
        .sum()
}

/// CPU seconds of every thread of this process so far, to the nanosecond: the first field of
/// each thread's `/proc/self/task/*/schedstat` (Linux; NaN elsewhere). Rayon's workers live as
/// long as their pool, so a difference of two readings around a call counts all its threads.
pub fn cpu_seconds() -> f64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return f64::NAN;
    };
    let mut nanoseconds = 0u64;
    for task in tasks.flatten() {
        let stat = std::fs::read_to_string(task.path().join("schedstat")).unwrap_or_default();
        match stat.split_whitespace().next().map(str::parse::<u64>) {
            Some(Ok(ns)) => nanoseconds += ns,
            _ => return f64::NAN,
        }
    }
    nanoseconds as f64 * 1e-9
}

/// Writes rays as six little-endian `f32`s each (origin, direction).
#[allow(dead_code)] // the example only reads
pub fn write_rays(path: &Path, rays: &[(Vec3, Vec3)]) -> std::io::Result<()> {
    let mut out = BufWriter::new(std::fs::File::create(path)?);
    for (o, d) in rays {
        for x in o.to_array().into_iter().chain(d.to_array()) {
            out.write_all(&x.to_le_bytes())?;
        }
    }
    out.flush()
}

/// Reads what [`write_rays`] wrote.
#[allow(dead_code)] // the bench only writes
pub fn read_rays(path: &Path) -> std::io::Result<Vec<(Vec3, Vec3)>> {
    let mut bytes = Vec::new();
    BufReader::new(std::fs::File::open(path)?).read_to_end(&mut bytes)?;
    let floats: Vec<f32> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    Ok(floats
        .chunks_exact(6)
        .map(|f| (Vec3::new(f[0], f[1], f[2]), Vec3::new(f[3], f[4], f[5])))
        .collect())
}
