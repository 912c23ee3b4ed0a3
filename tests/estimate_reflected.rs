//! Reflected radiance from photons at a glossy receiver (`RadianceEstimate::reflected`): the
//! same kernel over the same photons as the irradiance estimate, each photon weighed by the
//! receiver's BSDF for its direction. Checked for every estimate: a constant BSDF gives
//! ρ/π times the irradiance; a BSDF that sees one direction only picks out the photons that
//! came that way; a receiver that sees nothing returns zero.

mod estimate_support;

use dpm::estimate::{
    FixedRadiusEstimate, KnnEstimate, RadialKernel, RadianceEstimate, Receiver, Scratch,
};
use dpm::photon::{Photon, PhotonMap};
use estimate_support::diffusion::params;
use estimate_support::*;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// f = `value` for every direction.
struct Constant(Vec3);
impl Receiver for Constant {
    fn bsdf(&self, _travel: Vec3) -> Vec3 {
        self.0
    }
}

/// f = 1 for photons that travelled within 10° of `along`, 0 otherwise.
struct Cone {
    along: Vec3,
}
impl Receiver for Cone {
    fn bsdf(&self, travel: Vec3) -> Vec3 {
        if travel.dot(self.along) > 10f32.to_radians().cos() {
            Vec3::ONE
        } else {
            Vec3::ZERO
        }
    }
}

/// Every estimate dpm has, at radius (or about k photons for) 0.05 on a density of 8000.
fn estimates() -> Vec<(&'static str, Box<dyn RadianceEstimate>)> {
    vec![
        (
            "knn cone",
            Box::new(KnnEstimate::new(
                RadialKernel::Cone { slope: 1.0 },
                60,
                None,
            )),
        ),
        (
            "knn gaussian",
            Box::new(KnnEstimate::new(RadialKernel::Gaussian, 60, None)),
        ),
        (
            "fixed radius",
            Box::new(FixedRadiusEstimate::new(RadialKernel::Epanechnikov, 0.05)),
        ),
        (
            "diffusion",
            Box::new(dpm::estimate::DiffusionEstimate::new(params(0.05))),
        ),
    ]
}

/// Two photon populations over the unit square, on z = 0 lit from above: `steep` arriving
/// straight down, `grazing` along (1, 0, −1)/√2, with a step in the grazing density at x = 0.5
/// so the diffusion kernel has an edge to turn to.
fn two_directions(seed: u64) -> (Vec<Photon>, Vec3, Vec3) {
    let mut rng = Rng(seed);
    let steep = -Vec3::Z;
    let grazing = Vec3::new(1.0, 0.0, -1.0).normalize();
    let mut photons = Vec::new();
    for _ in 0..8000 {
        let p = Vec3::new(rng.f32(), rng.f32(), 0.0);
        photons.push(Photon::new(p, Vec3::new(1.0, 0.5, 0.25), steep, Vec3::Z));
        let g = Vec3::new(rng.f32(), rng.f32(), 0.0);
        let power = if g.x < 0.5 { 2.0 } else { 0.5 };
        photons.push(Photon::new(g, Vec3::splat(power), grazing, Vec3::Z));
    }
    (photons, steep, grazing)
}

fn queries() -> Vec<dpm::estimate::Query> {
    grid(0.2, 0.8, 0.15)
        .into_iter()
        .map(|(x, y)| up(x, y))
        .collect()
}

#[test]
fn a_constant_bsdf_reflects_its_albedo_over_pi_times_the_irradiance() {
    let (photons, _, _) = two_directions(3);
    let albedo = Vec3::new(0.8, 0.4, 0.2);
    for (name, e) in estimates() {
        let map = prepared_for(&*e, photons.clone());
        let mut scratch = Scratch::default();
        for q in queries() {
            let e_irr = e.irradiance(&map, &q, &mut scratch);
            let l = e.reflected(&map, &q, &Constant(albedo * FRAC_1_PI), &mut scratch);
            let expected = albedo * FRAC_1_PI * e_irr;
            for c in 0..3 {
                assert!(
                    rel(l[c], expected[c]) < 2e-4,
                    "{name} at {:?}: {l} against {expected}",
                    q.position
                );
            }
            assert!(l.x > 0.0, "{name}: no photons reached {:?}", q.position);
        }
    }
}

#[test]
fn a_receiver_that_sees_one_direction_reads_only_the_photons_from_it() {
    let (photons, steep, grazing) = two_directions(5);
    let steep_only: Vec<Photon> = (photons.iter().copied())
        .filter(|p| p.direction().dot(steep) > 0.99)
        .collect();
    for (name, e) in estimates() {
        if name.starts_with("knn") {
            // A k-NN radius depends on every photon: the populations cannot be told apart by
            // estimating one of them alone.
            continue;
        }
        let map = prepared_for(&*e, photons.clone());
        let mut scratch = Scratch::default();
        for q in queries() {
            let seen = e.reflected(&map, &q, &Cone { along: grazing }, &mut scratch);
            let all = e.reflected(&map, &q, &Constant(Vec3::ONE), &mut scratch);
            let steep_seen = e.reflected(&map, &q, &Cone { along: steep }, &mut scratch);
            // The two directions' parts add up to the whole, and the steep part alone carries
            // the steep photons' colour.
            for c in 0..3 {
                assert!(rel(seen[c] + steep_seen[c], all[c]) < 1e-4, "{name}");
            }
            assert!((steep_seen.y / steep_seen.x - 0.5).abs() < 1e-3, "{name}");
            assert!((seen.y / seen.x - 1.0).abs() < 1e-3, "{name}");
            if name == "fixed radius" {
                // A fixed kernel reads the steep photons exactly as a map of them alone.
                let alone = PhotonMap::build(steep_only.clone(), 0);
                let direct = e.irradiance(&alone, &q, &mut scratch);
                assert!(
                    rel(steep_seen.x, direct.x) < 1e-4,
                    "{steep_seen} vs {direct}"
                );
            }
        }
    }
}

#[test]
fn a_receiver_that_sees_nothing_reflects_nothing() {
    let (photons, _, _) = two_directions(7);
    for (name, e) in estimates() {
        let map = prepared_for(&*e, photons.clone());
        let mut scratch = Scratch::default();
        for q in queries() {
            let l = e.reflected(&map, &q, &Constant(Vec3::ZERO), &mut scratch);
            assert_eq!(l, Vec3::ZERO, "{name}");
        }
    }
}

fn prepared_for(e: &dyn RadianceEstimate, photons: Vec<Photon>) -> PhotonMap {
    let mut m = PhotonMap::build(photons, 0);
    e.prepare(&mut m);
    m
}
