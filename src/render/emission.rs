//! The light a camera sees along its mirror and glass chains (the emitters themselves, their
//! images in glass and mirrors, the environment), estimated apart from the rest of a pixel.
//! A light's image through glass is often far smaller than a pixel: a camera sample finds it
//! or misses it, so a pixel's value there is a rare hit of thousands of times its mean, the
//! error that dominates a whole image after a few passes. Here such pixels take many cheap
//! samples of that light alone (a few rays each, glass sampled, no estimates:
//! [`Integrator::emitted`]) while their camera samples leave it out
//! ([`super::integrator::Emission::Elsewhere`]): the same expectation, far less variance per
//! second. Which pixels do so is decided once per render from the
//! geometry alone ([`EmissionPixels::find`]), so that every pass, thread count and shard
//! agrees. Owns that choice; must not shade diffuse surfaces.

use super::camera::PinholeCamera;
use super::integrator::Integrator;
use crate::scene::Material;
use crate::world::{Surface, World};
use glam::Vec3;
use rayon::prelude::*;

/// The pixels whose emitted light is sampled apart: those where a pilot ray (through the
/// pixel's centre or one of its corners, which neighbours share: about two rays a pixel)
/// meets a light, a mirror or glass first, or leaves the scene under a lit environment.
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionPixels {
    flagged: Vec<bool>,
    /// Samples of the emitted light per flagged pixel and pass.
    samples: u32,
}

impl EmissionPixels {
    /// The pixels of `camera` whose `samples` emission samples a pass draws (none when
    /// `samples` is 0: then every camera sample counts its own emitted light). `None` if an
    /// interruption was requested meanwhile.
    pub fn find(camera: &PinholeCamera, world: &World, samples: u32) -> Option<Self> {
        let (w, h) = (camera.width(), camera.height());
        if samples == 0 {
            return Some(Self {
                flagged: vec![false; w * h],
                samples,
            });
        }
        let sees =
            |x: f32, y: f32| sees_emission_first(world, camera.origin(), camera.direction(x, y));
        // Row by row, so that an interruption is noticed within one row.
        let rows = |count: usize, width: usize, at: &(dyn Fn(usize, usize) -> bool + Sync)| {
            (0..count)
                .into_par_iter()
                .map(|y| {
                    if crate::interrupt::requested() {
                        return Vec::new();
                    }
                    (0..width).map(|x| at(x, y)).collect::<Vec<bool>>()
                })
                .collect::<Vec<_>>()
        };
        let corners = rows(h + 1, w + 1, &|x, y| sees(x as f32, y as f32));
        let centres = rows(h, w, &|x, y| sees(x as f32 + 0.5, y as f32 + 0.5));
        if crate::interrupt::requested() {
            return None;
        }
        let flagged = (0..w * h)
            .map(|pixel| {
                let (x, y) = (pixel % w, pixel / w);
                centres[y][x]
                    || corners[y][x]
                    || corners[y][x + 1]
                    || corners[y + 1][x]
                    || corners[y + 1][x + 1]
            })
            .collect();
        Some(Self { flagged, samples })
    }

    /// Whether `pixel` (row-major) samples its emitted light apart.
    #[inline]
    pub fn flagged(&self, pixel: usize) -> bool {
        self.samples > 0 && self.flagged[pixel]
    }

    pub fn samples(&self) -> u32 {
        self.samples
    }

    /// Pixels flagged.
    pub fn count(&self) -> usize {
        if self.samples == 0 {
            0
        } else {
            self.flagged.iter().filter(|&&f| f).count()
        }
    }
}

/// Whether the first thing the ray meets is a light, a mirror or glass, or nothing under a
/// lit environment.
fn sees_emission_first(world: &World, origin: Vec3, dir: Vec3) -> bool {
    match world.intersect(origin, dir, 0.0, f32::INFINITY) {
        None => world.background() != Vec3::ZERO,
        Some(hit) => match hit.surface {
            Surface::Light(_) => true,
            Surface::Material(m) => !matches!(world.material(m), Material::Diffuse { .. }),
        },
    }
}

/// The mean of a flagged pixel's emission samples: `positions` are its sample positions in
/// pixels (image coordinates), each with the random stream for its glass choices.
pub fn emitted_mean(
    camera: &PinholeCamera,
    integrator: &Integrator,
    samples: impl ExactSizeIterator<Item = ((f32, f32), crate::sampling::Rng)>,
) -> Vec3 {
    let n = samples.len().max(1) as f32;
    let mut sum = Vec3::ZERO;
    for ((x, y), mut rng) in samples {
        sum += integrator.emitted(camera.origin(), camera.direction(x, y), &mut rng);
    }
    sum / n
}
