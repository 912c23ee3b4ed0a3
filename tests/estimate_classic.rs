//! The classic estimates (issue 3): unbiased on a uniform density for every kernel and k,
//! blind to photons on other surfaces, linear in power, invariant under rotation, zero on an
//! empty map. Uses only the public interface.

mod estimate_support;

use dpm::estimate::{
    EstimateError, EstimatorKind, EstimatorSettings, FixedRadiusEstimate, KnnEstimate, Query,
    RadialKernel, RadianceEstimate, ResolvedEstimator,
};
use dpm::photon::{Neighbours, Photon, PhotonMap};
use estimate_support::*;
use glam::Vec3;
use std::f32::consts::PI;

/// Photons per unit-square set; the density (photons per unit area) is the same number.
const N: usize = 6000;
/// Powers of two are stored exactly, so the true irradiance is exact too.
const POWER: Vec3 = Vec3::new(1.0, 0.5, 0.25);

fn knn_kernels() -> Vec<RadialKernel> {
    vec![
        RadialKernel::Constant,
        RadialKernel::Cone { slope: 1.0 },
        RadialKernel::Cone { slope: 1.1 },
        RadialKernel::Cone { slope: 4.0 },
        RadialKernel::Gaussian,
        RadialKernel::Epanechnikov,
    ]
}

/// Estimates (red channel, relative to the truth) at grid queries spaced so that no two
/// share photons, over as many independent sets as it takes to reach `min_queries`.
/// `also` sees the map and query too, for test-side variants.
fn sample_uniform(
    estimates: &[&dyn RadianceEstimate],
    support: f32,
    min_queries: usize,
    seed: u64,
    mut also: impl FnMut(&PhotonMap, &Query, &[Vec3]),
) -> Vec<Vec<f64>> {
    let mut out = vec![Vec::new(); estimates.len()];
    let mut rng = Rng(seed);
    let queries = grid(1.5 * support, 1.0 - 1.5 * support, 2.5 * support);
    while out[0].len() < min_queries {
        let map = PhotonMap::build(
            uniform_rect(&mut rng, N, (0.0, 1.0), (0.0, 1.0), POWER),
            N as u64,
        );
        for &(x, y) in &queries {
            let q = up(x, y);
            let values: Vec<Vec3> = estimates.iter().map(|e| estimate(*e, &map, &q)).collect();
            for (i, v) in values.iter().enumerate() {
                assert!((v.y / v.x - 0.5).abs() < 1e-5 && (v.z / v.x - 0.25).abs() < 1e-5);
                out[i].push(v.x as f64 / N as f64);
            }
            also(&map, &q, &values);
        }
    }
    out
}

fn assert_unbiased(name: &str, samples: &[f64]) {
    let (mean, se) = mean_se(samples);
    assert!(se < 0.02, "{name}: too few samples to tell (se {se})");
    assert!(
        (mean - 1.0).abs() < 4.0 * se,
        "{name}: mean {mean} ± {se}, truth 1"
    );
}

#[test]
fn knn_estimates_are_unbiased_on_a_uniform_density() {
    for (k, min_queries) in [(20usize, 1400usize), (50, 400), (200, 64)] {
        let knn: Vec<KnnEstimate> = knn_kernels()
            .into_iter()
            .map(|kernel| KnnEstimate::new(kernel, k, None))
            .collect();
        let refs: Vec<&dyn RadianceEstimate> =
            knn.iter().map(|e| e as &dyn RadianceEstimate).collect();
        let r_mean = (k as f32 / (PI * N as f32)).sqrt();
        // Test-side variants that sum the k-th photon too: they must fail the same check.
        let mut included_simple = Vec::new();
        let mut included_cone4 = Vec::new();
        let mut found = Neighbours::new();
        let samples = sample_uniform(&refs, r_mean, min_queries, 11 + k as u64, |map, q, v| {
            map.tree()
                .k_nearest(q.position, k, f32::INFINITY, &mut found);
            let r2 = found.farthest().unwrap().dist2;
            included_simple.push(v[0].x as f64 * k as f64 / (k - 1) as f64 / N as f64);
            let rim = RadialKernel::Cone { slope: 4.0 }.rim_weight() * POWER.x as f64 / r2 as f64;
            included_cone4.push((v[3].x as f64 + rim) / N as f64);
        });
        for (e, s) in knn.iter().zip(&samples) {
            assert_unbiased(&format!("{} {:?} k={k}", e.name(), e.kernel()), s);
        }
        if k == 20 {
            for (name, s) in [
                ("simple", &included_simple),
                ("cone slope 4", &included_cone4),
            ] {
                let (mean, se) = mean_se(s);
                assert!(
                    mean - 1.0 > 4.0 * se,
                    "{name} with the k-th photon: {mean} ± {se}"
                );
            }
        }
    }
}

#[test]
fn capped_knn_search_stays_unbiased() {
    // The cap is about the k-th distance, so about half the queries stop at the cap.
    let k = 40;
    let cap = (k as f32 / (PI * N as f32)).sqrt();
    let e = [
        KnnEstimate::new(RadialKernel::Constant, k, Some(cap)),
        KnnEstimate::new(RadialKernel::Cone { slope: 1.1 }, k, Some(cap)),
    ];
    let mut capped = 0;
    let mut found = Neighbours::new();
    let refs: Vec<&dyn RadianceEstimate> = e.iter().map(|e| e as &dyn RadianceEstimate).collect();
    let samples = sample_uniform(&refs, cap, 700, 5, |map, q, _| {
        map.tree().k_nearest(q.position, k, cap * cap, &mut found);
        capped += (found.len() < k) as usize;
    });
    assert!(
        capped > 100 && capped < samples[0].len() - 100,
        "cap hit {capped} times"
    );
    for (e, s) in e.iter().zip(&samples) {
        assert_unbiased(&format!("capped {}", e.name()), s);
    }
}

#[test]
fn fixed_radius_epanechnikov_is_unbiased_on_a_uniform_density() {
    for (photons_per_disc, min_queries) in [(50.0f32, 600usize), (200.0, 150)] {
        let r = (photons_per_disc / (PI * N as f32)).sqrt();
        let e = FixedRadiusEstimate::new(RadialKernel::Epanechnikov, r);
        let samples = sample_uniform(&[&e], r, min_queries, 3, |_, _, _| {});
        assert_unbiased(&format!("epanechnikov r={r}"), &samples[0]);
    }
}

/// Every estimate the settings can build that needs no gradient pass, with `k` and `radius`.
fn classic_estimates(k: usize, radius: f32) -> Vec<Box<dyn RadianceEstimate>> {
    [
        EstimatorKind::Simple,
        EstimatorKind::Cone,
        EstimatorKind::Gaussian,
        EstimatorKind::Epanechnikov,
    ]
    .into_iter()
    .map(|estimator| {
        let s = EstimatorSettings {
            estimator,
            k,
            radius: (estimator == EstimatorKind::Epanechnikov).then_some(radius),
            ..Default::default()
        };
        s.build(&PhotonMap::default()).expect("valid settings")
    })
    .collect()
}

/// Mean red-channel estimate over grid queries, relative to `truth`.
fn mean_relative(
    e: &dyn RadianceEstimate,
    map: &PhotonMap,
    queries: &[Query],
    truth: f32,
) -> (f64, f64) {
    let v: Vec<f64> = queries
        .iter()
        .map(|q| (estimate(e, map, q).x / truth) as f64)
        .collect();
    mean_se(&v)
}

#[test]
fn the_far_side_of_a_thin_wall_is_not_gathered() {
    // Two sheets a hair apart: the front (normal +z) lit with power 1, the back (normal −z)
    // with power 16. Each side's estimate must see only its own sheet, on average exactly.
    let k = 40;
    let r = (k as f32 / (PI * N as f32)).sqrt();
    let mut rng = Rng(21);
    let mut photons = Vec::new();
    for _ in 0..3 * N / 2 {
        let (x, y) = (rng.f32(), rng.f32());
        photons.push(if rng.f32() < 0.5 {
            plane_photon(x, y, 0.0, Vec3::ONE, Vec3::Z)
        } else {
            plane_photon(x, y, -1e-4, Vec3::splat(16.0), -Vec3::Z)
        });
    }
    let map = PhotonMap::build(photons, 0);
    let density = 3.0 * N as f32 / 4.0; // per sheet
    let points = grid(1.5 * r, 1.0 - 1.5 * r, 2.5 * r);
    let front: Vec<Query> = points.iter().map(|&(x, y)| up(x, y)).collect();
    let back: Vec<Query> = points
        .iter()
        .map(|&(x, y)| Query {
            position: Vec3::new(x, y, -1e-4),
            normal: -Vec3::Z,
        })
        .collect();
    for e in classic_estimates(k, r) {
        let (m, se) = mean_relative(&*e, &map, &front, density);
        assert!(
            (m - 1.0).abs() < 4.0 * se && se < 0.05,
            "{} front: {m} ± {se}",
            e.name()
        );
        let (m, se) = mean_relative(&*e, &map, &back, 16.0 * density);
        assert!(
            (m - 1.0).abs() < 4.0 * se && se < 0.05,
            "{} back: {m} ± {se}",
            e.name()
        );
    }
}

#[test]
fn a_perpendicular_wall_at_a_corner_is_not_gathered() {
    // A floor (normal +z) crossed by a wall at x = 0.5 (normal +x, 16 times brighter); queries
    // on the floor right next to the wall and on the wall right above the floor.
    let k = 40;
    let r = (k as f32 / (PI * N as f32)).sqrt();
    let mut rng = Rng(8);
    let mut photons = uniform_rect(&mut rng, N, (0.0, 1.0), (0.0, 1.0), Vec3::ONE);
    for _ in 0..N / 2 {
        let p = Vec3::new(0.5, rng.f32(), rng.f32() * 0.5);
        photons.push(Photon::new(p, Vec3::splat(16.0), -Vec3::X, Vec3::X));
    }
    let map = PhotonMap::build(photons, 0);
    let ys: Vec<f32> = (0..)
        .map(|i| 0.1 + i as f32 * 2.5 * r)
        .take_while(|y| *y < 0.9)
        .collect();
    let floor: Vec<Query> = ys.iter().map(|&y| up(0.5 + 0.3 * r, y)).collect();
    let wall: Vec<Query> = ys
        .iter()
        .map(|&y| Query {
            position: Vec3::new(0.5, y, 0.3 * r),
            normal: Vec3::X,
        })
        .collect();
    for e in classic_estimates(k, r) {
        let (m, se) = mean_relative(&*e, &map, &floor, N as f32);
        assert!(
            (m - 1.0).abs() < 4.0 * se + 0.02,
            "{} floor: {m} ± {se}",
            e.name()
        );
        // On the wall the floor is rejected, but the wall ends at z = 0, so a disc reaching
        // below it is cut: between half and all of the wall's density, never the floor's 1/8.
        let (m, se) = mean_relative(&*e, &map, &wall, 16.0 * (N / 2) as f32 / 0.5);
        assert!(
            m > 0.5 - 4.0 * se && m < 1.0 + 4.0 * se,
            "{} wall: {m} ± {se}",
            e.name()
        );
    }
}

fn small_map(seed: u64, scale: f32) -> PhotonMap {
    let mut rng = Rng(seed);
    let photons: Vec<Photon> = (0..2000)
        .map(|_| {
            let p = Vec3::new(rng.f32(), rng.f32(), 0.0);
            let c = Vec3::new(0.25 + rng.f32(), 0.5 * rng.f32(), 2.0);
            plane_photon(p.x, p.y, 0.0, c * scale, Vec3::Z)
        })
        .collect();
    PhotonMap::build(photons, 2000)
}

#[test]
fn estimates_scale_linearly_with_light_power() {
    let r = 0.08;
    let queries: Vec<Query> = grid(0.2, 0.8, 0.1)
        .into_iter()
        .map(|(x, y)| up(x, y))
        .collect();
    let base = small_map(4, 1.0);
    for (scale, tolerance) in [
        (1024.0f32, 1e-6),
        (2f32.powi(-60), 1e-6),
        // Other factors round each photon's power again: within 1/256 of its largest channel.
        (3.0, 1.0 / 200.0),
        (1e20, 1.0 / 200.0),
        (1e-20, 1.0 / 200.0),
    ] {
        let scaled = small_map(4, scale);
        for e in classic_estimates(30, r) {
            for q in &queries {
                let (a, b) = (estimate(&*e, &base, q) * scale, estimate(&*e, &scaled, q));
                assert!(a.x > 0.0, "{}", e.name());
                let largest = a.max_element();
                for c in 0..3 {
                    assert!(
                        (a[c] - b[c]).abs() <= tolerance * largest,
                        "{} ×{scale}: {a} vs {b}",
                        e.name()
                    );
                }
            }
        }
    }
}

#[test]
fn rotating_photons_and_query_leaves_estimates_unchanged() {
    let base = small_map(9, 1.0);
    let queries: Vec<Query> = grid(0.2, 0.8, 0.15)
        .into_iter()
        .map(|(x, y)| up(x, y))
        .collect();
    let mut rng = Rng(77);
    for _ in 0..3 {
        let rot = rng.rotation();
        let photons = base.photons().map(|p| rotate_photon(&p, rot)).collect();
        let rotated = PhotonMap::build(photons, 2000);
        for e in classic_estimates(30, 0.08) {
            for q in &queries {
                let (a, b) = (
                    estimate(&*e, &base, q),
                    estimate(&*e, &rotated, &rotate_query(q, rot)),
                );
                assert!(a.x > 0.0, "{}", e.name());
                for c in 0..3 {
                    assert!(rel(a[c], b[c]) < 1e-4, "{} {rot:?}: {a} vs {b}", e.name());
                }
            }
        }
    }
}

#[test]
fn an_empty_or_tiny_map_gives_zero_never_nan() {
    let empty = PhotonMap::default();
    let one = PhotonMap::build(vec![plane_photon(0.0, 0.0, 0.0, Vec3::ONE, Vec3::Z)], 1);
    let same_point = PhotonMap::build(
        vec![plane_photon(0.0, 0.0, 0.0, Vec3::ONE, Vec3::Z); 50],
        50,
    );
    for estimator in [
        EstimatorKind::Simple,
        EstimatorKind::Cone,
        EstimatorKind::Gaussian,
        EstimatorKind::Epanechnikov,
    ] {
        let s = EstimatorSettings {
            estimator,
            k: 10,
            ..Default::default()
        };
        let e = s.build(&empty).expect("an empty map needs no radius");
        assert_eq!(estimate(&*e, &empty, &up(0.0, 0.0)), Vec3::ZERO);
        // One photon: k-NN leaves it out; the fixed radius (1, the empty-map fallback) has it.
        let v = estimate(&*e, &one, &up(0.1, 0.0));
        assert!(
            v.is_finite() && v.min_element() >= 0.0,
            "{estimator:?}: {v}"
        );
        // Coincident photons: no area to divide by for k-NN, a finite sum for fixed radius.
        let s = EstimatorSettings {
            radius: Some(0.5),
            ..s
        };
        let e = s.build(&same_point).unwrap();
        for q in [up(0.0, 0.0), up(0.2, 0.0), up(5.0, 5.0)] {
            let v = estimate(&*e, &same_point, &q);
            assert!(
                v.is_finite() && v.min_element() >= 0.0,
                "{estimator:?}: {v}"
            );
        }
    }
    // Deriving a radius from coincident photons is impossible, and says so.
    let s = EstimatorSettings {
        estimator: EstimatorKind::Epanechnikov,
        k: 10,
        ..Default::default()
    };
    assert_eq!(
        s.build(&same_point).err(),
        Some(EstimateError::DegenerateMap)
    );
}

#[test]
fn settings_derive_the_k_equivalent_radius_and_reject_bad_values() {
    let map = PhotonMap::build(
        uniform_rect(&mut Rng(2), N, (0.0, 1.0), (0.0, 1.0), POWER),
        N as u64,
    );
    for k in [20, 100] {
        let s = EstimatorSettings {
            estimator: EstimatorKind::Epanechnikov,
            k,
            ..Default::default()
        };
        let ResolvedEstimator::FixedRadius(e) = s.resolve(&map).unwrap() else {
            panic!()
        };
        // The median of Gamma(k) is about k − 1/3; borders make it a little larger.
        let expected = (k as f32 / (PI * N as f32)).sqrt();
        assert!(
            rel(e.radius(), expected) < 0.1,
            "k={k}: {} vs {expected}",
            e.radius()
        );
        let ResolvedEstimator::Diffusion(d) = (EstimatorSettings {
            estimator: EstimatorKind::Diffusion,
            ..s
        })
        .resolve(&map)
        .unwrap() else {
            panic!()
        };
        let p = d.params();
        assert_eq!(
            (p.radius, p.gradient_radius, p.smoothing_radius),
            (e.radius(), e.radius() / 2.0, e.radius())
        );
    }
    let s = EstimatorSettings {
        estimator: EstimatorKind::Cone,
        k: 1,
        ..Default::default()
    };
    assert!(matches!(
        s.build(&map).err(),
        Some(EstimateError::InvalidSetting { flag: "k", .. })
    ));
    let s = EstimatorSettings {
        estimator: EstimatorKind::Simple,
        radius: Some(f32::NAN),
        ..Default::default()
    };
    assert!(matches!(
        s.build(&map).err(),
        Some(EstimateError::InvalidSetting { flag: "radius", .. })
    ));
    let s = EstimatorSettings {
        estimator: EstimatorKind::Cone,
        k: 50,
        cone_slope: 2.0,
        ..Default::default()
    };
    assert_eq!(
        s.resolve(&map).unwrap().to_string(),
        "cone k=50 cone-slope=2"
    );
}
