//! Point and spot lights: light from one point, the same in every direction or shaped by a
//! spot's cone and falloff. Owns the spot's intensity profile, the direction sampling that
//! follows it, and the aimed spot's choice between that and the cones towards the targets;
//! must not trace rays.
//!
//! A spot's photons follow its intensity exactly (the cap inside the falloff start uniformly,
//! the band by inverting the falloff's integral), so each carries the whole power Φ, and a map
//! of N photons holds Φ whatever the falloff. Aimed at specular targets, a photon draws from
//! whichever is narrower: the spot's own cone, or the union of the cones towards the targets
//! that meet it (then it carries I(ω) / pdf(ω), zero outside the spot's cone, and is not traced).

use super::{Emission, IncidentSample};
use crate::sampling::{Rng, basis, cone_solid_angle, sin_cos_turns, uniform_sphere};
use crate::scene::SpotFalloff;
use crate::world::BoundingSphere;
use crate::world::aim::{UnionOfCones, cone_towards};
use crate::world::aim_guide::AimedCones;
use glam::Vec3;
use std::f32::consts::PI;

/// Light arriving at `x` from an isotropic point light.
pub(super) fn point_incident(position: Vec3, power: Vec3, x: Vec3) -> Option<IncidentSample> {
    let to = position - x;
    let d2 = to.length_squared();
    (d2 > 0.0).then(|| {
        let distance = d2.sqrt();
        IncidentSample {
            direction: to / distance,
            distance,
            irradiance: power / (4.0 * PI * d2),
            pdf: f32::INFINITY,
        }
    })
}

/// A point light's photons: from the cones towards the targets when there are some and the
/// light is outside them all (flux Φ/4π per steradian), else from the whole sphere.
#[derive(Clone, Debug)]
pub(super) struct PointEmitter {
    position: Vec3,
    cones: Option<AimedCones>,
    /// Flux of a photon standing for one steradian when aimed, for the whole sphere when not.
    flux: Vec3,
}

impl PointEmitter {
    pub(super) fn cones_mut(&mut self) -> Option<&mut AimedCones> {
        self.cones.as_mut()
    }

    pub(super) fn cones(&self) -> Option<&AimedCones> {
        self.cones.as_ref()
    }

    pub(super) fn new(position: Vec3, power: Vec3, aim: &[BoundingSphere]) -> Self {
        let cones = UnionOfCones::towards(aim, position).map(|u| AimedCones::new(u.prepared()));
        Self {
            position,
            flux: if cones.is_some() {
                power / (4.0 * PI)
            } else {
                power
            },
            cones,
        }
    }

    #[inline(always)]
    pub(super) fn emit(&self, rng: &mut Rng) -> Emission {
        match &self.cones {
            Some(cones) => {
                let (direction, weight) = cones.sample(rng);
                Emission {
                    origin: self.position,
                    direction,
                    flux: self.flux * weight,
                }
            }
            None => Emission {
                origin: self.position,
                direction: uniform_sphere(rng.next_2d()),
                flux: self.flux,
            },
        }
    }
}

/// A spot light with its profile worked out.
#[derive(Clone, Debug)]
pub(super) struct Spot {
    position: Vec3,
    axis: Vec3,
    /// The tangents of `axis` ([`basis`]).
    tangents: (Vec3, Vec3),
    cos_cone: f32,
    cos_start: f32,
    falloff: SpotFalloff,
    /// W/sr on the axis: Φ / ∫ factor dω.
    intensity: Vec3,
    power: Vec3,
    /// The probability that a photon leaves inside the falloff start (the full-intensity cap):
    /// the cap's share of ∫ factor dω.
    cap_probability: f32,
}

impl Spot {
    pub(super) fn position(&self) -> Vec3 {
        self.position
    }

    /// The cone it lights: apex, unit axis, cosine of the half-angle past which it is dark.
    pub(super) fn cone(&self) -> (Vec3, Vec3, f32) {
        (self.position, self.axis, self.cos_cone)
    }

    pub(super) fn new(
        position: Vec3,
        direction: Vec3,
        cone_angle_degrees: f32,
        falloff_start_degrees: f32,
        falloff: SpotFalloff,
        power: Vec3,
    ) -> Self {
        let cos_cone = cone_angle_degrees.to_radians().cos();
        // The start may round to just above the cone; the band then has no width.
        let cos_start = falloff_start_degrees.to_radians().cos().max(cos_cone);
        let cap = 1.0 - cos_start;
        let band = (cos_start - cos_cone) * falloff.band_mean();
        let axis = direction.normalize_or(Vec3::NEG_Y);
        Self {
            position,
            axis,
            tangents: basis(axis),
            cos_cone,
            cos_start,
            falloff,
            intensity: power / (2.0 * PI * (cap + band)),
            power,
            cap_probability: cap / (cap + band),
        }
    }

    pub(super) fn power(&self) -> Vec3 {
        self.power
    }

    /// Its bounds for the light tree: the power it would have at full intensity every way
    /// (the cone, not the power, says where it is dark), the axis, the falloff start as
    /// the cone of full light and the rest of the cone as its spread.
    pub(super) fn bounds(&self) -> super::tree::LightBounds {
        let theta_start = self.cos_start.clamp(-1.0, 1.0).acos();
        let theta_cone = self.cos_cone.clamp(-1.0, 1.0).acos();
        super::tree::LightBounds {
            lo: self.position,
            hi: self.position,
            phi: 4.0 * PI * super::weight(self.intensity),
            axis: self.axis,
            cos_normals: self.cos_start,
            cos_emission: (theta_cone - theta_start).max(0.0).cos(),
            two_sided: false,
        }
    }

    /// Intensity (W/sr) along unit `direction` leaving the light.
    #[inline]
    fn intensity(&self, direction: Vec3) -> Vec3 {
        self.intensity
            * self
                .falloff
                .factor(direction.dot(self.axis), self.cos_cone, self.cos_start)
    }

    /// A direction drawn with density ∝ the intensity (so a photon along it carries Φ).
    #[inline]
    fn sample_direction(&self, (u, v): (f32, f32)) -> Vec3 {
        let cos_theta = if u < self.cap_probability {
            1.0 - (u / self.cap_probability) * (1.0 - self.cos_start)
        } else {
            let w = (u - self.cap_probability) / (1.0 - self.cap_probability);
            let t = band_position(self.falloff, w);
            self.cos_cone + t * (self.cos_start - self.cos_cone)
        };
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let (sin, cos) = sin_cos_turns(v);
        let (t, b) = self.tangents;
        t * (sin_theta * cos) + b * (sin_theta * sin) + self.axis * cos_theta
    }

    /// Light arriving at `x`: I(ω) / d² towards the light.
    pub(super) fn incident(&self, x: Vec3) -> Option<IncidentSample> {
        let to = self.position - x;
        let d2 = to.length_squared();
        if d2 == 0.0 {
            return None;
        }
        let distance = d2.sqrt();
        let direction = to / distance;
        let intensity = self.intensity(-direction);
        (intensity.max_element() > 0.0).then(|| IncidentSample {
            direction,
            distance,
            irradiance: intensity / d2,
            pdf: f32::INFINITY,
        })
    }
}

/// Where in the falloff band, as t in [0, 1] from the cone (factor 0) to the falloff start
/// (factor 1), the `w`-quantile of the band's share of the intensity lies: the inverse of
/// ∫₀ᵗ factor / ∫₀¹ factor, which is t⁵ for the quartic and 2t³ − t⁴ for smoothstep (that
/// one by bisection, to f32 precision: it is monotone on [0, 1]).
#[inline]
fn band_position(falloff: SpotFalloff, w: f32) -> f32 {
    match falloff {
        SpotFalloff::Quartic => w.powf(0.2),
        SpotFalloff::Smoothstep => {
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for _ in 0..24 {
                let t = 0.5 * (lo + hi);
                if t * t * t * (2.0 - t) < w {
                    lo = t;
                } else {
                    hi = t;
                }
            }
            0.5 * (lo + hi)
        }
    }
}

/// A spot's photons, aimed or not.
#[derive(Clone, Debug)]
pub(super) struct SpotEmitter {
    spot: Spot,
    /// The cones towards the targets that meet the spot's cone, when they are narrower than it.
    toward_targets: Option<AimedCones>,
}

impl SpotEmitter {
    pub(super) fn cones_mut(&mut self) -> Option<&mut AimedCones> {
        self.toward_targets.as_mut()
    }

    pub(super) fn cones(&self) -> Option<&AimedCones> {
        self.toward_targets.as_ref()
    }

    pub(super) fn new(spot: &Spot, aim: &[BoundingSphere]) -> Self {
        let cone_half_angle = spot.cos_cone.clamp(-1.0, 1.0).acos();
        let meets_the_spot = |&(axis, cos_max): &(Vec3, f32)| {
            let apart = axis.dot(spot.axis).clamp(-1.0, 1.0).acos();
            apart <= cone_half_angle + cos_max.clamp(-1.0, 1.0).acos() + 1e-3
        };
        // From inside a target every direction may reach it: no cones then.
        let cones: Option<Vec<(Vec3, f32)>> = aim
            .iter()
            .map(|target| cone_towards(target, spot.position))
            .collect();
        let toward_targets = cones
            .map(|cones| cones.into_iter().filter(meets_the_spot))
            .and_then(UnionOfCones::new)
            .filter(|union| union.solid_angle() < cone_solid_angle(spot.cos_cone))
            .map(|union| AimedCones::new(union.prepared()));
        Self {
            spot: spot.clone(),
            toward_targets,
        }
    }

    #[inline(always)]
    pub(super) fn emit(&self, rng: &mut Rng) -> Emission {
        let spot = &self.spot;
        match &self.toward_targets {
            Some(cones) => {
                let (direction, weight) = cones.sample(rng);
                Emission {
                    origin: spot.position,
                    direction,
                    flux: spot.intensity(direction) * weight,
                }
            }
            None => Emission {
                origin: spot.position,
                direction: spot.sample_direction(rng.next_2d()),
                flux: spot.power,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Stream;

    fn spot(falloff: SpotFalloff, cone: f32, start: f32) -> Spot {
        Spot::new(
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(0.3, 0.0, -1.0).normalize(),
            cone,
            start,
            falloff,
            Vec3::new(6.0, 3.0, 1.0),
        )
    }

    /// The closed forms of ∫ factor dω (`SpotFalloff::solid_angle`, and so the intensity) agree
    /// with the factor integrated numerically over the sphere (midpoint rule in cos θ).
    #[test]
    fn the_falloff_integrals_match_the_factor_integrated() {
        for falloff in [SpotFalloff::Smoothstep, SpotFalloff::Quartic] {
            for (cone, start) in [(30.0f32, 25.0f32), (60.0, 10.0), (90.0, 0.0), (45.0, 45.0)] {
                let (cos_cone, cos_start) = (cone.to_radians().cos(), start.to_radians().cos());
                let n = 2_000_000;
                let numeric: f64 = (0..n)
                    .map(|i| {
                        let mu = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                        falloff.factor(mu as f32, cos_cone, cos_start) as f64
                    })
                    .sum::<f64>()
                    * 2.0
                    / n as f64
                    * 2.0
                    * std::f64::consts::PI;
                let closed = falloff.solid_angle(cone, start) as f64;
                let (a, b) = (cos_cone as f64, cos_start as f64);
                let by_hand = 2.0
                    * std::f64::consts::PI
                    * match falloff {
                        SpotFalloff::Smoothstep => 1.0 - (a + b) / 2.0,
                        SpotFalloff::Quartic => (1.0 - b) + (b - a) / 5.0,
                    };
                assert!(
                    (numeric - closed).abs() < 1e-4 * closed && (by_hand - closed).abs() < 1e-5,
                    "{falloff:?} {cone}/{start}: numeric {numeric}, closed {closed}, {by_hand}"
                );
            }
        }
    }

    /// Unaimed photons carry the whole power each, and their directions follow the intensity:
    /// the share of photons in each band of θ matches the share of ∫ I dω there.
    #[test]
    fn spot_photons_follow_the_intensity_and_carry_the_power() {
        for falloff in [SpotFalloff::Smoothstep, SpotFalloff::Quartic] {
            let spot = spot(falloff, 40.0, 20.0);
            let emitter = SpotEmitter::new(&spot, &[]);
            let bins = 20;
            let mut counts = vec![0u32; bins];
            let n = 400_000;
            let mut rng = Rng::for_index(3, Stream::GlobalPhotons, 0);
            for _ in 0..n {
                let e = emitter.emit(&mut rng);
                assert_eq!(e.flux, spot.power);
                assert!((e.direction.length() - 1.0).abs() < 1e-5);
                let cos = e.direction.dot(spot.axis);
                assert!(cos >= spot.cos_cone - 1e-6, "outside the cone");
                let bin = ((1.0 - cos) / (1.0 - spot.cos_cone) * bins as f32) as usize;
                counts[bin.min(bins - 1)] += 1;
            }
            let total = (1.0 - spot.cos_cone) as f64;
            for (k, &count) in counts.iter().enumerate() {
                // The factor integrated over the bin, in cos θ, relative to the whole.
                let steps = 1000;
                let share: f64 = (0..steps)
                    .map(|j| {
                        let mu = 1.0
                            - total * (k as f64 + (j as f64 + 0.5) / steps as f64) / bins as f64;
                        falloff.factor(mu as f32, spot.cos_cone, spot.cos_start) as f64
                    })
                    .sum::<f64>()
                    * total
                    / (bins * steps) as f64
                    / (falloff.solid_angle(40.0, 20.0) as f64 / (2.0 * std::f64::consts::PI));
                let got = count as f64 / n as f64;
                let sigma = (share / n as f64).sqrt();
                assert!(
                    (got - share).abs() < 5.0 * sigma + 1e-4,
                    "{falloff:?} bin {k}: {got} vs {share}"
                );
            }
        }
    }

    #[test]
    fn band_position_inverts_the_band_integral() {
        for w in [0.0f32, 0.01, 0.3, 0.5, 0.9, 0.999] {
            let t = band_position(SpotFalloff::Smoothstep, w);
            assert!((t * t * t * (2.0 - t) - w).abs() < 1e-5, "{w}: {t}");
            let t = band_position(SpotFalloff::Quartic, w);
            assert!((t.powi(5) - w).abs() < 1e-5, "{w}: {t}");
        }
    }

    /// Aimed at a small target inside a wide spot the photons come from the target's cone;
    /// at one outside the spot, from the spot itself (no cone meets it).
    #[test]
    fn an_aimed_spot_draws_from_the_narrower_set() {
        let spot = spot(SpotFalloff::Smoothstep, 60.0, 50.0);
        let inside = [BoundingSphere {
            center: Vec3::new(0.3, 0.0, 1.0),
            radius: 0.1,
        }];
        assert!(SpotEmitter::new(&spot, &inside).toward_targets.is_some());
        let behind = [BoundingSphere {
            center: Vec3::new(0.0, 0.0, 4.0),
            radius: 0.5,
        }];
        assert!(SpotEmitter::new(&spot, &behind).toward_targets.is_none());
        let enclosing = [BoundingSphere {
            center: Vec3::new(0.0, 0.0, 2.1),
            radius: 0.5,
        }];
        assert!(SpotEmitter::new(&spot, &enclosing).toward_targets.is_none());
    }
}
