//! What an open scene's global map costs and buys, decided once per render before pass 0. In
//! an open scene (a product on a floor under the sky) most diffuse bounces drawn by the
//! cosine leave it: a probe of paths finds a stored photon for more than
//! [`OPEN_PATHS_PER_PHOTON`] of them, and half the global photons' bounces then aim at the
//! other objects (`World::aim_bounces_at_objects`). And there the global map is often a small
//! part of the image: a probe map and a grid of camera rays measure its share of the
//! irradiance the camera sees, and a pass stores photons in proportion to that share (the
//! full count from [`FULL_SHARE`] on) and to one over the square root of the paths a stored
//! photon costs past [`OPEN_PATHS_PER_PHOTON`]. Both probes draw from a fixed seed, so every
//! shard of a render, whatever its seed, decides alike. Owns those decisions; must not shade
//! pixels.

use super::RayCamera;
use super::args::RenderArgs;
use super::pass::RenderSettings;
use crate::estimate::{KnnEstimate, Query, RadialKernel, Scratch};
use crate::photon::PhotonMap;
use crate::photon::tracer::{MapKind, trace_map_within};
use crate::sampling::{Rng, Stream};
use crate::timing::PhaseTimes;
use crate::world::{Surface, World};
use rayon::prelude::*;

/// Paths the open-scene probe traces.
const OPEN_PROBE_PATHS: u64 = 20_000;
/// Paths a stored global photon past which a scene is open: most diffuse bounces leave it.
const OPEN_PATHS_PER_PHOTON: u64 = 16;
/// The share of an open scene's global photons' diffuse bounces aimed at its objects.
const OPEN_BOUNCE_AIM: f32 = 0.5;
/// Photons of the map that measures the global map's share, and the paths it may take.
const SHARE_PROBE_PHOTONS: usize = 5_000;
const SHARE_PROBE_PATHS: u64 = 500_000;
/// Camera rays per side of the grid that measures the share.
const GRID: usize = 32;
/// The global map's share of the seen irradiance from which a pass stores every photon it
/// asks for; below it, photons in proportion.
pub const FULL_SHARE: f64 = 0.25;
/// The fewest photons a pass stores, as a fraction of those asked for.
const LEAST_FRACTION: f64 = 1.0 / 32.0;
/// The probes' seed: the same for every run of a scene.
const PROBE_SEED: u64 = 0x006C_0BA1;

/// Aims an open scene's global bounces and sizes its global map by what the image reads
/// from it (only where `--global-photons` is not given, in a scene without media, and not
/// with `--no-open-scene`).
pub(super) fn size_for_an_open_scene(
    settings: &mut RenderSettings,
    args: &RenderArgs,
    world: &mut World,
    times: &mut PhaseTimes,
) {
    let skipped = settings.no_open_scene || world.media.is_some();
    if skipped || settings.global_photons == 0 || world.lights_itself_alone() {
        return;
    }
    let start = std::time::Instant::now();
    let kind = MapKind::Global {
        with_direct: settings.final_gather > 0,
    };
    let bar = indicatif::ProgressBar::hidden();
    let probe = |world: &World, photons, paths| {
        trace_map_within(world, kind, photons, Some(paths), PROBE_SEED, &bar)
    };
    let (_, _, counts) = probe(world, settings.global_photons, OPEN_PROBE_PATHS);
    let open = counts.stored.saturating_mul(OPEN_PATHS_PER_PHOTON) < counts.emitted;
    let aimed = open && world.aim_bounces_at_objects(OPEN_BOUNCE_AIM);
    let mut counted = vec![
        ("emitted", counts.emitted),
        ("stored", counts.stored),
        ("aimed", u64::from(aimed)),
    ];
    if open && args.global_photons.is_none() && settings.final_gather == 0 {
        let (map, _, cost) = probe(world, SHARE_PROBE_PHOTONS, SHARE_PROBE_PATHS);
        let share = seen_share(world, &map, settings.global_k);
        // Photons where they are dear buy less: variance over cost is least with n ∝ 1/√cost.
        let paths_per_photon = cost.emitted as f64 / cost.stored.max(1) as f64;
        let dear = (OPEN_PATHS_PER_PHOTON as f64 / paths_per_photon)
            .sqrt()
            .min(1.0);
        let fraction = (share / FULL_SHARE * dear).clamp(LEAST_FRACTION, 1.0);
        settings.global_photons = (settings.global_photons as f64 * fraction).round() as usize;
        counted.push(("share per mille", (share * 1000.0).round() as u64));
        counted.push(("global photons", settings.global_photons as u64));
    }
    times.record("probe open scene", start.elapsed(), &counted);
}

/// The global map's share of the irradiance at the diffuse surfaces a grid of camera rays
/// sees first: `map`'s k-NN estimate against the direct light there (one shadow ray a light).
fn seen_share(world: &World, map: &PhotonMap, k: usize) -> f64 {
    if map.is_empty() {
        return 0.0;
    }
    let camera = RayCamera::new(&world.description.camera);
    let estimate = KnnEstimate::new(RadialKernel::Constant, k.max(2), None);
    let (w, h) = camera.film_size();
    let (w, h) = (w as f32, h as f32);
    let (direct, global) = (0..GRID * GRID)
        .into_par_iter()
        .map_init(Scratch::default, |scratch, i| {
            let x = ((i % GRID) as f32 + 0.5) / GRID as f32 * w;
            let y = ((i / GRID) as f32 + 0.5) / GRID as f32 * h;
            let ray = camera.chief_ray(x, y);
            let Some(closest) = world.closest_hit(ray.origin, ray.direction, 0.0, f32::INFINITY)
            else {
                return (0.0, 0.0);
            };
            let Surface::Material(m) = closest.surface else {
                return (0.0, 0.0);
            };
            if !world.reads_photons(m) {
                return (0.0, 0.0);
            }
            let hit = world.resolve(closest);
            let (_, n) = hit.facing(ray.direction);
            let mut rng = Rng::for_index(PROBE_SEED, Stream::Distribution, i as u64);
            let direct = super::caustic_guide::direct_irradiance(world, hit.position, n, &mut rng);
            let query = Query {
                position: hit.position,
                normal: n,
            };
            let (e, _) = estimate.irradiance_and_radius2(map, &query, scratch);
            (f64::from(direct), f64::from(e.element_sum() / 3.0))
        })
        .reduce(|| (0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    if direct + global > 0.0 {
        global / (direct + global)
    } else {
        0.0
    }
}
