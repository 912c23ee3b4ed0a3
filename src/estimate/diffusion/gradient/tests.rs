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

#[test]
fn node_sums_match_the_photon_by_photon_sum() {
    for (seed, radius) in [(1, 0.004f32), (2, 0.03), (3, 0.15), (4, 0.6), (5, 5.0)] {
        let map = tricky_scene(6000, seed);
        let sums = NodeSums::build(&map);
        let dual = compute_gradients(&map, radius);
        let scale = 4.0 / (PI * (radius as f64).powi(4));
        let tolerance = map.total_power().x as f64 * radius as f64 * 1e-9;
        for slot in (0..map.len() as u32).step_by(7) {
            let want = brute_force_sum(&map, slot, radius);
            let got = sums.sum_at(&map, slot, radius);
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
