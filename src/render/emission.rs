//! The light a camera sees along its mirror and glass chains (the emitters themselves, their
//! images in glass and mirrors, the environment), estimated apart from the rest of a pixel.
//! A light's image through glass is often far smaller than a pixel: a camera sample finds it
//! or misses it, so a pixel's value there is a rare hit of thousands of times its mean, the
//! error that dominates a whole image after a few passes. Here such pixels take many cheap
//! samples of that light alone (a few rays each, glass sampled, no estimates:
//! [`Integrator::emitted`]) while their camera samples leave it out
//! ([`super::integrator::Emission::Elsewhere`]): the same expectation, far less variance per
//! second; half of them aim at the light images the pilots found in the pixel
//! ([`super::light_images`]). Which pixels do so is decided once per render by the pilot rays
//! ([`super::pilots::PixelPlan`]). Owns the emission samples' estimate; must not choose the
//! pixels or shade diffuse surfaces.

use super::camera::{EmissionSample, RayCamera};
use super::integrator::Integrator;
use super::light_images::Aim;
use glam::{Vec2, Vec3};

/// The mean of a flagged pixel's emission samples, the pixel's film corner at `pixel`: each
/// placed as `aim` says (across the pixel as its camera samples go, or at a light image
/// found in it) and weighed so, through the lens at the sample's lens point, with the
/// sample's random stream for its glass choices.
pub fn emitted_mean(
    integrator: &Integrator,
    camera: &RayCamera,
    aim: &Aim,
    pixel: Vec2,
    samples: impl ExactSizeIterator<Item = EmissionSample>,
) -> Vec3 {
    let n = samples.len().max(1) as f32;
    let mut sum = Vec3::ZERO;
    for (j, sample) in samples.enumerate() {
        let Some((x, along)) = aim.point(j as u32, sample.jitter, pixel) else {
            continue;
        };
        let ray = camera.ray(x.x, x.y, sample.lens);
        let mut rng = sample.rng;
        if aim.aims() {
            let seen = integrator.emitted_chain(ray.origin, ray.direction, &mut rng, along);
            sum += aim.weight(x, seen.code, seen.probability) * seen.value;
        } else {
            sum += integrator.emitted(ray.origin, ray.direction, &mut rng);
        }
    }
    // Spread samples alone weigh 1/n each: summed first, as before aiming.
    if aim.aims() { sum } else { sum / n }
}
