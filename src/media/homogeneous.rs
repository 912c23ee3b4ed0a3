//! A homogeneous medium: absorption σa and scattering σs per colour channel, constant
//! everywhere. Transmittance over a distance d is exp(−σt·d) per channel. A free flight is
//! drawn as pbrt draws it: a channel chosen uniformly, a distance from its exponential, and
//! the result weighed by the channel average of the densities (one-sample spectral MIS), so a
//! medium whose σt differs by channel stays unbiased in every channel.

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    pub sigma_a: Vec3,
    pub sigma_s: Vec3,
}

/// Where a free flight along a segment ends, and the weight it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FreeFlight {
    /// A real scattering event at distance `t`; `weight` is σs·Tr(t)/pdf, what multiplies
    /// the path's throughput there (before the phase function is sampled).
    Scattered { t: f32, weight: Vec3 },
    /// No event before the segment's end; `weight` is Tr(end)/P(no event).
    Passed { weight: Vec3 },
}

impl Homogeneous {
    pub fn sigma_t(&self) -> Vec3 {
        self.sigma_a + self.sigma_s
    }

    /// exp(−σt·d) per channel.
    pub fn transmittance(&self, d: f32) -> Vec3 {
        (-self.sigma_t() * d.max(0.0)).exp()
    }

    /// The scattering albedo σs/σt per channel (0 where σt is 0).
    pub fn albedo(&self) -> Vec3 {
        let t = self.sigma_t();
        Vec3::select(t.cmpgt(Vec3::ZERO), self.sigma_s / t, Vec3::ZERO)
    }

    /// A free flight along a segment of length `end` (may be infinite), from `u_channel` and
    /// `u` in [0, 1).
    pub fn free_flight(&self, end: f32, u_channel: f32, u: f32) -> FreeFlight {
        let sigma_t = self.sigma_t();
        let channel = ((u_channel * 3.0) as usize).min(2);
        let s = sigma_t[channel];
        let t = if s > 0.0 {
            -(1.0 - u).ln() / s
        } else {
            f32::INFINITY
        };
        if t < end {
            let tr = self.transmittance(t);
            // pdf of this distance, over the channel chosen: the average of σt_c·Tr_c(t).
            let pdf = (sigma_t * tr).element_sum() / 3.0;
            FreeFlight::Scattered {
                t,
                weight: self.sigma_s * tr / pdf,
            }
        } else {
            let tr = self.transmittance(end);
            let pdf = tr.element_sum() / 3.0;
            FreeFlight::Passed {
                weight: if pdf > 0.0 { tr / pdf } else { Vec3::ZERO },
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Stream};

    #[test]
    fn a_slab_lets_through_exp_of_minus_sigma_t_d() {
        let m = Homogeneous {
            sigma_a: Vec3::new(0.1, 0.5, 2.0),
            sigma_s: Vec3::new(0.4, 0.5, 1.0),
        };
        let t = m.transmittance(1.5);
        for (got, s) in t.to_array().into_iter().zip([0.5f32, 1.0, 3.0]) {
            assert!((got - (-s * 1.5f32).exp()).abs() < 1e-6);
        }
        assert_eq!(m.transmittance(0.0), Vec3::ONE);
    }

    #[test]
    fn free_flights_are_exponential_and_their_weights_unbiased_in_every_channel() {
        // Over many flights through a slab of depth d: the mean Passed weight is Tr(d) and the
        // mean Scattered weight, per channel, is ∫ σs Tr(t) dt = σs/σt (1 − Tr(d)).
        let m = Homogeneous {
            sigma_a: Vec3::new(0.2, 0.1, 0.0),
            sigma_s: Vec3::new(0.3, 1.4, 2.0),
        };
        let d = 1.2;
        let n = 400_000;
        let mut rng = Rng::for_index(5, Stream::Pixels, 0);
        let (mut passed, mut scattered) = (Vec3::ZERO, Vec3::ZERO);
        for _ in 0..n {
            match m.free_flight(d, rng.next_f32(), rng.next_f32()) {
                FreeFlight::Passed { weight } => passed += weight,
                FreeFlight::Scattered { t, weight } => {
                    assert!(t >= 0.0 && t < d);
                    scattered += weight;
                }
            }
        }
        let (passed, scattered) = (passed / n as f32, scattered / n as f32);
        let tr = m.transmittance(d);
        let want = m.sigma_s / m.sigma_t() * (Vec3::ONE - tr);
        for c in 0..3 {
            assert!(
                (passed[c] / tr[c] - 1.0).abs() < 0.01,
                "{passed} against {tr}"
            );
            assert!(
                (scattered[c] / want[c] - 1.0).abs() < 0.01,
                "{scattered} against {want}"
            );
        }
        // One channel alone: distances follow the exponential (mean 1/σt with no end).
        let grey = Homogeneous {
            sigma_a: Vec3::splat(0.5),
            sigma_s: Vec3::splat(1.5),
        };
        let mean: f64 = (0..n)
            .map(
                |_| match grey.free_flight(f32::INFINITY, rng.next_f32(), rng.next_f32()) {
                    FreeFlight::Scattered { t, .. } => t as f64,
                    FreeFlight::Passed { .. } => panic!("an infinite slab lets nothing through"),
                },
            )
            .sum::<f64>()
            / n as f64;
        assert!((mean - 0.5).abs() < 0.005, "{mean}");
    }
}
