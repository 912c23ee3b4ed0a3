//! The gradient pass against the photon-by-photon sum, on data built to trip the node
//! shortcut: dense clusters, two walls meeting at a corner, a curved surface, radii from far
//! below the photon spacing to far above the scene.

use super::*;
use crate::photon::Photon;

fn photon(x: f32, y: f32, power: f32) -> Photon {
    Photon::new(Vec3::new(x, y, 0.0), Vec3::splat(power), -Vec3::Z, Vec3::Z)
}

/// A small deterministic generator (the tests need no statistical quality).
struct Lcg(u64);
impl Lcg {
    fn unit(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// Floor z = 0 (normal +z) with a dense cluster, a wall x = 0 (normal +x) meeting it, and a
/// cylinder of radius 0.3 (normals outwards), with powers over four decades.
fn tricky_scene(count: usize, seed: u64) -> PhotonMap {
    let mut rng = Lcg(seed);
    let mut photons = Vec::with_capacity(count);
    for i in 0..count {
        let power = 10f32.powf(4.0 * rng.unit() - 2.0);
        let (u, v) = (rng.unit(), rng.unit());
        let (position, normal) = match i % 4 {
            0 => (Vec3::new(u, v, 0.0), Vec3::Z),
            1 => (Vec3::new(0.3 + 0.02 * u, 0.4 + 0.02 * v, 0.0), Vec3::Z),
            2 => (Vec3::new(0.0, u, v), Vec3::X),
            _ => {
                let a = u * std::f32::consts::TAU;
                let n = Vec3::new(a.cos(), a.sin(), 0.0);
                (Vec3::new(0.6, 0.6, v) + 0.3 * n, n)
            }
        };
        photons.push(Photon::new(position, Vec3::splat(power), -normal, normal));
    }
    PhotonMap::build(photons, count as u64)
}

/// Checks the one-photon walk ([`NodeSums::sum_at`]) and the pass itself (the dual walk,
/// scaled) against the photon-by-photon sum at `slots`.
fn assert_matches_photon_by_photon(map: &PhotonMap, radius: f32, slots: impl Iterator<Item = u32>) {
    let sums = NodeSums::build(map);
    let dual = compute_gradients(map, radius);
    let scale = 4.0 / (PI * (radius as f64).powi(4));
    let tolerance = map.total_power().x as f64 * radius as f64 * 1e-9;
    for slot in slots {
        let want = brute_force_sum(map, slot, radius);
        let got = sums.sum_at(map, slot, radius);
        assert!(
            (got - want).length() <= tolerance,
            "r = {radius}, slot {slot}: {got} vs {want}"
        );
        let got = dual[slot as usize].as_dvec3();
        assert!(
            (got - want * scale).length() <= tolerance * scale + 1e-6 * got.length(),
            "dual, r = {radius}, slot {slot}: {got} vs {}",
            want * scale
        );
    }
}

#[test]
fn node_sums_match_the_photon_by_photon_sum() {
    for (seed, radius) in [(1, 0.004f32), (2, 0.03), (3, 0.15), (4, 0.6), (5, 5.0)] {
        let map = tricky_scene(6000, seed);
        assert_matches_photon_by_photon(&map, radius, (0..map.len() as u32).step_by(7));
    }
}

#[test]
fn a_node_with_mixed_normals_is_opened_not_taken() {
    // Two photons 1 mm apart on either side of a thin wall: one node holds both, and a radius
    // covering the whole node must still leave the far side out.
    let front = Photon::new(Vec3::ZERO, Vec3::ONE, -Vec3::Z, Vec3::Z);
    let back = Photon::new(
        Vec3::new(0.001, 0.0, 0.0),
        Vec3::splat(5.0),
        Vec3::Z,
        -Vec3::Z,
    );
    let map = PhotonMap::build(vec![front, back], 2);
    for g in compute_gradients(&map, 1.0) {
        assert_eq!(g, Vec3::ZERO);
    }
}

#[test]
fn gradient_points_towards_more_power_with_the_epanechnikov_scale() {
    // One photon at the origin and one at (0.5, 0) of power 2: within r_g = 1 the origin's
    // gradient is 4/π · 0.5 · 2 along +x; the other photon's is its mirror image.
    let map = PhotonMap::build(vec![photon(0.0, 0.0, 1.0), photon(0.5, 0.0, 2.0)], 2);
    let g = compute_gradients(&map, 1.0);
    for (slot, p) in map.photons().enumerate() {
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
    for (slot, p) in map.photons().enumerate() {
        assert_eq!(g[slot], Vec3::ZERO, "{:?}", p.position());
    }
    let map = PhotonMap::build(vec![photon(0.0, 0.0, 1e30), photon(1e-9, 0.0, 1e30)], 2);
    let g = compute_gradients(&map, 1e-8);
    assert!(g.iter().all(|g| g.is_finite() && g.x != 0.0));
}

#[test]
fn the_lanes_past_a_leafs_end_are_masked_out() {
    // Eight photons, all inside the disc: summing the first n must see only those n, though
    // the four-wide groups read on to the eighth.
    let xs: Vec<f32> = (0..8).map(|i| 0.01 * i as f32).collect();
    let ys: Vec<f32> = (0..8).map(|i| -0.02 * i as f32).collect();
    let zs = [0.0f32; 8];
    let powers: Vec<f64> = (0..8).map(|i| 1.0 + i as f64).collect();
    let q = Query {
        x: Vec3::new(0.005, 0.0, 0.0),
        normal: Vec3::Z,
        radius2: 1.0,
    };
    for n in 0..=8usize {
        let len = n.div_ceil(4) * 4;
        let got = sum_within([&xs[..len], &ys[..len], &zs[..len]], &powers[..len], n, &q);
        let want = (0..n).fold(DVec3::ZERO, |s, i| {
            s + DVec3::new((xs[i] - q.x.x) as f64, ys[i] as f64, 0.0) * powers[i]
        });
        assert!((got - want).length() <= 1e-12, "n = {n}: {got} vs {want}");
    }
}

#[test]
fn every_photon_of_the_last_leaves_matches_the_photon_by_photon_sum() {
    // Photon counts whose last leaf is not a whole number of four-wide groups: its scan
    // cannot read past the arrays and goes through a padded copy.
    for count in [1usize, 2, 3, 5, 23, 41, 6001] {
        let map = tricky_scene(count, count as u64);
        let first = map.len().saturating_sub(60) as u32;
        assert_matches_photon_by_photon(&map, 0.2, first..map.len() as u32);
    }
}

#[test]
fn far_from_the_origin_the_box_tests_still_agree_with_each_photons_own() {
    // At |x| ≈ 10⁴ an f32 has about a millimetre of resolution, so a photon's distance and a
    // box's are both rounded coarsely; the box tests must still never skip a photon the
    // photon-by-photon sum takes, nor take one it skips.
    let offset = Vec3::new(12_345.6, -9_876.5, 4_321.0);
    let mut rng = Lcg(11);
    // Half spread thinly, half in a dense patch, so that many photons lie near every rim.
    let photons: Vec<Photon> = (0..4000)
        .map(|i| {
            let spread = if i % 2 == 0 { 0.5 } else { 0.03 };
            let p = offset + Vec3::new(rng.unit(), rng.unit(), 0.0) * spread;
            Photon::new(p, Vec3::splat(1.0 + rng.unit()), -Vec3::Z, Vec3::Z)
        })
        .collect();
    let map = PhotonMap::build(photons, 4000);
    for radius in [0.004f32, 0.02, 0.1] {
        assert_matches_photon_by_photon(&map, radius, (0..map.len() as u32).step_by(3));
    }
}
