//! Photon tracing (Jensen's first pass): photons leave the lights in proportion to their power,
//! Embree finds every hit (through [`World`]), mirrors and glass redirect them (Fresnel, total
//! internal reflection), diffuse surfaces store them and reflect them with Russian roulette.
//! Two maps: the caustic map (light → specular+ → diffuse) and the global map (indirect diffuse).
//! Owns paths and photon bookkeeping; must not estimate radiance or shade pixels.
//!
//! Determinism: path `i` draws only from `Rng::for_index(seed, stream, i)` and paths are kept in
//! index order, so the maps are identical whatever the thread count.

use super::{Photon, PhotonMap};
use crate::optics::{fresnel_dielectric, reflect, refract};
use crate::sampling::{Rng, Stream, cosine_hemisphere};
use crate::scene::Material;
use crate::world::lights::{self, Emission};
use crate::world::{Surface, World};
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

/// A photon as traced, before the flux is divided by the number of paths emitted.
#[derive(Clone, Copy)]
struct TracedPhoton {
    position: Vec3,
    flux: Vec3,
    direction: Vec3,
    normal: Vec3,
}

/// Splits photon paths among the lights in proportion to their power.
struct LightChooser {
    cdf: Vec<f32>,
    /// Probability of each light.
    pdf: Vec<f32>,
}

impl LightChooser {
    fn new(world: &World) -> Option<Self> {
        let w: Vec<f32> = world
            .description
            .lights
            .iter()
            .map(|l| lights::weight(lights::power(l)))
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

/// Traces paths until `target` photons are stored (or `max_paths` are emitted), and builds the map.
/// Stops early with an empty map when an interruption is requested ([`crate::interrupt`]);
/// the caller must check for it and discard the map.
pub fn trace_map(
    world: &World,
    kind: MapKind,
    target: usize,
    seed: u64,
    progress: &ProgressBar,
) -> (PhotonMap, TraceCounts) {
    let max_paths = (target as u64).saturating_mul(1000).max(1_000_000);
    let Some(chooser) = LightChooser::new(world) else {
        return (PhotonMap::build(Vec::new(), 0), TraceCounts::default());
    };
    let aim = match kind {
        MapKind::Caustic => world.specular_bounds,
        MapKind::Global { .. } => None,
    };
    let stream = match kind {
        MapKind::Caustic => Stream::CausticPhotons,
        MapKind::Global { .. } => Stream::GlobalPhotons,
    };
    let mut traced: Vec<TracedPhoton> = Vec::with_capacity(target);
    let mut emitted: u64 = 0;
    let mut batch = 16_384u64;
    while traced.len() < target && emitted < max_paths && !crate::interrupt::requested() {
        let start = emitted;
        let end = (start + batch).min(max_paths);
        let paths: Vec<Vec<TracedPhoton>> = (start..end)
            .into_par_iter()
            .map(|i| {
                if crate::interrupt::requested() {
                    return Vec::new();
                }
                let mut rng = Rng::for_index(seed, stream, i);
                trace_path(world, kind, &chooser, aim, &mut rng)
            })
            .collect();
        for (offset, path) in paths.into_iter().enumerate() {
            if traced.len() >= target {
                break;
            }
            emitted = start + offset as u64 + 1;
            let room = target - traced.len();
            traced.extend(path.into_iter().take(room));
        }
        progress.set_position(traced.len().min(target) as u64);
        // Grow batches towards the expected remainder so few batches are needed.
        let rate = traced.len().max(1) as f64 / emitted.max(1) as f64;
        let remaining = (target - traced.len().min(target)) as f64 / rate;
        batch = (remaining * 1.05).clamp(16_384.0, 4_000_000.0) as u64;
    }
    if crate::interrupt::requested() {
        // Not worth building: the caller discards it.
        return (PhotonMap::default(), TraceCounts { emitted, stored: 0 });
    }
    let scale = 1.0 / emitted.max(1) as f32;
    let photons: Vec<Photon> = traced
        .par_iter()
        .map(|p| Photon::new(p.position, p.flux * scale, p.direction, p.normal))
        .collect();
    drop(traced);
    let stored = photons.len() as u64;
    (
        PhotonMap::build(photons, emitted),
        TraceCounts { emitted, stored },
    )
}

fn trace_path(
    world: &World,
    kind: MapKind,
    chooser: &LightChooser,
    aim: Option<crate::world::BoundingSphere>,
    rng: &mut Rng,
) -> Vec<TracedPhoton> {
    let mut stored = Vec::new();
    let l = chooser.pick(rng.next_f32());
    let light = &world.description.lights[l];
    let Emission {
        origin,
        direction,
        flux,
    } = lights::emit(light, aim, rng);
    let mut flux = flux / chooser.pdf[l];
    if flux.max_element() <= 0.0 {
        return stored;
    }
    let eps = world.ray_epsilon();
    // Start just off the light: the first ray would otherwise hit the light's own surface.
    let (mut o, mut d) = (origin + direction * eps, direction);
    let mut specular_seen = false;
    let mut diffuse_seen = false;
    for _ in 0..MAX_BOUNCES {
        let Some(hit) = world.intersect(o, d, 0.0, f32::INFINITY) else {
            break;
        };
        let Surface::Material(m) = hit.surface else {
            break;
        };
        // Normals facing the side the photon arrives from.
        let entering = d.dot(hit.geometric_normal) < 0.0;
        let ng = if entering {
            hit.geometric_normal
        } else {
            -hit.geometric_normal
        };
        let ns = if entering {
            hit.shading_normal
        } else {
            -hit.shading_normal
        };
        let next = match world.material(m) {
            Material::Diffuse { albedo } => {
                let store = match kind {
                    MapKind::Caustic => specular_seen,
                    MapKind::Global { with_direct } => diffuse_seen || with_direct,
                };
                if store {
                    stored.push(TracedPhoton {
                        position: hit.position,
                        flux,
                        direction: d,
                        normal: ns,
                    });
                }
                if kind == MapKind::Caustic {
                    break;
                }
                let survive = albedo.max_element();
                if rng.next_f32() >= survive {
                    break;
                }
                flux *= *albedo / survive;
                diffuse_seen = true;
                cosine_hemisphere(ns, rng.next_2d())
            }
            Material::Mirror => {
                if kind == MapKind::Caustic && diffuse_seen {
                    break;
                }
                specular_seen = true;
                reflect(d, ns)
            }
            Material::Glass { ior } => {
                specular_seen = true;
                let eta = if entering { 1.0 / ior } else { *ior };
                let cos_i = -d.dot(ns);
                if rng.next_f32() < fresnel_dielectric(cos_i, eta) {
                    reflect(d, ns)
                } else {
                    refract(d, ns, eta).unwrap_or_else(|| reflect(d, ns))
                }
            }
        };
        // Leave the surface on the side the new direction points to.
        let side = if next.dot(ng) >= 0.0 { ng } else { -ng };
        o = hit.position + side * eps;
        d = next;
    }
    stored
}
