//! The pass schedule of a progressive render: what pass `i` draws and at which radii. Each pass
//! has its own random streams ([`pass_seed`]), the same photon counts and samples per pixel,
//! and a radius scale from the probabilistic formulation of progressive photon mapping (Knaus
//! and Zwicker, ACM TOG 2011): `r²(i+1) = r²(i) · (i + α)/(i + 1)`, `0 < α < 1`. Every radius
//! of every estimate (the fixed radius, the diffusion estimate's gradient and smoothing radii,
//! the k-NN search caps) shrinks by the same factor, so the diffusion tensor's dimensionless
//! contrast keeps its meaning from pass to pass. Owns those numbers; must not trace or shade.
//!
//! After `i` passes `r²(i) ∝ i^(α−1)`: the bias of a smooth density (∝ r²) falls like
//! `i^(α−1)` and the variance of the passes' mean like `i^(−α)`, so both vanish.

use crate::estimate::EstimatorSettings;
use crate::sampling::pass_seed;

/// Knaus and Zwicker's usual α.
pub const DEFAULT_ALPHA: f64 = 2.0 / 3.0;

/// Passes one run may name (first pass + passes): the radius scale is a product over passes.
pub const MAX_PASSES: u64 = 1_000_000;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Schedule {
    /// `α` of the radius reduction, in (0, 1).
    pub alpha: f64,
    pub seed: u64,
}

impl Schedule {
    pub fn new(alpha: f64, seed: u64) -> Self {
        Self { alpha, seed }
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
    let scale = schedule.radius_scale(pass);
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
}
