//! The light a camera sees along its mirror and glass chains (the emitters themselves, their
//! images in glass and mirrors, the environment), estimated apart from the rest of a pixel.
//! A light's image through glass is often far smaller than a pixel: a camera sample finds it
//! or misses it, so a pixel's value there is a rare hit of thousands of times its mean, the
//! error that dominates a whole image after a few passes. Here such pixels take many cheap
//! samples of that light alone (a few rays each, glass sampled, no estimates:
//! [`Integrator::emitted`]) while their camera samples leave it out
//! ([`super::integrator::Emission::Elsewhere`]): the same expectation, far less variance per
//! second. Which pixels do so is decided once per render by the pilot rays
//! ([`super::pilots::PixelPlan`]). Owns the emission samples' estimate; must not choose the
//! pixels or shade diffuse surfaces.

use super::camera::CameraRay;
use super::integrator::Integrator;
use glam::Vec3;

/// The mean of a flagged pixel's emission samples: their camera rays (through the pixel and
/// the lens, as its camera samples go), each with the random stream for its glass choices.
pub fn emitted_mean(
    integrator: &Integrator,
    samples: impl ExactSizeIterator<Item = (CameraRay, crate::sampling::Rng)>,
) -> Vec3 {
    let n = samples.len().max(1) as f32;
    let mut sum = Vec3::ZERO;
    for (ray, mut rng) in samples {
        sum += integrator.emitted(ray.origin, ray.direction, &mut rng);
    }
    sum / n
}
