//! The memory check made before a render allocates anything: what the photon maps, their
//! gradients and the image will take, against what the machine has. Owns those estimates and
//! the refusal's message; must not trace, estimate or render.
//!
//! The per-photon figure bounds the peak while a map is traced and built; BENCHMARKS.md has the
//! measured peak.

use super::pass::pass_target;
use super::pipeline::RenderError;
use super::schedule::PhotonGrowth;
use crate::estimate::settings::{EstimatorKind, EstimatorSettings};
use crate::photon::store::MapInfo;
use crate::photon::tracer::MapKind;
use crate::world::World;

/// Bytes one stored photon may cost at the peak of tracing and building its map (the tracer's
/// record, the 20-byte photon record, the kd-tree under construction): a bound with a margin;
/// 70 bytes with the gradient were measured at 10 million photons.
pub const BYTES_PER_PHOTON: u64 = 20 + 16 + 48;
/// Extra bytes a caustic photon costs with the diffusion estimate: its packed gradient (7) and
/// the gradient pass's node sums and unpacked result while it runs.
pub const GRADIENT_BYTES: u64 = 12;
/// Bytes each photon of the tensor history costs: its record kept between passes (20) and its
/// place in the map that shapes the kernels, gradient field included (90 at most, the bound of
/// `PhotonMap::bytes_per_photon`'s test).
pub const HISTORY_BYTES: u64 = 20 + 90;
/// Bytes a stored photon may cost in a scene with media, where any of them may be a volume
/// photon: its traced record (32) kept until the pass's maps are split, the volume photon (36)
/// and its radius (4) twice (built, then ordered for the ray query), the positions and kd-tree
/// its radius is found with (12 + 16) and its share of the query's nodes (8). 54.5 bytes a
/// photon were measured for the built maps of pbrt's cloud scene.
pub const VOLUME_BYTES_PER_PHOTON: u64 = 32 + 2 * (36 + 4) + 12 + 16 + 8;
/// Bytes a pixel costs: the film's f64 sums (15 channels), one pass's f32 values, the resolved
/// image, its checked copy and the encoded file in memory.
pub const BYTES_PER_PIXEL: u64 = 240;
/// What is assumed available when /proc/meminfo cannot be read.
pub const FALLBACK_MEMORY: u64 = 16 << 30;

/// Bytes a caustic photon's share of `passes` passes' worth of tensor history costs.
fn history_bytes(passes: f64) -> u64 {
    (passes * HISTORY_BYTES as f64).ceil() as u64
}

/// Estimated peak memory of the photon maps and the image, in bytes (saturating): with the
/// diffusion estimate, `history` passes' worth of earlier caustic photons too. Loaded maps need no
/// tracing records, so for them this is an overestimate.
pub fn memory_estimate(wanted: &[MapInfo], diffusion: Option<f64>, width: u32, height: u32) -> u64 {
    let photons = wanted.iter().fold(0u64, |sum, info| {
        let per = match (diffusion, info.kind) {
            (Some(history), MapKind::Caustic) => {
                BYTES_PER_PHOTON + GRADIENT_BYTES + history_bytes(history)
            }
            _ => BYTES_PER_PHOTON,
        };
        sum.saturating_add(info.target.saturating_mul(per))
    });
    photons.saturating_add((width as u64 * height as u64).saturating_mul(BYTES_PER_PIXEL))
}

/// Memory available to this process: MemAvailable from /proc/meminfo, else
/// [`FALLBACK_MEMORY`]; with where the figure comes from.
pub fn available_memory() -> (u64, &'static str) {
    let from_meminfo = std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|text| {
            let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
            let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kib.saturating_mul(1024))
        });
    match from_meminfo {
        Some(bytes) => (bytes, "MemAvailable in /proc/meminfo"),
        None => (
            FALLBACK_MEMORY,
            "a fixed cap; /proc/meminfo could not be read",
        ),
    }
}

/// Bytes in binary units, e.g. "3.7 GiB".
pub fn human_bytes(bytes: u64) -> String {
    let units = ["bytes", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"];
    let mut value = bytes as f64;
    let mut unit = 0;
    while value >= 1024.0 && unit + 1 < units.len() {
        value /= 1024.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{bytes} bytes")
    } else {
        format!("{value:.1} {}", units[unit])
    }
}

/// Refuses, before anything is allocated, photon counts (and an image size) that would not
/// fit in memory. `wanted` holds pass 0's counts; the caustic map's grows by `growth` up to
/// pass `last_pass`, the last this run may render.
pub(super) fn check_memory(
    estimator: &EstimatorSettings,
    world: &World,
    wanted: &[MapInfo],
    growth: &PhotonGrowth,
    last_pass: u64,
) -> Result<(), RenderError> {
    let peak: Vec<MapInfo> = (wanted.iter())
        .map(|w| MapInfo {
            target: pass_target(w, growth, last_pass),
            ..*w
        })
        .collect();
    let camera = &world.description.camera;
    // Passes' worth of caustic photons the tensor history keeps.
    let diffusion = (estimator.estimator == EstimatorKind::Diffusion)
        .then_some((estimator.history_photons).passes_kept(estimator.tensor_history));
    let (width, height) = camera.image_size();
    let mut needed = memory_estimate(&peak, diffusion, width, height);
    if let Some(media) = &world.media {
        // Any photon may be a volume photon, and the media's grids are held throughout.
        let photons: u64 = peak.iter().map(|p| p.target).sum();
        let extra = VOLUME_BYTES_PER_PHOTON.saturating_sub(BYTES_PER_PHOTON);
        needed = needed
            .saturating_add(photons.saturating_mul(extra))
            .saturating_add(media.bytes() as u64);
    }
    let (available, source) = available_memory();
    if needed <= available {
        return Ok(());
    }
    let mut what: Vec<String> = (wanted.iter().zip(&peak))
        .map(|(w, p)| match w.kind {
            MapKind::Caustic if p.target > w.target => format!(
                "--caustic-photons {} (growing to {} a pass by pass {last_pass}, \
                 --caustic-photons-max {})",
                w.target, p.target, growth.max_photons
            ),
            MapKind::Caustic => format!("--caustic-photons {}", w.target),
            MapKind::Global { .. } => format!("--global-photons {}", w.target),
        })
        .collect();
    what.push(format!("a {}x{} image (camera.resolution)", width, height));
    if let Some(media) = &world.media {
        what.push(format!(
            "the media's grids ({})",
            human_bytes(media.bytes() as u64)
        ));
    }
    Err(RenderError::Invalid(format!(
        "{} would need about {} of memory ({} bytes a photon{}, {BYTES_PER_PIXEL} a pixel), but \
         only {} is available ({source}); lower the photon counts or the resolution",
        what.join(", "),
        human_bytes(needed),
        if world.media.is_some() {
            VOLUME_BYTES_PER_PHOTON
        } else {
            BYTES_PER_PHOTON
        },
        match diffusion {
            Some(history) => format!(
                ", {} a caustic photon with its gradient and {history:.2} passes' worth of tensor history",
                BYTES_PER_PHOTON + GRADIENT_BYTES + history_bytes(history)
            ),
            None => String::new(),
        },
        human_bytes(available),
    )))
}
