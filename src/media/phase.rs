//! The Henyey–Greenstein phase function as pbrt defines it: for unit `wo` and `wi` both
//! pointing away from the scattering point, p = (1/4π)(1 − g²)/(1 + g² + 2g·(wo · wi))^{3/2},
//! so g > 0 scatters forward (wi near −wo, on along the way the light travelled). Sampled
//! exactly: the pdf is p itself and a sample's weight 1. g is clamped to ±0.99, as pbrt-v4
//! does, so that no sample is NaN as |g| → 1.

use crate::sampling::basis;
use glam::Vec3;
use std::f32::consts::PI;

/// The largest |g| kept.
pub const MAX_ASYMMETRY: f32 = 0.99;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HenyeyGreenstein {
    g: f32,
}

impl HenyeyGreenstein {
    /// The phase function of asymmetry `g` (clamped to ±[`MAX_ASYMMETRY`]; NaN reads as 0).
    pub fn new(g: f32) -> Self {
        let g = if g.is_nan() { 0.0 } else { g };
        Self {
            g: g.clamp(-MAX_ASYMMETRY, MAX_ASYMMETRY),
        }
    }

    pub fn g(&self) -> f32 {
        self.g
    }

    /// The density over the sphere of directions of the scattering angle whose cosine (between
    /// the direction light travelled in and the one it leaves by) is `mu`.
    pub fn of_cosine(&self, mu: f32) -> f32 {
        let g = self.g;
        let denom = (1.0 + g * g - 2.0 * g * mu).max(f32::MIN_POSITIVE);
        (1.0 - g * g) / (4.0 * PI * denom * denom.sqrt())
    }

    /// p(wo, wi), both unit and pointing away from the point.
    pub fn p(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.of_cosine(-wo.dot(wi))
    }

    /// The cosine of a scattering angle drawn from `u` in [0, 1).
    pub fn sample_cosine(&self, u: f32) -> f32 {
        let g = self.g;
        if g.abs() < 1e-3 {
            return 1.0 - 2.0 * u;
        }
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    }

    /// A direction wi drawn from p(wo, ·) by `u`, and its density (p itself).
    pub fn sample(&self, wo: Vec3, u: (f32, f32)) -> (Vec3, f32) {
        let mu = self.sample_cosine(u.0);
        let sin = (1.0 - mu * mu).max(0.0).sqrt();
        let (sin_phi, cos_phi) = (2.0 * PI * u.1).sin_cos();
        // Around the direction light travelled, −wo.
        let forward = -wo;
        let (t, b) = basis(forward);
        let wi = (mu * forward + sin * (cos_phi * t + sin_phi * b)).normalize();
        (wi, self.of_cosine(mu))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Stream};

    /// ∫ f(μ) dμ over [−1, 1] by the midpoint rule on `n` steps.
    fn integrate(n: usize, f: impl Fn(f64) -> f64) -> f64 {
        let h = 2.0 / n as f64;
        (0..n).map(|i| f(-1.0 + (i as f64 + 0.5) * h) * h).sum()
    }

    #[test]
    fn it_integrates_to_one_and_its_mean_cosine_is_g() {
        for g in [-0.9f32, -0.5, 0.0, 0.3, 0.8, 0.95] {
            let hg = HenyeyGreenstein::new(g);
            let total = integrate(200_000, |mu| {
                2.0 * std::f64::consts::PI * hg.of_cosine(mu as f32) as f64
            });
            let mean = integrate(200_000, |mu| {
                2.0 * std::f64::consts::PI * mu * hg.of_cosine(mu as f32) as f64
            });
            assert!((total - 1.0).abs() < 1e-3, "g {g}: {total}");
            assert!((mean - g as f64).abs() < 2e-3, "g {g}: mean cosine {mean}");
        }
    }

    #[test]
    fn positive_g_scatters_on_along_the_light_s_way_as_pbrt_s_does() {
        let hg = HenyeyGreenstein::new(0.7);
        let wo = Vec3::Z; // light came travelling along −z
        assert!(hg.p(wo, Vec3::NEG_Z) > 10.0 * hg.p(wo, Vec3::Z));
        let mut rng = Rng::for_index(3, Stream::Pixels, 0);
        let mean: f32 = (0..20_000)
            .map(|_| -hg.sample(wo, rng.next_2d()).0.z)
            .sum::<f32>()
            / 20_000.0;
        assert!((mean - 0.7).abs() < 0.02, "{mean}");
    }

    #[test]
    fn sampled_cosines_follow_the_density_by_a_chi_square_test() {
        let bins = 40;
        for g in [-0.6f32, 0.0, 0.5, 0.9] {
            let hg = HenyeyGreenstein::new(g);
            let n = 200_000;
            let mut counts = vec![0u32; bins];
            let mut rng = Rng::for_index(7, Stream::Pixels, g.to_bits() as u64);
            let wo = Vec3::new(0.3, -0.5, 0.8).normalize();
            for _ in 0..n {
                let (wi, pdf) = hg.sample(wo, rng.next_2d());
                assert!((pdf - hg.p(wo, wi)).abs() <= 1e-3 * pdf.max(1.0));
                let mu = -wo.dot(wi);
                counts[(((mu + 1.0) / 2.0 * bins as f32) as usize).min(bins - 1)] += 1;
            }
            let mut chi2 = 0.0;
            for (i, &c) in counts.iter().enumerate() {
                let (a, b) = (
                    -1.0 + 2.0 * i as f64 / bins as f64,
                    -1.0 + 2.0 * (i + 1) as f64 / bins as f64,
                );
                let p = integrate(2_000, |x| {
                    let mu = a + (b - a) * (x + 1.0) / 2.0;
                    2.0 * std::f64::consts::PI * hg.of_cosine(mu as f32) as f64 * (b - a) / 2.0
                });
                let expected = p * n as f64;
                chi2 += (c as f64 - expected).powi(2) / expected;
            }
            // 39 degrees of freedom: p = 0.001 at 72.
            assert!(chi2 < 72.0, "g {g}: χ² {chi2}");
        }
    }

    #[test]
    fn no_sample_is_nan_as_g_nears_one() {
        for g in [1.0f32, -1.0, 0.99999, f32::NAN] {
            let hg = HenyeyGreenstein::new(g);
            let mut rng = Rng::for_index(1, Stream::Pixels, 0);
            for _ in 0..10_000 {
                let (wi, pdf) = hg.sample(Vec3::X, rng.next_2d());
                assert!(wi.is_finite() && pdf.is_finite() && pdf > 0.0, "g {g}");
            }
            for mu in [-1.0, -0.5, 0.0, 1.0] {
                assert!(hg.of_cosine(mu).is_finite(), "g {g} μ {mu}");
            }
        }
    }
}
