//! The gradient pass (Eq. 6): the gradient of the fixed-radius Epanechnikov estimate at every
//! photon, `∇L(x) = 4/(π r_g⁴) Σ (x_i − x) Φ_i` over the photons within `r_g` whose normal
//! agrees with the photon's own. Owns that pass only; must not build tensors or estimates.
//!
//! The scalar photon power `Φ_i` is the mean of the three channels: it is linear (so the
//! dimensionless contrast, which divides by an estimate made the same way, is colour-neutral)
//! and does not favour green as luminance would. `f_r` is left out, as in the rest of the
//! estimates. Gradients are summed in f64 and stored as f32 in tree order; a gradient too large
//! for f32 keeps its direction and is clamped in length. The result does not depend on the
//! number of threads: each photon's sum is made by one thread in the tree's visiting order.

use super::super::{normals_agree, power_f64};
use crate::photon::PhotonMap;
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Scalar power of a photon for the structure analysis: the channel mean.
#[inline]
pub fn scalar_power(photon: &crate::photon::Photon) -> f64 {
    let p = power_f64(photon);
    (p.x + p.y + p.z) / 3.0
}

/// The gradient at every photon, in tree order, computed in parallel.
///
/// # Panics
/// If `radius` is not positive and finite.
pub fn compute_gradients(map: &PhotonMap, radius: f32) -> Vec<Vec3> {
    assert!(
        radius > 0.0 && radius.is_finite(),
        "gradient radius must be positive, got {radius}"
    );
    (0..map.len() as u32)
        .into_par_iter()
        .map(|slot| gradient_at_photon(map, slot, radius))
        .collect()
}

/// Computes the gradients and stores them in the map (`map.set_gradients`). This is what the
/// diffusion estimate's `prepare` runs; call it yourself to time it as a phase of its own.
pub fn gradient_pass(map: &mut PhotonMap, radius: f32) {
    let gradients = compute_gradients(map, radius);
    map.set_gradients(gradients);
}

fn gradient_at_photon(map: &PhotonMap, slot: u32, radius: f32) -> Vec3 {
    let photon = map.photon(slot);
    let (x, normal) = (photon.position(), photon.normal());
    let mut sum = DVec3::ZERO;
    map.tree().for_each_within(x, radius * radius, |other, _| {
        let p = map.photon(other);
        if normals_agree(p, normal) {
            sum += (p.position() - x).as_dvec3() * scalar_power(p);
        }
    });
    let r = radius as f64;
    to_f32_direction_kept(sum * (4.0 / (PI * r * r * r * r)))
}

/// f64 → f32, scaling the whole vector down if a component would overflow.
fn to_f32_direction_kept(g: DVec3) -> Vec3 {
    if !g.is_finite() {
        return Vec3::ZERO;
    }
    let largest = g.abs().max_element();
    let limit = f32::MAX as f64 * 0.5;
    if largest > limit {
        (g * (limit / largest)).as_vec3()
    } else {
        g.as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::Photon;

    fn photon(x: f32, y: f32, power: f32) -> Photon {
        Photon::new(Vec3::new(x, y, 0.0), Vec3::splat(power), -Vec3::Z, Vec3::Z)
    }

    #[test]
    fn gradient_points_towards_more_power_with_the_epanechnikov_scale() {
        // One photon at the origin and one at (0.5, 0) of power 2: within r_g = 1 the origin's
        // gradient is 4/π · 0.5 · 2 along +x; the other photon's is its mirror image.
        let map = PhotonMap::build(vec![photon(0.0, 0.0, 1.0), photon(0.5, 0.0, 2.0)], 2);
        let g = compute_gradients(&map, 1.0);
        for (slot, p) in map.photons().iter().enumerate() {
            let expected = if p.position().x == 0.0 {
                4.0 / PI as f32
            } else {
                -2.0 / PI as f32
            };
            assert!(
                (g[slot].x - expected).abs() < 1e-6 && g[slot].y == 0.0,
                "{:?}",
                g[slot]
            );
        }
    }

    #[test]
    fn photons_on_the_other_side_are_ignored_and_huge_gradients_stay_finite() {
        let back = Photon::new(
            Vec3::new(0.1, 0.0, 0.0),
            Vec3::splat(1e30),
            Vec3::Z,
            -Vec3::Z,
        );
        let map = PhotonMap::build(vec![photon(0.0, 0.0, 1.0), back], 2);
        let g = compute_gradients(&map, 1.0);
        for (slot, p) in map.photons().iter().enumerate() {
            assert_eq!(g[slot], Vec3::ZERO, "{:?}", p.position());
        }
        let map = PhotonMap::build(vec![photon(0.0, 0.0, 1e30), photon(1e-9, 0.0, 1e30)], 2);
        let g = compute_gradients(&map, 1e-8);
        assert!(g.iter().all(|g| g.is_finite() && g.x != 0.0));
    }
}
