//! What a caustic photon landing is worth to this image, for the caustic guide learnt once per
//! render (`photon::guide`, `world::aim_guide`), and the phase that learns it before pass 0.
//! Owns that valuation; must not trace photons or shade pixels.
//!
//! The image's error is relative (the relative MSE of `crate::image_metrics`: squared error over the
//! reference's square plus ε², ε a tenth of the image's mean). A photon's share of a caustic
//! estimate's variance is the same wherever it lands, so where the image is bright it adds
//! little relative error, and where it is dim much. Spreading N photons with density w·C over
//! a caustic C so as to minimise Σ C / (w (R² + ε²)) at a fixed Σ w C gives w ∝ 1 / √(R² + ε²):
//! a landing is worth one over the light seen there. R is estimated, in irradiance, as the
//! direct light (one shadow ray per light) plus the pilots' own caustic irradiance there; ε as a
//! tenth of the mean direct irradiance at the diffuse surfaces a coarse grid of camera rays
//! sees. Landings outside the camera's view are worth nothing (the guide's uniform share still
//! sends photons there, for the mirrors and glass that may show them).

use super::RayCamera;
use super::pass::RenderSettings;
use crate::photon::Neighbours;
use crate::photon::guide::{Landing, PilotPhotons};
use crate::sampling::{Rng, Stream};
use crate::timing::PhaseTimes;
use crate::world::{Surface, World};
use glam::Vec3;
use rayon::prelude::*;

/// Camera rays per side of the grid that sets ε.
const GRID: usize = 32;

/// Learns the caustic guide (once per render, before pass 0: every pass draws through it) and
/// hands it to the world's emitters.
pub fn learn(world: &mut World, settings: &RenderSettings, seed: u64, times: &mut PhaseTimes) {
    if settings.guide_paths == 0 || world.caustic_targets.is_empty() {
        return;
    }
    let camera = RayCamera::new(&world.description.camera);
    let guide = times.time("caustic guide", || {
        crate::photon::guide::learn_caustic_guide(
            world,
            seed,
            settings.guide_paths,
            |landings, pilots| landing_worth(world, &camera, seed, landings, pilots),
        )
    });
    times.add_counts(
        "caustic guide",
        &[
            ("pilot paths", guide.paths),
            ("landings", guide.landings),
            ("guided lights", guide.guided_lights() as u64),
        ],
    );
    world.caustic_guide = guide.cells;
}

/// One number per landing: 1 / √(R² + ε²) where the camera sees it, 0 elsewhere.
pub fn landing_worth(
    world: &World,
    camera: &RayCamera,
    seed: u64,
    landings: &[Landing],
    pilots: &PilotPhotons,
) -> Vec<f64> {
    let epsilon = 0.1 * mean_direct_irradiance(world, camera, seed);
    landings
        .par_iter()
        .enumerate()
        .map_init(Neighbours::new, |found, (i, landing)| {
            if !camera.sees(landing.position) {
                return 0.0;
            }
            let caustic = pilots.caustic_irradiance(landing.position, found);
            // The pilot paths take this stream's first indices, the ε grid those from 2⁶³, the
            // landings' light samples those counting down from the top.
            let mut rng = Rng::for_index(seed, Stream::CausticPilots, u64::MAX - i as u64);
            let direct = direct_irradiance(world, landing.position, landing.normal, &mut rng);
            let r = f64::from(direct + caustic);
            let floor = f64::from(epsilon).max(f64::MIN_POSITIVE);
            1.0 / (r * r + floor * floor).sqrt()
        })
        .collect()
}

/// Irradiance at `p` (unit normal `n`) straight from the lights: one shadow-tested sample per
/// light (past a few bounded lights, one drawn from the light tree for them all), mean over
/// the channels.
pub(super) fn direct_irradiance(world: &World, p: Vec3, n: Vec3, rng: &mut Rng) -> f32 {
    let origin = p + n * world.ray_epsilon_at(p);
    let lights = &world.light_sampler;
    let seen = |light: &crate::world::lights::LightSource, part, u| {
        let Some(s) = light.sample_incident_part(p, n, u, part) else {
            return Vec3::ZERO;
        };
        let cos = n.dot(s.direction);
        if cos > 0.0 && !world.occluded(origin, s.direction, 0.0, s.distance * (1.0 - 1e-4)) {
            s.irradiance * cos
        } else {
            Vec3::ZERO
        }
    };
    let mut e = Vec3::ZERO;
    for l in lights.one_by_one(world.light_sources.len()) {
        e += seen(&world.light_sources[l], None, rng.next_2d());
    }
    if !lights.samples_every_light()
        && let Some((part, pmf)) = lights.sample(p, n, rng.next_f32())
    {
        let light = &world.light_sources[part.light];
        e += seen(light, part.triangle, rng.next_2d()) / pmf;
    }
    e.element_sum() / 3.0
}

/// Mean direct irradiance over a grid of camera rays (pixel centres of a coarse image): at a
/// diffuse first hit the direct light there, anywhere else nothing.
fn mean_direct_irradiance(world: &World, camera: &RayCamera, seed: u64) -> f32 {
    // The full film's grid: a crop keeps the full render's guide.
    let (w, h) = camera.film_size();
    let (w, h) = (w as f32, h as f32);
    let sum: f64 = (0..GRID * GRID)
        .into_par_iter()
        .map(|i| {
            let x = ((i % GRID) as f32 + 0.5) / GRID as f32 * w;
            let y = ((i / GRID) as f32 + 0.5) / GRID as f32 * h;
            let ray = camera.chief_ray(x, y);
            let dir = ray.direction;
            let Some(closest) = world.closest_hit(ray.origin, dir, 0.0, f32::INFINITY) else {
                return 0.0;
            };
            let Surface::Material(m) = closest.surface else {
                return 0.0;
            };
            if !world.reads_photons(m) {
                return 0.0;
            }
            let hit = world.resolve(closest);
            let (_, n) = hit.facing(dir);
            let mut rng = Rng::for_index(seed, Stream::CausticPilots, u64::MAX / 2 + i as u64);
            f64::from(direct_irradiance(world, hit.position, n, &mut rng))
        })
        .sum();
    (sum / (GRID * GRID) as f64) as f32
}
