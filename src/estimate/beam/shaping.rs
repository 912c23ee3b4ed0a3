//! The paper's diffusion kernel in volumes: each volume photon's kernel shaped to the
//! structure of the photons around it, so that a volumetric caustic's sheet or filament is
//! smoothed along itself and not across. Per photon, at its analysis radius `h` (the distance
//! to its k-th neighbour before the pass's radius scale):
//! 1. the gradient of the 3-D Epanechnikov density `∇ρ = 15/(4π h⁵) Σ Φⱼ (xⱼ − x)` and the
//!    variance photon noise alone gives it per axis, `(15/(4π h⁵))² Σ Φⱼ² |xⱼ − x|² / 3`;
//! 2. the structure tensor, `g gᵀ` averaged over the photons within `smoothing·h` (weights
//!    `1 − d²/ρ²`), less `noise_floor` times the averaged noise on every axis;
//! 3. its eigenvalues `μ1 ≥ μ2 ≥ μ3` as dimensionless contrasts `μ r²/ρ̂²` (`r` the kernel's
//!    radius, `ρ̂` the density at the photon): the squared relative change of density over
//!    one kernel radius;
//! 4. the diffusion tensor of Eq. 8–9 in 3-D: `λ = max(floor, 1/(1 + (c/K)^(1+α)))` across
//!    the two strongest directions (a sheet squeezes one, a filament both), 1 along the
//!    third, where the density changes least.
//!
//! The kernel is the ellipsoid of axes `r√λ` ([`super::ellipsoid`]), inside the photon's
//! sphere, its integral 1 whatever its shape. Owns that analysis; must not trace or render.

use super::eigen3::SymmetricTensor3;
use super::ellipsoid::{ball, ellipsoid};
use crate::estimate::diffusion::tensor::diffusivity;
use crate::photon::KdTree;
use crate::photon::volume::{KernelEllipsoid, VolumeMap};
use glam::DVec3;
use rayon::prelude::*;
use std::f64::consts::PI;

/// The volume diffusion kernel's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumeDiffusion {
    /// `K`: the dimensionless contrast at which a direction's `λ` is one half.
    pub contrast: f64,
    /// `α` of Eq. 9.
    pub alpha: f64,
    /// The least `λ` (the kernel never thinner than `√floor` of its radius).
    pub floor: f64,
    /// Multiples of the photon noise's gradient variance taken off the structure tensor.
    pub noise_floor: f64,
    /// The structure tensor's smoothing radius, in analysis radii.
    pub smoothing: f64,
}

impl Default for VolumeDiffusion {
    fn default() -> Self {
        Self {
            contrast: 0.2,
            alpha: 1.0,
            floor: 0.02,
            noise_floor: 2.0,
            smoothing: 1.0,
        }
    }
}

/// What the analysis keeps of each photon: its neighbourhood's gradient, density and noise.
#[derive(Clone, Copy, Debug, Default)]
struct Local {
    gradient: DVec3,
    density: f64,
    noise: f64,
}

/// Every photon's kernel ellipsoid (in the map's order), its radius the map's, its structure
/// read at `radius / radius_scale`.
pub fn shape_kernels(
    map: &VolumeMap,
    radius_scale: f32,
    params: &VolumeDiffusion,
) -> Vec<KernelEllipsoid> {
    let photons = map.photons();
    let positions: Vec<_> = photons.iter().map(|p| p.position).collect();
    let power: Vec<f64> = photons
        .iter()
        .map(|p| p.power.element_sum() as f64 / 3.0)
        .collect();
    let tree = KdTree::build(&positions);
    let analysis = |i: usize| (map.radii()[i] / radius_scale) as f64;
    let locals: Vec<Local> = (0..photons.len())
        .into_par_iter()
        .map(|i| {
            let h = analysis(i);
            let x = positions[i].as_dvec3();
            let (mut sum, mut density, mut second) = (DVec3::ZERO, 0.0, 0.0);
            tree.for_each_within(positions[i], (h * h) as f32, |slot, _| {
                let j = tree.source_index(slot as usize) as usize;
                let d = positions[j].as_dvec3() - x;
                let d2 = d.length_squared();
                sum += power[j] * d;
                density += power[j] * (1.0 - d2 / (h * h)).max(0.0);
                second += power[j] * power[j] * d2;
            });
            let g = 15.0 / (4.0 * PI * h.powi(5));
            Local {
                gradient: g * sum,
                density: 15.0 / (8.0 * PI * h.powi(3)) * density,
                noise: g * g * second / 3.0,
            }
        })
        .collect();
    (0..photons.len())
        .into_par_iter()
        .map(|i| {
            let (h, r) = (analysis(i), map.radii()[i] as f64);
            let rho2 = (params.smoothing * h).powi(2);
            let (mut structure, mut noise, mut weight) = (SymmetricTensor3::default(), 0.0, 0.0);
            tree.for_each_within(positions[i], rho2 as f32, |slot, d2| {
                let j = tree.source_index(slot as usize) as usize;
                let w = (1.0 - d2 as f64 / rho2).max(0.0);
                structure.add_scaled(&SymmetricTensor3::outer(locals[j].gradient), w);
                noise += w * locals[j].noise;
                weight += w;
            });
            if weight <= 0.0 {
                return ball(r);
            }
            let eigen = structure.scaled(1.0 / weight).eigen();
            let noise = params.noise_floor * noise / weight;
            let density = locals[i].density;
            let lambda = |mu: f64| {
                let signal = (mu - noise).max(0.0);
                let contrast = match density > 0.0 {
                    true => (signal / density) * (r * r / density),
                    false if signal > 0.0 => f64::INFINITY,
                    false => 0.0,
                };
                diffusivity(contrast, params.contrast, params.alpha).max(params.floor)
            };
            let lambdas = [lambda(eigen.values[0]), lambda(eigen.values[1]), 1.0];
            ellipsoid(eigen.vectors, lambdas, r)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::volume::VolumePhoton;
    use glam::Vec3;

    use crate::sampling::{Rng, Stream};

    fn draws(seed: u64) -> Rng {
        Rng::for_index(seed, Stream::Pixels, 0)
    }

    /// `n` photons of equal power uniform in the box `lo..hi`.
    fn uniform(rng: &mut Rng, n: usize, lo: Vec3, hi: Vec3) -> Vec<VolumePhoton> {
        (0..n)
            .map(|_| VolumePhoton {
                position: lo
                    + (hi - lo) * Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()),
                power: Vec3::splat(1.0),
                direction: Vec3::Y,
            })
            .collect()
    }

    /// The ellipsoid's semi-axis along `v` over its radius: `1/√(vᵀMv)/r`.
    fn extent(shape: &KernelEllipsoid, v: Vec3, r: f32) -> f32 {
        let [xx, yy, zz, xy, xz, yz] = shape.metric;
        let mv = Vec3::new(
            xx * v.x + xy * v.y + xz * v.z,
            xy * v.x + yy * v.y + yz * v.z,
            xz * v.x + yz * v.y + zz * v.z,
        );
        1.0 / v.dot(mv).sqrt() / r
    }

    fn shaped(photons: Vec<VolumePhoton>) -> (VolumeMap, Vec<KernelEllipsoid>) {
        let map = VolumeMap::build(photons, 60, 1.0, 1.0);
        let shapes = shape_kernels(&map, 1.0, &VolumeDiffusion::default());
        (map, shapes)
    }

    #[test]
    fn kernels_in_a_uniform_cloud_stay_round() {
        let mut rng = draws(3);
        let (map, shapes) = shaped(uniform(&mut rng, 20_000, Vec3::ZERO, Vec3::ONE));
        let mut thin = 0;
        let mut inner = 0;
        for ((p, s), &r) in map.photons().iter().zip(&shapes).zip(map.radii()) {
            if (p.position - Vec3::splat(0.5)).abs().max_element() > 0.3 {
                continue; // the cloud's own faces are structure
            }
            inner += 1;
            let least = [Vec3::X, Vec3::Y, Vec3::Z].map(|v| extent(s, v, r));
            if least.iter().any(|&e| e < 0.7) {
                thin += 1;
            }
        }
        assert!(
            thin * 20 < inner,
            "{thin} of {inner} kernels squeezed in a flat cloud"
        );
    }

    #[test]
    fn kernels_at_a_sheet_squeeze_across_it_and_not_along_it() {
        // A slab thin in y: its faces are sheets whose normal is y.
        let mut rng = draws(5);
        let photons = uniform(&mut rng, 20_000, Vec3::ZERO, Vec3::new(1.0, 0.04, 1.0));
        let (map, shapes) = shaped(photons);
        let (mut across, mut along, mut n) = (0.0, 0.0, 0);
        for ((p, s), &r) in map.photons().iter().zip(&shapes).zip(map.radii()) {
            if (p.position.x - 0.5).abs() > 0.3 || (p.position.z - 0.5).abs() > 0.3 {
                continue;
            }
            across += extent(s, Vec3::Y, r);
            along += (extent(s, Vec3::X, r) + extent(s, Vec3::Z, r)) / 2.0;
            n += 1;
        }
        let (across, along) = (across / n as f32, along / n as f32);
        assert!(
            across < 0.5 && along > 0.85,
            "across {across}, along {along}"
        );
    }

    #[test]
    fn kernels_on_a_filament_squeeze_both_ways_across_it() {
        // A rod along z, thinner than the kernels (60 photons reach about 0.01 along it).
        let mut rng = draws(8);
        let photons = uniform(&mut rng, 3_000, Vec3::ZERO, Vec3::new(0.005, 0.005, 1.0));
        let (map, shapes) = shaped(photons);
        let (mut x, mut y, mut z, mut n) = (0.0, 0.0, 0.0, 0);
        for ((p, s), &r) in map.photons().iter().zip(&shapes).zip(map.radii()) {
            if (p.position.z - 0.5).abs() > 0.3 {
                continue;
            }
            x += extent(s, Vec3::X, r);
            y += extent(s, Vec3::Y, r);
            z += extent(s, Vec3::Z, r);
            n += 1;
        }
        let [x, y, z] = [x, y, z].map(|v| v / n as f32);
        assert!(x < 0.8 && y < 0.8 && z > 0.95, "x {x}, y {y}, z {z}");
    }

    #[test]
    fn shapes_do_not_depend_on_the_number_of_threads() {
        let mut rng = draws(9);
        let photons = uniform(&mut rng, 5_000, Vec3::ZERO, Vec3::new(1.0, 0.1, 1.0));
        let map = VolumeMap::build(photons, 30, 1.0, 0.8);
        let run = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| shape_kernels(&map, 0.8, &VolumeDiffusion::default()))
        };
        assert_eq!(run(1), run(2));
    }
}
