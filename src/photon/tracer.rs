//! Photon tracing (Jensen's first pass): photons leave the lights in proportion to their power,
//! Embree finds every hit (through [`World`]), mirrors and glass redirect them (Fresnel, total
//! internal reflection), diffuse surfaces store them and reflect them with Russian roulette.
//! Two maps: the caustic map (light → specular+ → diffuse) and the global map (indirect diffuse).
//! Owns paths and photon bookkeeping; must not estimate radiance or shade pixels.
//!
//! Determinism: path `i` draws only from `Rng::for_index(seed, stream, i)` and paths are kept in
//! index order, so the maps are identical whatever the thread count.

use super::PhotonMap;
pub(super) use super::emitter::Emitter;
use super::medium_scatter::scatter_in_medium;
use super::path::MAX_WALK_EVENTS;
pub use super::path::MapKind;
pub(super) use super::path::{LivePath, bounce_limit, store_photon};
use super::traced::IN_VOLUME;
pub use super::traced::TraceCounts;
pub(super) use super::traced::TracedPhoton;
pub use super::traced::TracedPhotons;
use super::volume::VolumePhoton;
use crate::optics::{reflect, scatter_dielectric};
use crate::sampling::{Rng, cosine_hemisphere};
use crate::scene::Material;
use crate::world::aim::UnionOfCones;
use crate::world::participating::Flight;
use crate::world::{ClosestHit, SHADING_AGREEMENT_MIN_COS, Surface, World};
use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

/// The first ray (origin, unit direction) of each path in `paths`, drawn exactly as
/// [`trace_photons`] draws it (same lights, same aim, same random numbers), for timing Embree
/// alone on the same rays. Paths that carry no flux cast no ray and are left out.
pub fn emission_rays(
    world: &World,
    kind: MapKind,
    seed: u64,
    paths: std::ops::Range<u64>,
) -> Vec<(Vec3, Vec3)> {
    let Some(emitter) = Emitter::new(world, kind, seed) else {
        return Vec::new();
    };
    paths
        .filter_map(|i| emitter.start(i).map(|s| (s.origin, s.direction)))
        .collect()
}

/// Traces paths until `target` photons are stored (or [`MAX_PATHS_PER_PHOTON`] times `target`
/// paths are emitted), and builds the map.
/// Stops early with an empty map when an interruption is requested ([`crate::interrupt`]);
/// the caller must check for it and discard the map.
pub fn trace_map(
    world: &World,
    kind: MapKind,
    target: usize,
    seed: u64,
    progress: &ProgressBar,
) -> (PhotonMap, TraceCounts) {
    let (map, _, counts) = trace_map_within(world, kind, target, None, seed, progress);
    (map, counts)
}

/// [`trace_map`] emitting at most `max_paths` paths when given (the map is left short), with
/// the volume photons the paths left in media (counted in the target with the rest), their
/// power divided by the paths emitted.
pub fn trace_map_within(
    world: &World,
    kind: MapKind,
    target: usize,
    max_paths: Option<u64>,
    seed: u64,
    progress: &ProgressBar,
) -> (PhotonMap, Vec<VolumePhoton>, TraceCounts) {
    let mut traced = trace_photons(world, kind, target, max_paths, seed, progress);
    if traced.interrupted {
        // Not worth building: the caller discards it.
        return (PhotonMap::default(), Vec::new(), traced.counts);
    }
    let counts = traced.counts;
    let volume = traced.take_volume();
    (traced.into_map(), volume, counts)
}

/// What one rayon task traced: a run of consecutive paths.
struct Chunk {
    photons: Vec<TracedPhoton>,
    /// The first path of the run, and one past the last.
    start: u64,
    end: u64,
    rays: u64,
}

/// Paths per rayon task: many tasks per thread so that none waits long at the end of a batch,
/// each long enough (a few hundred microseconds) that scheduling costs nothing; 64 per thread
/// keeps the idle tail at the end of a batch (one thread waiting on the other's last chunk) short.
fn chunk_len(batch: u64) -> u64 {
    let threads = rayon::current_num_threads().max(1) as u64;
    (batch / (threads * 64)).clamp(512, 16_384)
}

/// Paths a wanted photon past which a map is left short.
pub const MAX_PATHS_PER_PHOTON: u64 = 64;

/// Paths past which a map that has kept no photon at all is left empty: its paths never land
/// (a glossy sphere alone, whose reflections leave the scene), and the rest of the path
/// limit would find as few.
pub const EMPTY_AFTER_PATHS: u64 = 1 << 20;

/// The tracing half of [`trace_map_within`], kept apart so that it can be timed on its own;
/// with `max_paths`, at most that many paths are emitted (the map is left short).
///
/// Paths run in batches sized to finish the pass; a batch is split into chunks of consecutive
/// paths, one rayon task each, whose photons are kept in chunk order: the same photons in the
/// same order whatever the thread count.
pub fn trace_photons(
    world: &World,
    kind: MapKind,
    target: usize,
    max_paths: Option<u64>,
    seed: u64,
    progress: &ProgressBar,
) -> TracedPhotons {
    // Under an open sky most paths leave the scene and store nothing: past this many paths a
    // wanted photon the map stays short, still right (flux is over the paths emitted), rather
    // than the pass spending minutes on escaping rays.
    let max_paths = max_paths.unwrap_or_else(|| {
        (target as u64)
            .saturating_mul(MAX_PATHS_PER_PHOTON)
            .max(1_000_000)
    });
    let Some(emitter) = Emitter::new(world, kind, seed) else {
        return TracedPhotons::new(Vec::new(), TraceCounts::default(), 0);
    };
    let mut kept: Vec<Vec<TracedPhoton>> = Vec::new();
    let mut stored = 0usize;
    let mut emitted: u64 = 0;
    let mut rays = 0u64;
    let mut batch = 16_384u64;
    while stored < target
        && emitted < max_paths
        && !(stored == 0 && emitted >= EMPTY_AFTER_PATHS)
        && !crate::interrupt::requested()
    {
        let start = emitted;
        let end = (start + batch).min(max_paths);
        let step = chunk_len(end - start);
        // Photons expected per path so far, to size each chunk's buffer once.
        let rate = if emitted == 0 {
            1.0
        } else {
            stored as f64 / emitted as f64
        };
        let chunks: Vec<Chunk> = (0..(end - start).div_ceil(step) as usize)
            .into_par_iter()
            // One chunk per task. Rayon's default split leaves runs of up to a quarter of the
            // batch on one thread, which nothing can steal: the other thread idled through the
            // last of them.
            .with_max_len(1)
            .map(|c| {
                let c = c as u64;
                let paths = start + c * step..(start + (c + 1) * step).min(end);
                let chunk = trace_chunk(&emitter, kind, paths, rate);
                progress.inc(chunk.photons.len() as u64);
                chunk
            })
            .collect();
        for mut chunk in chunks {
            rays += chunk.rays;
            if stored >= target {
                continue;
            }
            let room = target - stored;
            if chunk.photons.len() < room {
                emitted = chunk.end;
            } else {
                // The pass ends at the path that stores the last photon wanted.
                chunk.photons.truncate(room);
                emitted =
                    chunk.start + u64::from(chunk.photons[room - 1].path_in_chunk & !IN_VOLUME) + 1;
            }
            stored += chunk.photons.len();
            kept.push(chunk.photons);
        }
        progress.set_position(stored as u64);
        // Grow batches towards the expected remainder so few batches are needed, with a little
        // to spare: the paths of a batch past the target are traced for nothing.
        let rate = stored.max(1) as f64 / emitted.max(1) as f64;
        let remaining = (target - stored.min(target)) as f64 / rate;
        batch = if stored == 0 {
            // Nothing has landed yet: grow by steps, to find out soon if nothing ever will.
            (batch * 4).min(EMPTY_AFTER_PATHS)
        } else {
            (remaining * 1.02).clamp(16_384.0, 4_000_000.0) as u64
        };
    }
    if crate::interrupt::requested() {
        let mut traced = TracedPhotons::new(Vec::new(), TraceCounts { emitted, stored: 0 }, rays);
        traced.interrupted = true;
        return traced;
    }
    let counts = TraceCounts {
        emitted,
        stored: stored as u64,
    };
    TracedPhotons::new(kept, counts, rays)
}

/// Paths `paths`, one after another on this thread.
fn trace_chunk(
    emitter: &Emitter,
    kind: MapKind,
    paths: std::ops::Range<u64>,
    photons_per_path: f64,
) -> Chunk {
    let expected = (paths.end - paths.start) as f64 * photons_per_path * 1.1;
    let mut chunk = Chunk {
        photons: Vec::with_capacity(expected as usize + 16),
        start: paths.start,
        end: paths.end,
        rays: 0,
    };
    if crate::interrupt::requested() {
        return chunk;
    }
    for path in paths.clone() {
        if let Some(start) = emitter.start(path) {
            let live = LivePath::new((path - paths.start) as u32, start);
            chunk.rays += trace_path(emitter.world, kind, live, &mut chunk.photons, &mut NoRayLog);
        }
    }
    chunk
}

/// Where a path reports each ray it casts: nowhere when tracing, a list for benchmarks.
pub(super) trait RayLog {
    fn cast(&mut self, origin: Vec3, direction: Vec3);
}

pub(super) struct NoRayLog;

impl RayLog for NoRayLog {
    #[inline(always)]
    fn cast(&mut self, _: Vec3, _: Vec3) {}
}

impl RayLog for Vec<(Vec3, Vec3)> {
    fn cast(&mut self, origin: Vec3, direction: Vec3) {
        self.push((origin, direction));
    }
}

/// Every ray (origin, unit direction) that the paths in `paths` cast, bounces included, in
/// order: Embree alone can then be timed on exactly the tracer's rays.
pub fn path_rays(
    world: &World,
    kind: MapKind,
    seed: u64,
    paths: std::ops::Range<u64>,
) -> Vec<(Vec3, Vec3)> {
    let Some(emitter) = Emitter::new(world, kind, seed) else {
        return Vec::new();
    };
    let (mut rays, mut photons) = (Vec::new(), Vec::new());
    for path in paths {
        if let Some(start) = emitter.start(path) {
            trace_path(
                world,
                kind,
                LivePath::new(0, start),
                &mut photons,
                &mut rays,
            );
            photons.clear();
        }
    }
    rays
}

/// Follows one path until it ends, appending the photons it stores to `stored`; returns the
/// number of rays cast.
pub(super) fn trace_path(
    world: &World,
    kind: MapKind,
    mut path: LivePath,
    stored: &mut Vec<TracedPhoton>,
    log: &mut impl RayLog,
) -> u64 {
    let mut rays = 0;
    loop {
        rays += 1;
        log.cast(path.origin, path.direction);
        let hit = world.closest_hit(path.origin, path.direction, 0.0, f32::INFINITY);
        if let Some(media) = &world.media {
            let t_max = hit.as_ref().map_or(f32::INFINITY, ClosestHit::t);
            let ray = (path.origin, path.direction);
            match media.free_flight(ray, t_max, path.medium, &mut path.rng) {
                Flight::Scattered { t, medium, weight } => {
                    if !scatter_in_medium(world, kind, &mut path, t, medium, weight, stored) {
                        return rays;
                    }
                    continue;
                }
                Flight::Passed { weight, medium } => {
                    path.flux *= weight;
                    path.medium = medium;
                    if path.flux.max_element() <= 0.0 {
                        return rays;
                    }
                }
            }
        }
        if !advance(world, kind, &mut path, hit, stored) {
            return rays;
        }
    }
}

/// Moves one path on by the hit of its last ray, appending a photon to `stored` where it
/// leaves one; returns whether the path goes on.
#[inline(always)]
fn advance(
    world: &World,
    kind: MapKind,
    path: &mut LivePath,
    closest: Option<ClosestHit>,
    stored: &mut Vec<TracedPhoton>,
) -> bool {
    let Some(closest) = closest else {
        return false;
    };
    let Surface::Material(m) = closest.surface else {
        return false;
    };
    let material = world.material(m);
    let d = path.direction;
    if kind == MapKind::Caustic
        && !path.specular_seen
        && matches!(material, Material::Diffuse { .. })
    {
        // Straight from the light to a diffuse surface: no caustic, and nothing more to
        // resolve (most of the rays aimed at a caustic object miss it).
        return false;
    }
    let hit = world.resolve(closest);
    let material = &world.material_at(m, &hit);
    let entering = hit.entering(d);
    let (ng, ns) = hit.facing(d);
    if world.keeps_photon_on_mix(m, material) {
        store_photon(kind, path, hit.position, d, ns, stored);
    }
    let next = match material {
        Material::Diffuse { albedo } => {
            store_photon(kind, path, hit.position, d, ns, stored);
            if kind == MapKind::Caustic {
                return false;
            }
            let survive = albedo.max_element();
            if path.rng.next_f32() >= survive {
                return false;
            }
            // A shading normal far from the face would send every photon its way.
            let leaving = if ns.dot(ng) < SHADING_AGREEMENT_MIN_COS {
                ng
            } else {
                ns
            };
            let Some((next, weight)) = diffuse_bounce(world, hit.position, leaving, &mut path.rng)
            else {
                return false;
            };
            path.flux *= *albedo * (weight / survive);
            path.diffuse_seen = true;
            next
        }
        Material::Mirror { tint } => {
            if kind == MapKind::Caustic && path.diffuse_seen {
                return false;
            }
            path.specular_seen = true;
            path.flux *= *tint;
            reflect(d, ns)
        }
        Material::Glass {
            ior,
            reflect_tint,
            transmit_tint,
        } => {
            path.specular_seen = true;
            let eta = if entering { 1.0 / ior } else { *ior };
            // The branch is drawn with its Fresnel probability, so the flux that goes on is
            // the tint's share alone.
            let (next, branch) = scatter_dielectric(d, ns, eta, path.rng.next_f32());
            path.flux *= branch.pick(*reflect_tint, *transmit_tint);
            next
        }
        Material::Bsdf(model) => {
            match super::bsdf_scatter::scatter(kind, path, &world.bsdf(model), &hit, d, ns, stored)
            {
                Some(next) => next,
                None => return false,
            }
        }
        // `World::material_at` never gives a mix.
        Material::Mix { .. } => return false,
    };
    if specular_tinted_out(material, path.flux) {
        // A tint took everything: nothing left to store.
        return false;
    }
    // Meeting a subsurface surface from under it (reflected back in, or leaving) is part of
    // the walk there, as pbrt's BSSRDF takes entry to exit as one bounce.
    let walking = match (&world.media, path.medium) {
        (Some(media), Some(medium)) => media.is_subsurface(medium),
        _ => false,
    };
    if walking {
        path.walk_events += 1;
    } else {
        path.bounces += 1;
    }
    if let Some(media) = &world.media {
        let normal = hit.geometric_normal;
        path.medium = media.after_surface(hit.geometry, hit.instance, normal, next, path.medium);
    }
    // Leave the surface on the side the new direction points to.
    let side = if next.dot(ng) >= 0.0 { ng } else { -ng };
    path.origin = world.offset_from(&hit, side);
    path.direction = next;
    path.bounces < bounce_limit(world) && path.walk_events < MAX_WALK_EVENTS
}

/// A Lambert bounce off `position` (unit normal `ns` on the side the photon came from): the
/// direction and its weight cos θ/(π·pdf). Drawn by the cosine, or with probability
/// [`World::diffuse_bounce_aim`] towards the caustic targets (in an open scene, the objects
/// whose bounds do not hold `position`: [`World::bounce_targets`]; uniformly over their cones),
/// the density the mixture of both; `None` when the aimed direction leaves below the surface.
#[inline(always)]
fn diffuse_bounce(world: &World, position: Vec3, ns: Vec3, rng: &mut Rng) -> Option<(Vec3, f32)> {
    let aim = world.diffuse_bounce_aim;
    let cones = match world.bounce_targets() {
        _ if aim <= 0.0 => None,
        // An open scene: towards the other objects, whose bounds do not hold the bounce.
        Some(objects) => UnionOfCones::towards_those_outside(objects, position),
        None => UnionOfCones::towards(&world.caustic_targets, position),
    }
    .filter(|cones| !cones.behind(ns));
    let Some(cones) = cones else {
        return Some((cosine_hemisphere(ns, rng.next_2d()), 1.0));
    };
    let next = if rng.next_f32() < aim {
        cones.sample(rng).0
    } else {
        cosine_hemisphere(ns, rng.next_2d())
    };
    let cos = next.dot(ns);
    if cos <= 0.0 {
        return None;
    }
    let pdf = aim * cones.density(next) + (1.0 - aim) * cos * std::f32::consts::FRAC_1_PI;
    Some((next, cos * std::f32::consts::FRAC_1_PI / pdf))
}

/// Whether a mirror's or glass's tint has left a path nothing to carry.
#[inline(always)]
fn specular_tinted_out(material: &Material, flux: Vec3) -> bool {
    !matches!(material, Material::Diffuse { .. }) && flux.max_element() <= 0.0
}
