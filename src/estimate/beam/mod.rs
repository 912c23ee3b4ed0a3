//! The beam radiance estimate (Jarosz, Zwicker and Jensen 2008): the light a medium scatters
//! towards the eye along a whole camera segment, from the volume photons whose spheres the
//! segment passes through, each weighed by a normalised 2-D kernel of its distance to the ray
//! over its own radius, the phase function between its direction and the eye's, and the
//! transmittance from the segment's start to where it lies along the ray. One query per
//! segment, no marching. A map whose kernels are shaped ([`shaping`]) is read with each
//! photon's ellipsoid integrated along the ray ([`ellipsoid`]) instead of its disc; beside the
//! surfaces a segment starts or ends on, each weight is divided by the share of its kernel the
//! wall leaves inside the medium ([`walls`]). Owns that sum; must not trace rays or photons.

pub mod eigen3;
pub mod ellipsoid;
pub mod shaping;
pub mod walls;

use crate::media::{Medium, phase::HenyeyGreenstein};
use crate::photon::volume::VolumeMap;
use crate::sampling::Rng;
use glam::Vec3;
use std::f32::consts::FRAC_2_PI;
use walls::{SegmentWalls, kept_share};

/// The 2-D Epanechnikov kernel over the unit disc, (2/π)(1 − x²) at squared distance `x2`
/// (in radii): it integrates to 1 over the disc.
#[inline]
pub fn disc_kernel(x2: f32) -> f32 {
    if x2 < 1.0 {
        FRAC_2_PI * (1.0 - x2)
    } else {
        0.0
    }
}

/// In-scattered radiance towards `origin` along `origin + t·dir` (unit `dir`) for t in
/// [`t0`, `t1`), all of it inside `medium` and between `walls`, from the photons of `map`,
/// before the transmittance from the ray's origin to `t0`. `found` is scratch.
#[allow(clippy::too_many_arguments)]
pub fn in_scattered(
    map: &VolumeMap,
    medium: &Medium,
    origin: Vec3,
    dir: Vec3,
    (t0, t1): (f32, f32),
    walls: &SegmentWalls,
    rng: &mut Rng,
    found: &mut Vec<(f32, Vec3)>,
) -> Vec3 {
    let phase: HenyeyGreenstein = medium.phase();
    found.clear();
    map.along(origin, dir, t0, t1, |on| {
        let kernel = match on.shape {
            None => {
                let r2 = on.radius * on.radius;
                disc_kernel(on.distance2 / r2) / r2
            }
            Some(shape) => ellipsoid::line_integral(shape, origin - on.photon.position, dir),
        };
        let kernel = match walls.is_empty() {
            true => kernel,
            false => kernel / kept_share(walls, (t0, on.t, t1), on.radius, on.shape),
        };
        if kernel > 0.0 {
            // The eye looks back along −dir; the photon's light arrives from −direction.
            let w = kernel * phase.p(-dir, -on.photon.direction);
            found.push((on.t, on.photon.power * w));
        }
    });
    if found.is_empty() {
        return Vec3::ZERO;
    }
    match medium {
        Medium::Homogeneous { coefficients, .. } => (found.iter())
            .map(|&(t, l)| l * coefficients.transmittance(t - t0))
            .sum(),
        Medium::Grid { .. } => {
            // One ratio-tracked walk over the photons in order along the ray.
            found.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let (mut sum, mut tr, mut at) = (Vec3::ZERO, Vec3::ONE, t0);
            for &(t, l) in found.iter() {
                tr *= medium.transmittance(origin, dir, at, t, rng);
                at = t;
                if tr.max_element() <= 0.0 {
                    break;
                }
                sum += l * tr;
            }
            sum
        }
    }
}
