//! The pass schedule of a progressive render: what pass `i` draws and at which radii. Each pass
//! has its own random streams ([`pass_seed`]), the same samples per pixel and global photons,
//! a caustic photon count that grows after `--caustic-growth-from` ([`PhotonGrowth`]), and a
//! radius scale from the probabilistic formulation of progressive photon mapping (Knaus
//! and Zwicker, ACM TOG 2011): `r²(i+1) = r²(i) · (i + α)/(i + 1)`, `0 < α < 1`. Every radius
//! of every estimate (the fixed radius, the diffusion estimate's gradient and smoothing radii,
//! the k-NN search caps) shrinks by the same factor, so the diffusion tensor's dimensionless
//! contrast keeps its meaning from pass to pass. Owns those numbers; must not trace or shade.
//!
//! After `i` passes `r²(i) ∝ i^(α−1)`: the bias of a smooth density (∝ r²) falls like
//! `i^(α−1)` and the variance of the passes' mean like `i^(−α)`, so both vanish. The caustic
//! map's growth is bounded: past its cap every pass is alike again, and neither limit moves.

use crate::estimate::EstimatorSettings;
use crate::sampling::pass_seed;

/// Knaus and Zwicker's usual α.
pub const DEFAULT_ALPHA: f64 = 2.0 / 3.0;

/// Passes one run may name (first pass + passes): the radius scale is a product over passes.
pub const MAX_PASSES: u64 = 1_000_000;

/// How the caustic map's photon count grows with the passes: pass `i` stores
/// `N · i / from_pass` photons (`N` = `--caustic-photons`), at least `N` and at most
/// `max_photons`, and its caustic radii shrink by the square root of that over `N` on top of
/// the progressive scale, so that each kernel holds the photons it would hold at the pass's own
/// index with a constant count: each pass is as noisy as before, only less blurred. Early
/// passes stay cheap (many camera samples soon, for the noise a short render shows); later
/// ones, whose error is mostly the kernels' blur, spend more of their time on photons, which
/// cost little beside the eye pass.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub struct PhotonGrowth {
    /// The last pass at the base count; 0: no growth.
    pub from_pass: u64,
    /// The most photons a pass stores.
    pub max_photons: u64,
}

impl PhotonGrowth {
    /// Every pass stores the same count: films written before growth existed.
    pub const NONE: PhotonGrowth = PhotonGrowth {
        from_pass: 0,
        max_photons: 0,
    };

    /// Growth from `base` photons after pass `from_pass` up to `max_photons`; every way of
    /// naming no growth (`from_pass` 0, `max_photons` at most `base`) is [`PhotonGrowth::NONE`],
    /// so that films that render alike compare equal.
    pub fn new(from_pass: u64, max_photons: u64, base: u64) -> Self {
        if from_pass == 0 || max_photons <= base {
            Self::NONE
        } else {
            Self {
                from_pass,
                max_photons,
            }
        }
    }

    pub fn is_none(&self) -> bool {
        *self == Self::NONE
    }

    /// Photons pass `pass` stores for a base count `base`.
    pub fn photons(&self, base: u64, pass: u64) -> u64 {
        if self.is_none() || pass <= self.from_pass {
            return base;
        }
        let grown = (base as f64 * pass as f64 / self.from_pass as f64).round();
        (grown.min(self.max_photons as f64) as u64).max(base)
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// `α` of the radius reduction, in (0, 1).
    pub alpha: f64,
    pub seed: u64,
    /// The caustic map's growth from `base_photons` a pass.
    pub growth: PhotonGrowth,
    pub base_photons: u64,
}

impl Schedule {
    pub fn new(alpha: f64, seed: u64) -> Self {
        Self {
            alpha,
            seed,
            growth: PhotonGrowth::NONE,
            base_photons: 0,
        }
    }

    /// The schedule with the caustic map growing from `base_photons` a pass.
    pub fn with_growth(self, growth: PhotonGrowth, base_photons: u64) -> Self {
        Self {
            growth,
            base_photons,
            ..self
        }
    }

    /// Photons pass `pass` stores in its caustic map.
    pub fn caustic_photons(&self, pass: u64) -> u64 {
        self.growth.photons(self.base_photons, pass)
    }

    /// The caustic estimate's radius scale in pass `pass`: the progressive scale, over the
    /// square root of the pass's photons over the base count.
    pub fn caustic_radius_scale(&self, pass: u64) -> f32 {
        let scale = self.radius_scale(pass) as f64;
        if self.growth.is_none() || self.base_photons == 0 {
            return scale as f32;
        }
        let factor = self.caustic_photons(pass) as f64 / self.base_photons as f64;
        (scale / factor.sqrt()) as f32
    }

    /// `r(pass) / r(0)`: `√Π_{j<pass} (j + α)/(j + 1)`, 1 at pass 0.
    pub fn radius_scale(&self, pass: u64) -> f32 {
        let pass = pass.min(MAX_PASSES);
        let mut r2 = 1.0f64;
        for j in 0..pass {
            r2 *= (j as f64 + self.alpha) / (j as f64 + 1.0);
        }
        r2.sqrt() as f32
    }

    /// The seed every random stream of pass `pass` derives from.
    pub fn seed(&self, pass: u64) -> u64 {
        pass_seed(self.seed, pass)
    }
}

/// The estimate's settings in pass `pass`, from the run's settings and the base radius pass 0
/// resolved (`--radius`, else its map's k-equivalent radius). The fixed-radius estimates scale
/// every radius from pass 0 on; the k-NN estimates keep pass 0 as the one-shot estimate and
/// cap their search at the scaled base radius from pass 1 on (see `render::pass`).
pub fn pass_estimator(
    settings: &EstimatorSettings,
    base_radius: Option<f32>,
    schedule: &Schedule,
    pass: u64,
) -> EstimatorSettings {
    let scale = schedule.caustic_radius_scale(pass);
    let mut e = settings.clone();
    if e.estimator.is_fixed_radius() {
        e.radius = base_radius.map(|r| r * scale).or(e.radius);
        e.gradient_radius = e.gradient_radius.map(|r| r * scale);
        e.smoothing_radius = e.smoothing_radius.map(|r| r * scale);
    } else if pass > 0 {
        e.radius = base_radius.map(|r| r * scale).or(e.radius);
    }
    e
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn radius_follows_the_recurrence_and_its_power_law() {
        let s = Schedule::new(DEFAULT_ALPHA, 1);
        assert_eq!(s.radius_scale(0), 1.0);
        for i in 0..50u64 {
            let (a, b) = (s.radius_scale(i) as f64, s.radius_scale(i + 1) as f64);
            let want = a * a * (i as f64 + DEFAULT_ALPHA) / (i as f64 + 1.0);
            assert!((b * b - want).abs() < 1e-6 * want, "pass {i}");
        }
        // r² ∝ i^(α−1) asymptotically: the ratio between i and 4i tends to 4^((α−1)/2).
        let ratio = s.radius_scale(40_000) as f64 / s.radius_scale(10_000) as f64;
        let want = 4f64.powf((DEFAULT_ALPHA - 1.0) / 2.0);
        assert!((ratio - want).abs() < 1e-3, "{ratio} vs {want}");
    }

    #[test]
    fn passes_have_distinct_seeds_and_pass_zero_keeps_the_run_seed() {
        let s = Schedule::new(0.5, 9);
        assert_eq!(s.seed(0), 9);
        assert_ne!(s.seed(1), s.seed(2));
    }

    #[test]
    fn photon_growth_is_flat_then_linear_then_capped() {
        let g = PhotonGrowth::new(8, 300_000, 75_000);
        let counts: Vec<u64> = [0, 7, 8, 9, 12, 16, 31, 32, 33, 1000]
            .iter()
            .map(|&p| g.photons(75_000, p))
            .collect();
        assert_eq!(
            counts,
            [
                75_000, 75_000, 75_000, 84_375, 112_500, 150_000, 290_625, 300_000, 300_000,
                300_000
            ]
        );
        for none in [
            PhotonGrowth::new(0, 300_000, 75_000),
            PhotonGrowth::new(8, 75_000, 75_000),
            PhotonGrowth::new(8, 300_000, 300_000),
            PhotonGrowth::new(8, 1000, 300_000),
        ] {
            assert_eq!(none, PhotonGrowth::NONE);
            assert_eq!(none.photons(75_000, 500), 75_000);
        }
    }

    /// A grown pass's caustic kernels cover the base count over its count of the area, so
    /// they hold the photons a pass of the base count holds at the same index: `r² · photons`
    /// does not move.
    #[test]
    fn a_grown_pass_keeps_its_photons_per_kernel() {
        let base = 1_000_000;
        let flat = Schedule::new(DEFAULT_ALPHA, 1);
        let grown = flat.with_growth(PhotonGrowth::new(4, 3 * base, base), base);
        for pass in 0..40u64 {
            let (r, r0) = (
                grown.caustic_radius_scale(pass) as f64,
                flat.caustic_radius_scale(pass) as f64,
            );
            assert_eq!(r0, flat.radius_scale(pass) as f64);
            let held = r * r * grown.caustic_photons(pass) as f64;
            let held0 = r0 * r0 * base as f64;
            assert!(
                (held / held0 - 1.0).abs() < 1e-5,
                "pass {pass}: {held} vs {held0}"
            );
            // The global map's radii do not grow.
            assert_eq!(grown.radius_scale(pass), flat.radius_scale(pass));
        }
        assert_eq!(grown.caustic_photons(39), 3 * base);
        assert!(grown.caustic_radius_scale(39) < 0.6 * flat.caustic_radius_scale(39));
    }
}
