//! Photon tracing (Jensen's first pass): photons leave the lights in proportion to their power,
//! Embree finds every hit (through [`World`]), mirrors and glass redirect them (Fresnel, total
//! internal reflection), diffuse surfaces store them and reflect them with Russian roulette.
//! Two maps: the caustic map (light → specular+ → diffuse) and the global map (indirect diffuse).
//! Owns paths and photon bookkeeping; must not estimate radiance or shade pixels.
//!
//! Determinism: path `i` draws only from `Rng::for_index(seed, stream, i)` and paths are kept in
//! index order, so the maps are identical whatever the thread count.

use super::{EncodedDirections, Photon, PhotonAttributes, PhotonMap};
use crate::optics::{reflect, scatter_dielectric};
use crate::sampling::{Rng, Stream, StreamSeed, cosine_hemisphere};
use crate::scene::Material;
use crate::world::aim::UnionOfCones;
use crate::world::lights::{self, Emission, LightEmitter};
use crate::world::{BoundingSphere, ClosestHit, SHADING_AGREEMENT_MIN_COS, Surface, World};
use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

/// Which map a tracing pass fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Light → specular+ → diffuse. Paths end at their first diffuse hit.
    Caustic,
    /// Photons on diffuse surfaces after at least one diffuse bounce (`with_direct`: every
    /// diffuse hit, as final gathering needs).
    Global { with_direct: bool },
}

/// What a pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCounts {
    pub emitted: u64,
    pub stored: u64,
}

/// Paths longer than this are cut: a photon trapped between mirrors must not loop forever.
const MAX_BOUNCES: u32 = 32;

/// A photon as traced, before the flux is divided by the number of paths emitted (32 bytes:
/// the directions are encoded as stored, since their encoding does not depend on that number).
#[derive(Clone, Copy)]
pub(super) struct TracedPhoton {
    pub(super) position: Vec3,
    pub(super) flux: Vec3,
    pub(super) directions: EncodedDirections,
    /// The path that stored it, counted from the first path of its chunk: where a pass that
    /// reaches its target stops counting.
    path_in_chunk: u32,
}

impl TracedPhoton {
    /// The stored photon, its flux multiplied by `scale` (one over the paths emitted).
    fn record(&self, scale: f32) -> Photon {
        Photon::with_directions(self.position, self.flux * scale, self.directions)
    }
}

/// Splits photon paths among the lights in proportion to their power.
struct LightChooser {
    cdf: Vec<f32>,
    /// Probability of each light.
    pdf: Vec<f32>,
}

impl LightChooser {
    fn new(world: &World) -> Option<Self> {
        let w: Vec<f32> = (world.light_sources.iter())
            .map(|l| lights::weight(l.power()))
            .collect();
        let total: f32 = w.iter().sum();
        if total.is_nan() || total <= 0.0 || !total.is_finite() {
            return None;
        }
        let pdf: Vec<f32> = w.iter().map(|x| x / total).collect();
        let mut acc = 0.0;
        let cdf = pdf.iter().map(|p| {
            acc += p;
            acc
        });
        Some(Self {
            cdf: cdf.collect(),
            pdf,
        })
    }

    fn pick(&self, u: f32) -> usize {
        self.cdf
            .iter()
            .position(|&c| u < c)
            .unwrap_or(self.cdf.len() - 1)
    }
}

/// How the paths of one pass start: which light, aimed where, with which random numbers.
pub(super) struct Emitter<'w> {
    pub(super) world: &'w World,
    chooser: LightChooser,
    /// One per light, in the scene's order.
    lights: Vec<LightEmitter>,
    streams: StreamSeed,
    ray_epsilon: f32,
}

/// The start of a path that carries flux.
pub(super) struct PathStart {
    /// The light it left, in the scene's order.
    pub(super) light: usize,
    rng: Rng,
    origin: Vec3,
    pub(super) direction: Vec3,
    flux: Vec3,
}

impl<'w> Emitter<'w> {
    /// A pass's emitter: caustic photons aimed at the targets, through the world's caustic
    /// guide where it has one.
    fn new(world: &'w World, kind: MapKind, seed: u64) -> Option<Self> {
        let targets = world.caustic_targets.as_slice();
        match kind {
            MapKind::Caustic => Self::with(world, targets, Stream::CausticPhotons, seed, true),
            MapKind::Global { .. } => Self::with(world, &[], Stream::GlobalPhotons, seed, false),
        }
    }

    /// The caustic guide's pilot paths: aimed, never guided, on their own stream.
    pub(super) fn pilots(world: &'w World, seed: u64) -> Option<Self> {
        let targets = world.caustic_targets.as_slice();
        Self::with(world, targets, Stream::CausticPilots, seed, false)
    }

    /// Paths from `stream`, aimed at `aim` (none: unaimed), through the world's caustic guide
    /// when `guided`.
    fn with(
        world: &'w World,
        aim: &[BoundingSphere],
        stream: Stream,
        seed: u64,
        guided: bool,
    ) -> Option<Self> {
        let lights = (world.light_sources.iter().enumerate())
            .map(|(l, light)| {
                let mut emitter = LightEmitter::new(light, aim);
                if let (true, Some(cells)) = (guided, world.caustic_guide.get(l).cloned().flatten())
                {
                    emitter.guide(cells);
                }
                emitter
            })
            .collect();
        Some(Self {
            world,
            chooser: LightChooser::new(world)?,
            lights,
            streams: StreamSeed::new(seed, stream),
            ray_epsilon: world.ray_epsilon(),
        })
    }

    /// Light `l`'s emitter.
    pub(super) fn light(&self, l: usize) -> &LightEmitter {
        &self.lights[l]
    }

    /// Path `index`: its generator (for the rest of the path) and first ray, or `None` when it
    /// carries no flux and so casts no ray.
    #[inline(always)]
    pub(super) fn start(&self, index: u64) -> Option<PathStart> {
        let mut rng = self.streams.rng(index);
        let l = self.chooser.pick(rng.next_f32());
        let Emission {
            origin,
            direction,
            flux,
        } = self.lights[l].emit(&mut rng);
        let flux = flux / self.chooser.pdf[l];
        (flux.max_element() > 0.0).then(|| PathStart {
            light: l,
            rng,
            // Just off the light: the first ray would otherwise hit the light's own surface.
            origin: origin + direction * self.ray_epsilon,
            direction,
            flux,
        })
    }
}

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
    trace_map_within(world, kind, target, None, seed, progress)
}

/// [`trace_map`] emitting at most `max_paths` paths when given (the map is left short).
pub fn trace_map_within(
    world: &World,
    kind: MapKind,
    target: usize,
    max_paths: Option<u64>,
    seed: u64,
    progress: &ProgressBar,
) -> (PhotonMap, TraceCounts) {
    let traced = trace_photons(world, kind, target, max_paths, seed, progress);
    if traced.interrupted {
        // Not worth building: the caller discards it.
        return (PhotonMap::default(), traced.counts);
    }
    let counts = traced.counts;
    (traced.into_map(), counts)
}

/// The photons of one pass, before any kd-tree is built: in path index order, as traced, with
/// the flux not yet divided by the number of paths emitted. Their power is encoded where the map
/// orders them ([`TracedPhotons::into_map`]): one pass over the photons, not two.
pub struct TracedPhotons {
    /// Runs of consecutive paths' photons, in order.
    chunks: Vec<Vec<TracedPhoton>>,
    len: usize,
    pub counts: TraceCounts,
    /// Closest-hit rays cast, counting the paths traced past the target too.
    pub rays: u64,
    /// An interruption was requested: there are no photons, and the pass must be discarded.
    pub interrupted: bool,
}

impl TracedPhotons {
    fn new(chunks: Vec<Vec<TracedPhoton>>, counts: TraceCounts, rays: u64) -> Self {
        Self {
            len: chunks.iter().map(Vec::len).sum(),
            chunks,
            counts,
            rays,
            interrupted: false,
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn flux_scale(&self) -> f32 {
        1.0 / self.counts.emitted.max(1) as f32
    }

    /// The stored photons, in path order.
    pub fn photons(&self) -> Vec<Photon> {
        let scale = self.flux_scale();
        (self.chunks.iter().flatten())
            .map(|p| p.record(scale))
            .collect()
    }

    /// The photon map of these photons: the same map as [`PhotonMap::build`] of
    /// [`TracedPhotons::photons`]. Each chunk is encoded (in parallel) into positions and
    /// attributes and freed before the kd-tree is built, so the 32-byte traced photons are gone
    /// by the time the tree and the map's attributes take their memory.
    pub fn into_map(self) -> PhotonMap {
        let scale = self.flux_scale();
        let emitted = self.counts.emitted;
        let encoded: Vec<(Vec<Vec3>, Vec<PhotonAttributes>)> = (self.chunks.into_par_iter())
            .map(|chunk| {
                let encoded = chunk
                    .iter()
                    .map(|p| (p.position, p.record(scale).attributes()))
                    .unzip();
                drop(chunk);
                encoded
            })
            .collect();
        let mut positions = Vec::with_capacity(self.len);
        let mut attributes = Vec::with_capacity(self.len);
        for (p, a) in encoded {
            positions.extend_from_slice(&p);
            attributes.extend_from_slice(&a);
        }
        PhotonMap::from_sources(positions, |i| attributes[i], emitted)
    }
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
                emitted = chunk.start + u64::from(chunk.photons[room - 1].path_in_chunk) + 1;
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

/// A path on its way: its next ray and what it carries.
pub(super) struct LivePath {
    path_in_chunk: u32,
    pub(super) rng: Rng,
    origin: Vec3,
    direction: Vec3,
    pub(super) flux: Vec3,
    bounces: u32,
    pub(super) specular_seen: bool,
    pub(super) diffuse_seen: bool,
}

impl LivePath {
    pub(super) fn new(path_in_chunk: u32, start: PathStart) -> Self {
        Self {
            path_in_chunk,
            rng: start.rng,
            origin: start.origin,
            direction: start.direction,
            flux: start.flux,
            bounces: 0,
            specular_seen: false,
            diffuse_seen: false,
        }
    }
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
    path.bounces += 1;
    // Leave the surface on the side the new direction points to.
    let side = if next.dot(ng) >= 0.0 { ng } else { -ng };
    path.origin = world.offset_from(&hit, side);
    path.direction = next;
    path.bounces < bounce_limit(world)
}

/// Surfaces a path may meet: the tracer's own limit, or fewer where the scene caps paths
/// (a photon stored on its k-th surface has met k − 1 before it).
#[inline(always)]
fn bounce_limit(world: &World) -> u32 {
    match world.description.transport.photon_bounces() {
        Some(cap) => MAX_BOUNCES.min(cap + 1),
        None => MAX_BOUNCES,
    }
}

/// A Lambert bounce off `position` (unit normal `ns` on the side the photon came from): the
/// direction and its weight cos θ/(π·pdf). Drawn by the cosine, or with probability
/// [`World::diffuse_bounce_aim`] towards the caustic targets (uniformly over their cones),
/// the density the mixture of both; `None` when the aimed direction leaves below the surface.
#[inline(always)]
fn diffuse_bounce(world: &World, position: Vec3, ns: Vec3, rng: &mut Rng) -> Option<(Vec3, f32)> {
    let aim = world.diffuse_bounce_aim;
    let cones = (aim > 0.0)
        .then(|| UnionOfCones::towards(&world.caustic_targets, position))
        .flatten()
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

/// Leaves the path's photon at a diffuse landing (`position`, arriving along `d` on the side
/// of `ns`) when its map keeps such paths: the caustic map those that met a mirror, glass or
/// glossy lobe first, the global map those past a diffuse bounce (or all, `with_direct`).
#[inline(always)]
pub(super) fn store_photon(
    kind: MapKind,
    path: &LivePath,
    position: Vec3,
    d: Vec3,
    ns: Vec3,
    stored: &mut Vec<TracedPhoton>,
) {
    let store = match kind {
        MapKind::Caustic => path.specular_seen,
        MapKind::Global { with_direct } => path.diffuse_seen || with_direct,
    };
    if store {
        stored.push(TracedPhoton {
            position,
            flux: path.flux,
            directions: EncodedDirections::new(d, ns),
            path_in_chunk: path.path_in_chunk,
        });
    }
}

/// Whether a mirror's or glass's tint has left a path nothing to carry.
#[inline(always)]
fn specular_tinted_out(material: &Material, flux: Vec3) -> bool {
    !matches!(material, Material::Diffuse { .. }) && flux.max_element() <= 0.0
}
