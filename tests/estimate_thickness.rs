//! How far a k-NN estimate's photons lie off the query's tangent plane
//! (`KnnEstimate::irradiance_and_thickness`), which decides where the eye pass stops reading
//! the global map: against a brute-force pass over every photon, and against the analytic
//! values of a plane (0), a sphere read over radius r (≈ 0.29 r/R) and photons filling a ball
//! (√(1/5)). A stack of planes closer than the radius is flagged, and shown to be what the
//! flag is for: the estimate there counts every plane's photons as the query's own.

mod estimate_support;

use dpm::estimate::{KnnEstimate, Query, RadialKernel, Scratch, THICK_GATHER};
use dpm::photon::{Photon, PhotonMap};
use estimate_support::*;
use glam::Vec3;

const K: usize = 100;
const POWER: Vec3 = Vec3::new(1.0, 1.0, 1.0);

fn knn() -> KnnEstimate {
    KnnEstimate::new(RadialKernel::Constant, K, None)
}

fn thickness(map: &PhotonMap, query: &Query) -> (Vec3, f32) {
    knn().irradiance_and_thickness(map, query, &mut Scratch::default())
}

/// The same statistic by brute force: every photon, the k-th distance by sorting, the agreeing
/// ones strictly inside it.
fn brute_thickness(photons: &[Photon], query: &Query) -> f32 {
    let mut d2: Vec<f32> = (photons.iter())
        .map(|p| p.position().distance_squared(query.position))
        .collect();
    d2.sort_by(f32::total_cmp);
    let r2 = d2[K - 1];
    let (mut sum, mut count) = (0.0f64, 0u32);
    for p in photons {
        let d = p.position() - query.position;
        if d.length_squared() < r2 && p.normal().dot(query.normal) >= 0.5 {
            sum += f64::from(d.dot(query.normal)).powi(2);
            count += 1;
        }
    }
    (sum / (f64::from(count) * f64::from(r2))).sqrt() as f32
}

/// `n` photons on the sphere of radius `radius` centred at the origin, normals outward.
fn on_sphere(rng: &mut Rng, n: usize, radius: f32) -> Vec<Photon> {
    (0..n)
        .map(|_| {
            let z = rng.range(-1.0, 1.0);
            let phi = rng.range(0.0, std::f32::consts::TAU);
            let s = (1.0 - z * z).sqrt();
            let normal = Vec3::new(s * phi.cos(), s * phi.sin(), z);
            Photon::new(normal * radius, POWER, -normal, normal)
        })
        .collect()
}

/// `n` photons filling the unit ball, every normal +z: the photons of many small surfaces
/// facing one way, scattered through a volume.
fn in_ball(rng: &mut Rng, n: usize) -> Vec<Photon> {
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let p = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        if p.length_squared() <= 1.0 {
            out.push(Photon::new(p, POWER, Vec3::NEG_Z, Vec3::Z));
        }
    }
    out
}

#[test]
fn thickness_matches_a_brute_force_pass_over_every_photon() {
    let mut rng = Rng(11);
    for photons in [
        on_sphere(&mut rng, 20_000, 0.3),
        in_ball(&mut rng, 20_000),
        uniform_rect(&mut rng, 20_000, (0.0, 1.0), (0.0, 1.0), POWER),
    ] {
        let map = PhotonMap::build(photons.clone(), photons.len() as u64);
        for i in 0..20 {
            let p = photons[i * 97];
            let query = Query {
                position: p.position(),
                normal: p.normal(),
            };
            let (_, got) = thickness(&map, &query);
            let want = brute_thickness(&photons, &query);
            assert!((got - want).abs() < 1e-4, "{got} against {want}");
        }
    }
}

#[test]
fn thickness_is_zero_on_a_plane_small_on_a_sphere_and_large_in_a_volume() {
    let mut rng = Rng(5);
    let plane = uniform_rect(&mut rng, 20_000, (0.0, 1.0), (0.0, 1.0), POWER);
    let map = PhotonMap::build(plane, 20_000);
    assert_eq!(thickness(&map, &up(0.5, 0.5)).1, 0.0);

    // On a sphere of radius R the height below the tangent plane at distance d is about
    // d²/(2R); over a disc of radius r its root mean square is r²/(2R√3), 0.29 r/R in radii.
    for (radius, n) in [(0.3f32, 40_000), (0.1, 4_000)] {
        let photons = on_sphere(&mut rng, n, radius);
        let map = PhotonMap::build(photons, n as u64);
        let top = Query {
            position: Vec3::new(0.0, 0.0, radius),
            normal: Vec3::Z,
        };
        let (_, t) = thickness(&map, &top);
        // k photons of n on the sphere lie within r where π r² ≈ 4π R² k/n.
        let r = radius * (4.0 * K as f32 / n as f32).sqrt();
        let want = r / (2.0 * radius * 3f32.sqrt());
        assert!(rel(t, want) < 0.2, "R = {radius}: {t} against {want}");
        assert!(t < THICK_GATHER, "a sphere read over {r} of its {radius}");
    }

    // A uniform ball of photons: E[z²] over a ball is r²/5.
    let photons = in_ball(&mut rng, 200_000);
    let map = PhotonMap::build(photons, 200_000);
    let (_, t) = thickness(&map, &up(0.0, 0.0));
    assert!(rel(t, 0.2f32.sqrt()) < 0.1, "{t}");
    assert!(t > THICK_GATHER);
}

#[test]
fn a_stack_of_planes_closer_than_the_radius_is_overstated_and_flagged() {
    // Ten planes 0.01 apart with the same photon density: the query's own plane holds a
    // tenth of the photons within a radius spanning the stack, and a k-NN estimate reads
    // them all as if they lay on it.
    let mut rng = Rng(9);
    let (planes, per_plane) = (10, 20_000);
    let mut photons = Vec::new();
    for i in 0..planes {
        for p in uniform_rect(&mut rng, per_plane, (0.0, 1.0), (0.0, 1.0), POWER) {
            let at = p.position() + Vec3::Z * (0.01 * i as f32);
            photons.push(Photon::new(at, POWER, Vec3::NEG_Z, Vec3::Z));
        }
    }
    let map = PhotonMap::build(photons, per_plane as u64);
    let mut overstated = 0.0;
    let queries = grid(0.2, 0.8, 0.2);
    for &(x, y) in &queries {
        let query = Query {
            position: Vec3::new(x, y, 0.05),
            normal: Vec3::Z,
        };
        let (e, t) = thickness(&map, &query);
        assert!(t > THICK_GATHER, "({x}, {y}): {t}");
        overstated += e.x as f64 / per_plane as f64 / queries.len() as f64;
    }
    assert!(
        overstated > 3.0,
        "{overstated} times the plane's irradiance"
    );
}
