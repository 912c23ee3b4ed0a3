//! Helpers of the diffusion-estimate tests: default parameters, step-edge layouts, and the
//! sanity check every extreme case must pass. Must not reimplement the estimate.

use super::*;
use dpm::estimate::{
    Crossings, DiffusionEstimate, DiffusionKernel, DiffusionParams, DiffusivityUnits, KernelShape,
    Query, RadianceEstimate, Scratch,
};
use dpm::photon::{Photon, PhotonMap};
use glam::Vec3;
use std::f32::consts::PI;

/// The defaults of `EstimatorSettings` at radius `r`.
pub fn params(r: f32) -> DiffusionParams {
    DiffusionParams {
        radius: r,
        gradient_radius: r / 2.0,
        smoothing_radius: r,
        diffusivity: 0.2,
        units: DiffusivityUnits::Dimensionless,
        alpha: 1.0,
        lambda3: 0.1,
        lambda2_floor: 0.01,
        kernel: DiffusionKernel::Epanechnikov,
        noise_floor: 2.0,
        min_kernel_photons: 0.0,
        gradient_sites: 256.0,
        crossings: Crossings::Keep,
        edge_cut: false,
    }
}

pub fn with(r: f32, change: impl FnOnce(&mut DiffusionParams)) -> DiffusionEstimate {
    let mut p = params(r);
    change(&mut p);
    DiffusionEstimate::new(p)
}

pub fn prepared(photons: Vec<Photon>, e: &DiffusionEstimate) -> PhotonMap {
    let mut map = PhotonMap::build(photons, 0);
    e.prepare(&mut map);
    map
}

/// Step edge along y at x = 0: `high` photons per unit area for x < 0, `low` for x > 0, in
/// `[-half_width, half_width] × [0, length]`, power `power` each.
pub fn step_edge(
    rng: &mut Rng,
    high: f32,
    low: f32,
    half_width: f32,
    length: f32,
    power: Vec3,
) -> Vec<Photon> {
    let count = |density: f32| (density * half_width * length).round() as usize;
    let mut p = uniform_rect(rng, count(high), (-half_width, 0.0), (0.0, length), power);
    p.extend(uniform_rect(
        rng,
        count(low),
        (0.0, half_width),
        (0.0, length),
        power,
    ));
    p
}

/// A small step-edge map with about `per_disc` bright photons per disc of radius 1.
pub fn small_edge(seed: u64, per_disc: f32, power: Vec3) -> Vec<Photon> {
    let high = per_disc / PI;
    step_edge(&mut Rng(seed), high, high / 4.0, 2.5, 4.0, power)
}

pub fn shape(e: &DiffusionEstimate, map: &PhotonMap, q: &Query) -> KernelShape {
    e.kernel_at(map, q, &mut Scratch::default())
}

pub fn edge_queries() -> Vec<Query> {
    let mut q = Vec::new();
    for i in -8..=8 {
        for j in 0..4 {
            q.push(up(i as f32 * 0.12, 1.2 + j as f32 * 0.5));
        }
    }
    q
}

/// Mean and standard deviation.
pub fn mean_sd(v: &[f64]) -> (f64, f64) {
    let (m, se) = mean_se(v);
    (m, se * (v.len() as f64).sqrt())
}

/// Every stability case must give finite, non-negative values and a sane kernel.
pub fn assert_sane(e: &DiffusionEstimate, map: &PhotonMap, q: &Query) -> Vec3 {
    let v = estimate(e, map, q);
    assert!(v.is_finite() && v.min_element() >= 0.0, "{v}");
    let s = shape(e, map, q);
    let floor = e.params().lambda2_floor as f32;
    assert!(s.lambda2 >= floor && s.lambda2 <= 1.0, "{s:?}");
    assert!(
        (s.x1.length() - 1.0).abs() < 1e-5 && s.x1.dot(q.normal).abs() < 1e-5,
        "{s:?}"
    );
    assert!(
        s.mu1.is_finite() && s.mu1 >= 0.0 && !s.contrast.is_nan(),
        "{s:?}"
    );
    v
}
