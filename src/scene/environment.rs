//! An image environment: radiance from every direction, read from an image that covers the
//! sphere of directions. Owns what a texel means (which directions it covers and their solid
//! angle) under the two mappings pbrt's scenes use; holds data only and must not sample, trace
//! or read files ([`crate::world`] samples it, the scene readers fill it).
//!
//! Radiance is piecewise constant: every direction takes its texel's value (pbrt-v4 looks its
//! image up the same way; pbrt-v3 filters bilinearly, which moves a visible sky's texel edges
//! but not its light). So the map's integral and its sampling densities are exact sums over
//! texels, and a texel's directions can be drawn uniformly by solid angle.

use glam::{Mat3, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};
use std::fmt;
use std::sync::Arc;

/// How an image's texels cover the sphere, in the map's own frame (+z up).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SphereMapping {
    /// Equirectangular (pbrt-v3's `mapname`): column u = φ/2π with φ = atan2(y, x) in
    /// [0, 2π), row v = θ/π with θ = acos z, row 0 at +z.
    LatLong,
    /// Clarberg's equal-area octahedral mapping of a square (pbrt-v4's `filename`): every
    /// texel covers the same solid angle, 4π over the texel count.
    EqualAreaOctahedral,
}

/// Radiance by direction from an image.
#[derive(Clone, PartialEq)]
pub struct EnvironmentMap {
    pub width: u32,
    pub height: u32,
    /// Radiance of each texel, W/(m² sr) per channel, row by row from row 0; finite, >= 0.
    pub texels: Arc<[Vec3]>,
    pub mapping: SphereMapping,
    /// From the map's frame to the world's: orthonormal (a rotation, or one with a mirror).
    pub light_to_world: Mat3,
}

impl fmt::Debug for EnvironmentMap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("EnvironmentMap")
            .field("width", &self.width)
            .field("height", &self.height)
            .field("mapping", &self.mapping)
            .field("light_to_world", &self.light_to_world)
            .field("integral", &self.integral())
            .finish_non_exhaustive()
    }
}

impl EnvironmentMap {
    /// A `width` × `height` map whose texel `i` (row-major) has radiance `radiance(i)`.
    pub fn from_fn(
        width: u32,
        height: u32,
        mapping: SphereMapping,
        light_to_world: Mat3,
        radiance: impl FnMut(u32) -> Vec3,
    ) -> Self {
        Self {
            width,
            height,
            texels: (0..width * height).map(radiance).collect::<Vec<_>>().into(),
            mapping,
            light_to_world,
        }
    }

    /// The texel (row-major index) radiance arrives from along the unit world direction
    /// `towards` (pointing away from the scene, into the sky).
    #[inline]
    pub fn texel_towards(&self, towards: Vec3) -> usize {
        let local = self.light_to_world.transpose() * towards;
        let (w, h) = (self.width as usize, self.height as usize);
        let (u, v) = match self.mapping {
            SphereMapping::LatLong => {
                let theta = local.z.clamp(-1.0, 1.0).acos();
                let mut phi = local.y.atan2(local.x);
                if phi < 0.0 {
                    phi += TAU;
                }
                (phi / TAU, theta / PI)
            }
            SphereMapping::EqualAreaOctahedral => sphere_to_square(local),
        };
        let column = ((u * w as f32) as usize).min(w - 1);
        let row = ((v * h as f32) as usize).min(h - 1);
        row * w + column
    }

    /// Radiance arriving from the unit world direction `towards`.
    #[inline]
    pub fn radiance(&self, towards: Vec3) -> Vec3 {
        self.texels[self.texel_towards(towards)]
    }

    /// The solid angle texel `texel` covers, in steradians.
    pub fn texel_solid_angle(&self, texel: usize) -> f32 {
        match self.mapping {
            SphereMapping::LatLong => {
                let (w, h) = (self.width as f32, self.height as f32);
                let row = (texel / self.width as usize) as f32;
                let (top, bottom) = ((PI * row / h).cos(), (PI * (row + 1.0) / h).cos());
                TAU / w * (top - bottom)
            }
            SphereMapping::EqualAreaOctahedral => {
                4.0 * PI / (self.width as f32 * self.height as f32)
            }
        }
    }

    /// A world direction inside texel `texel`, uniform by solid angle over it as `u` runs
    /// over the unit square.
    #[inline]
    pub fn direction_in(&self, texel: usize, u: (f32, f32)) -> Vec3 {
        let (w, h) = (self.width as usize, self.height as usize);
        let (column, row) = ((texel % w) as f32, (texel / w) as f32);
        let local = match self.mapping {
            SphereMapping::LatLong => {
                let phi = TAU * (column + u.0) / w as f32;
                let top = (PI * row / h as f32).cos();
                let bottom = (PI * (row + 1.0) / h as f32).cos();
                let cos_theta = (top + u.1 * (bottom - top)).clamp(-1.0, 1.0);
                let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta)
            }
            SphereMapping::EqualAreaOctahedral => {
                square_to_sphere((column + u.0) / w as f32, (row + u.1) / h as f32)
            }
        };
        (self.light_to_world * local).normalize()
    }

    /// The direction at texel `texel`'s centre, in the map's own frame.
    pub fn local_centre(&self, texel: usize) -> Vec3 {
        self.light_to_world.transpose() * self.direction_in(texel, (0.5, 0.5))
    }

    /// ∫ L dω over the sphere, W/m² per channel.
    pub fn integral(&self) -> Vec3 {
        (self.texels.iter().enumerate())
            .map(|(i, &l)| l * self.texel_solid_angle(i))
            .sum()
    }
}

/// Clarberg's equal-area map from the unit square to the unit sphere: the square's inner
/// diamond to the upper hemisphere, its corners to the lower.
pub fn square_to_sphere(s: f32, t: f32) -> Vec3 {
    let (u, v) = (2.0 * s - 1.0, 2.0 * t - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed_distance = 1.0 - (up + vp);
    let r = 1.0 - signed_distance.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed_distance);
    let (sin_phi, cos_phi) = phi.sin_cos();
    let ring = r * (2.0 - r * r).max(0.0).sqrt();
    Vec3::new(cos_phi.copysign(u) * ring, sin_phi.copysign(v) * ring, z)
}

/// The inverse of [`square_to_sphere`] for a unit direction: its point of the unit square.
pub fn sphere_to_square(d: Vec3) -> (f32, f32) {
    let (x, y, z) = (d.x.abs(), d.y.abs(), d.z.abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let ratio = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = ratio.atan() / FRAC_PI_2;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d.z < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    ((u.copysign(d.x) + 1.0) * 0.5, (v.copysign(d.y) + 1.0) * 0.5)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(width: u32, height: u32, mapping: SphereMapping, to_world: Mat3) -> EnvironmentMap {
        EnvironmentMap::from_fn(width, height, mapping, to_world, |i| {
            Vec3::new(i as f32, 1.0, 0.5)
        })
    }

    #[test]
    fn the_equal_area_square_and_sphere_maps_invert_each_other() {
        for i in 0..40 {
            for j in 0..40 {
                let (s, t) = ((i as f32 + 0.5) / 40.0, (j as f32 + 0.5) / 40.0);
                let d = square_to_sphere(s, t);
                assert!((d.length() - 1.0).abs() < 1e-5, "{d}");
                let (s2, t2) = sphere_to_square(d);
                assert!(
                    (s - s2).abs() < 1e-4 && (t - t2).abs() < 1e-4,
                    "{s} {t} -> {s2} {t2}"
                );
            }
        }
        // The centre is the pole, the corners the other pole.
        assert!(square_to_sphere(0.5, 0.5).distance(Vec3::Z) < 1e-6);
        assert!(square_to_sphere(0.0, 1.0).distance(Vec3::NEG_Z) < 1e-6);
    }

    #[test]
    fn texel_solid_angles_sum_to_the_sphere_and_match_a_count_of_directions() {
        for mapping in [SphereMapping::LatLong, SphereMapping::EqualAreaOctahedral] {
            let (w, h) = match mapping {
                SphereMapping::LatLong => (16, 8),
                SphereMapping::EqualAreaOctahedral => (8, 8),
            };
            let m = map(w, h, mapping, Mat3::IDENTITY);
            let total: f32 = (0..(w * h) as usize).map(|i| m.texel_solid_angle(i)).sum();
            assert!((total - 4.0 * PI).abs() < 1e-4, "{mapping:?}: {total}");
            // Uniform directions over the sphere land in each texel by its solid angle.
            let n = 400_000;
            let mut counts = vec![0usize; (w * h) as usize];
            for k in 0..n {
                let a = (k as f32 + 0.5) / n as f32;
                let b = (k as f64 * 0.618_033_988_749_895).fract() as f32;
                let z = 1.0 - 2.0 * a;
                let r = (1.0 - z * z).max(0.0).sqrt();
                let d = Vec3::new(r * (TAU * b).cos(), r * (TAU * b).sin(), z);
                counts[m.texel_towards(d)] += 1;
            }
            for (i, &c) in counts.iter().enumerate() {
                let expected = n as f32 * m.texel_solid_angle(i) / (4.0 * PI);
                assert!(
                    (c as f32 - expected).abs() < 0.05 * expected + 30.0,
                    "{mapping:?} texel {i}: {c} against {expected}"
                );
            }
        }
    }

    #[test]
    fn directions_drawn_in_a_texel_look_that_texel_up_through_any_rotation() {
        let turn =
            Mat3::from_rotation_x(-FRAC_PI_2) * Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
        for mapping in [SphereMapping::LatLong, SphereMapping::EqualAreaOctahedral] {
            let m = map(12, 12, mapping, turn);
            for texel in 0..144 {
                for u in [(0.1, 0.2), (0.5, 0.5), (0.9, 0.7)] {
                    let d = m.direction_in(texel, u);
                    assert!((d.length() - 1.0).abs() < 1e-5);
                    assert_eq!(m.texel_towards(d), texel, "{mapping:?} {u:?}");
                }
            }
        }
    }

    #[test]
    fn lat_long_row_zero_is_the_maps_up() {
        let m = map(8, 4, SphereMapping::LatLong, Mat3::IDENTITY);
        assert_eq!(m.texel_towards(Vec3::Z) / 8, 0);
        assert_eq!(m.texel_towards(Vec3::NEG_Z) / 8, 3);
        // φ = 0 (+x) is column 0; +y is a quarter turn on.
        assert_eq!(
            m.texel_towards(Vec3::new(1.0, 0.01, 0.0).normalize()) % 8,
            0
        );
        assert_eq!(
            m.texel_towards(Vec3::new(-0.01, 1.0, 0.0).normalize()) % 8,
            2
        );
    }
}
