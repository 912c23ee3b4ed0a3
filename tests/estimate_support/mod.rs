//! Shared helpers of the estimate tests: a seeded generator, photon layouts, rotations and
//! statistics. Owns nothing of the crate; must not reimplement the estimates.
#![allow(dead_code)]

pub mod diffusion;

use dpm::estimate::{Query, RadianceEstimate, Scratch};
use dpm::photon::{Photon, PhotonMap};
use glam::{Quat, Vec3};

/// SplitMix64: small, seeded, good enough for test layouts.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.f32()
    }
    pub fn rotation(&mut self) -> Quat {
        let axis = loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if v.length() > 0.1 && v.length() < 1.0 {
                break v.normalize();
            }
        };
        Quat::from_axis_angle(axis, self.range(0.0, std::f32::consts::TAU))
    }
}

/// A photon on the plane z = `z`, lit from the side of `normal` (±z).
pub fn plane_photon(x: f32, y: f32, z: f32, power: Vec3, normal: Vec3) -> Photon {
    Photon::new(Vec3::new(x, y, z), power, -normal, normal)
}

/// `n` photons uniform in `[x0, x1] × [y0, y1]` on z = 0, normal +z.
pub fn uniform_rect(
    rng: &mut Rng,
    n: usize,
    (x0, x1): (f32, f32),
    (y0, y1): (f32, f32),
    power: Vec3,
) -> Vec<Photon> {
    (0..n)
        .map(|_| plane_photon(rng.range(x0, x1), rng.range(y0, y1), 0.0, power, Vec3::Z))
        .collect()
}

pub fn up(x: f32, y: f32) -> Query {
    Query {
        position: Vec3::new(x, y, 0.0),
        normal: Vec3::Z,
    }
}

/// Rotates a photon's position, direction and normal about the origin.
pub fn rotate_photon(p: &Photon, q: Quat) -> Photon {
    Photon::new(
        q * p.position(),
        p.power(),
        q * p.direction(),
        q * p.normal(),
    )
}

pub fn rotate_query(query: &Query, q: Quat) -> Query {
    Query {
        position: q * query.position,
        normal: q * query.normal,
    }
}

/// Query points on a square grid inside `[lo, hi]²` with the given spacing.
pub fn grid(lo: f32, hi: f32, spacing: f32) -> Vec<(f32, f32)> {
    let n = ((hi - lo) / spacing).floor() as usize + 1;
    let mut out = Vec::new();
    for i in 0..n {
        for j in 0..n {
            out.push((lo + i as f32 * spacing, lo + j as f32 * spacing));
        }
    }
    out
}

/// Mean and standard error of the mean.
pub fn mean_se(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

pub fn estimate(e: &dyn RadianceEstimate, map: &PhotonMap, q: &Query) -> Vec3 {
    e.irradiance(map, q, &mut Scratch::default())
}

/// Relative difference, safe at zero.
pub fn rel(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(f32::MIN_POSITIVE)
}
