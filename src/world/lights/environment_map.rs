//! An image environment as light transport sees it: the radiance an escaping ray meets, light
//! samples for a surface point, and photons. Owns the map's sampling density; must not trace
//! rays (the texels' geometry is [`crate::scene::EnvironmentMap`]'s).
//!
//! Directions are importance-sampled by a piecewise-constant density over the texels: a texel
//! with probability in proportion to its mean channel times its solid angle, then a direction
//! uniform by solid angle within it, so the density in solid angle is the texel's probability
//! over its solid angle, exactly. A light sample for a surface mixes that density half and half
//! with a cosine-weighted one (one-sample multiple importance sampling by the balance
//! heuristic): a bright sun is found by the map's half, a dim even sky by the cosine half.
//! Photons start on the scene's disc across their direction as the constant environment's do
//! ([`super::infinite`]) and carry L·A/p: their flux sums to ∫L dω · πR².

use super::infinite::StartDiscs;
use super::{Emission, IncidentSample};
use crate::sampling::{Rng, basis, cosine_hemisphere};
use crate::scene::EnvironmentMap;
use crate::world::BoundingSphere;
use glam::Vec3;
use std::f32::consts::PI;
use std::sync::Arc;

/// An environment map with its sampling table, shared by every emitter built from it.
#[derive(Clone, Debug)]
pub(super) struct EnvironmentMapLight(Arc<Prepared>);

#[derive(Debug)]
struct Prepared {
    map: EnvironmentMap,
    scene: BoundingSphere,
    /// Texel probabilities summed up to and including each; the last is 1.
    cumulative: Vec<f64>,
    integral: Vec3,
}

impl EnvironmentMapLight {
    pub(super) fn new(map: &EnvironmentMap, scene: BoundingSphere) -> Self {
        let weights: Vec<f64> = (map.texels.iter().enumerate())
            .map(|(i, t)| f64::from(t.element_sum() / 3.0) * f64::from(map.texel_solid_angle(i)))
            .collect();
        let total: f64 = weights.iter().sum();
        let mut sum = 0.0;
        let mut cumulative: Vec<f64> = (weights.iter())
            .map(|w| {
                sum += w / total;
                sum
            })
            .collect();
        if let Some(last) = cumulative.last_mut() {
            *last = 1.0;
        }
        Self(Arc::new(Prepared {
            integral: map.integral(),
            map: map.clone(),
            scene,
            cumulative,
        }))
    }

    /// Radiance arriving from the unit direction `towards`.
    #[inline]
    pub(super) fn radiance(&self, towards: Vec3) -> Vec3 {
        self.0.map.radiance(towards)
    }

    /// ∫L dω · πR²: the flux through the scene's disc, over every direction.
    pub(super) fn power(&self) -> Vec3 {
        let r = self.0.scene.radius;
        self.0.integral * (PI * r * r)
    }

    fn probability(&self, texel: usize) -> f64 {
        let c = &self.0.cumulative;
        c[texel] - if texel == 0 { 0.0 } else { c[texel - 1] }
    }

    /// The sampling density of direction `towards`, per steradian.
    pub(super) fn pdf(&self, towards: Vec3) -> f32 {
        let texel = self.0.map.texel_towards(towards);
        (self.probability(texel) / f64::from(self.0.map.texel_solid_angle(texel))) as f32
    }

    /// A direction drawn by the map's density, its density and radiance.
    #[inline]
    pub(super) fn sample(&self, u: (f32, f32)) -> (Vec3, f32, Vec3) {
        let c = &self.0.cumulative;
        let pick = f64::from(u.0);
        let texel = c.partition_point(|&x| x <= pick).min(c.len() - 1);
        let below = if texel == 0 { 0.0 } else { c[texel - 1] };
        let p = c[texel] - below;
        // The pick's place inside its texel's share is a fresh uniform number.
        let within = (((pick - below) / p) as f32).clamp(0.0, 1.0 - f32::EPSILON);
        let map = &self.0.map;
        let towards = map.direction_in(texel, (within, u.1));
        let pdf = (p / f64::from(map.texel_solid_angle(texel))) as f32;
        (towards, pdf, map.texels[texel])
    }

    /// Light arriving at a point in a medium: half the directions by the map, half uniform
    /// over the sphere (so a dim texel's direction never weighs without bound).
    pub(super) fn incident_sphere(&self, u: (f32, f32)) -> Option<IncidentSample> {
        let towards = if u.0 < 0.5 {
            crate::sampling::uniform_sphere((2.0 * u.0, u.1))
        } else {
            self.sample((2.0 * u.0 - 1.0, u.1)).0
        };
        self.half_drawn_by_map(towards, 0.25 / PI)
    }

    /// The sample towards `towards` drawn half the time by the map and half by another
    /// density, `other` there.
    fn half_drawn_by_map(&self, towards: Vec3, other: f32) -> Option<IncidentSample> {
        let pdf = 0.5 * other + 0.5 * self.pdf(towards);
        let radiance = self.radiance(towards);
        (pdf > 0.0 && radiance != Vec3::ZERO).then(|| IncidentSample {
            direction: towards,
            distance: f32::INFINITY,
            irradiance: radiance / pdf,
            pdf,
        })
    }

    /// Light arriving at a point with unit normal `n`, by the half-map, half-cosine mixture.
    pub(super) fn incident(&self, n: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        let towards = if u.0 < 0.5 {
            cosine_hemisphere(n, (2.0 * u.0, u.1))
        } else {
            self.sample((2.0 * u.0 - 1.0, u.1)).0
        };
        let cos = towards.dot(n);
        if cos <= 0.0 {
            return None;
        }
        self.half_drawn_by_map(towards, cos / PI)
    }
}

/// An environment map's photons: a direction by the map's density, then a start on its disc.
#[derive(Clone, Debug)]
pub(super) struct EnvironmentMapEmitter {
    light: EnvironmentMapLight,
    discs: StartDiscs,
}

impl EnvironmentMapEmitter {
    pub(super) fn new(light: &EnvironmentMapLight, aim: &[BoundingSphere]) -> Self {
        Self {
            discs: StartDiscs::new(light.0.scene, aim),
            light: light.clone(),
        }
    }

    pub(super) fn share_discs(&mut self, extra: &[(BoundingSphere, f32)]) {
        self.discs = self.discs.sharing(extra);
    }

    #[inline(always)]
    pub(super) fn emit(&self, rng: &mut Rng) -> Emission {
        let (towards, pdf, radiance) = self.light.sample(rng.next_2d());
        let direction = -towards;
        let (origin, area) = self.discs.start(direction, basis(direction), rng);
        Emission {
            origin,
            direction,
            flux: radiance * (area / pdf),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Stream, uniform_sphere};
    use crate::scene::SphereMapping;
    use glam::Mat3;

    const SCENE: BoundingSphere = BoundingSphere {
        center: Vec3::ZERO,
        radius: 2.0,
    };

    fn map(
        width: u32,
        height: u32,
        mapping: SphereMapping,
        lit: impl Fn(u32) -> Vec3,
    ) -> EnvironmentMap {
        EnvironmentMap {
            width,
            height,
            texels: (0..width * height).map(lit).collect::<Vec<_>>().into(),
            mapping,
            light_to_world: Mat3::from_rotation_y(0.7)
                * Mat3::from_diagonal(Vec3::new(1.0, -1.0, 1.0)),
        }
    }

    /// Stratified directions over the sphere, for brute-force integrals.
    fn sphere_grid(n: u32) -> impl Iterator<Item = Vec3> {
        (0..n * n).map(move |k| {
            uniform_sphere((
                ((k % n) as f32 + 0.5) / n as f32,
                ((k / n) as f32 + 0.5) / n as f32,
            ))
        })
    }

    #[test]
    fn photon_power_is_the_maps_integral_and_the_density_integrates_to_one() {
        for mapping in [SphereMapping::LatLong, SphereMapping::EqualAreaOctahedral] {
            let m = map(32, 16 + 16 * (mapping as u32), mapping, |i| {
                Vec3::new(
                    1.0 + (i % 7) as f32,
                    0.5,
                    if i % 11 == 0 { 40.0 } else { 0.2 },
                )
            });
            let light = EnvironmentMapLight::new(&m, SCENE);
            // ∫L dω and ∫p dω by brute force over directions, not through the texels' areas.
            let n = 2000;
            let (mut integral, mut total_pdf) = (glam::DVec3::ZERO, 0.0f64);
            for d in sphere_grid(n) {
                integral += light.radiance(d).as_dvec3();
                total_pdf += f64::from(light.pdf(d));
            }
            let cell = 4.0 * std::f64::consts::PI / f64::from(n * n);
            let integral = (integral * cell).as_vec3();
            let total_pdf = total_pdf * cell;
            assert!(
                (total_pdf - 1.0).abs() < 2e-3,
                "{mapping:?}: ∫p = {total_pdf}"
            );
            let want = integral * (PI * SCENE.radius * SCENE.radius);
            assert!(
                (light.power() - want).abs().max_element() < 2e-3 * want.max_element(),
                "{mapping:?}: {} vs {want}",
                light.power()
            );
            // The photons' flux averages to the power, per channel.
            let emitter = EnvironmentMapEmitter::new(&light, &[]);
            let photons = 400_000;
            let mut flux = Vec3::ZERO;
            for i in 0..photons {
                flux += emitter
                    .emit(&mut Rng::for_index(3, Stream::GlobalPhotons, i))
                    .flux;
            }
            let mean = flux / photons as f32;
            let rel = ((mean - light.power()) / light.power()).abs().max_element();
            assert!(
                rel < 0.01,
                "{mapping:?}: photons carry {mean}, the map {}",
                light.power()
            );
        }
    }

    #[test]
    fn one_lit_texel_lights_a_surface_as_a_distant_light_would() {
        let (w, h) = (256, 128);
        let lit = w * 40 + 77;
        let m = map(w, h, SphereMapping::LatLong, |i| {
            if i == lit {
                Vec3::new(500.0, 250.0, 100.0)
            } else {
                Vec3::ZERO
            }
        });
        let light = EnvironmentMapLight::new(&m, SCENE);
        let towards = m.direction_in(lit as usize, (0.5, 0.5));
        // The distant light of the same flux: E = L Ω along the texel's centre.
        let e = m.texels[lit as usize] * m.texel_solid_angle(lit as usize);
        for n in [towards, (towards + Vec3::new(0.3, 0.2, -0.1)).normalize()] {
            let samples = 200_000;
            let mut sum = Vec3::ZERO;
            for i in 0..samples {
                let u = Rng::for_index(9, Stream::Pixels, i).next_2d();
                if let Some(s) = light.incident(n, u) {
                    sum += s.irradiance * s.direction.dot(n);
                }
            }
            let got = sum / samples as f32;
            let want = e * towards.dot(n);
            let rel = ((got - want) / want).abs().max_element();
            assert!(
                rel < 0.01,
                "normal {n}: {got} against the distant light's {want}"
            );
        }
        // Every photon comes from that texel and carries the whole power.
        let emitter = EnvironmentMapEmitter::new(&light, &[]);
        for i in 0..1000 {
            let photon = emitter.emit(&mut Rng::for_index(4, Stream::GlobalPhotons, i));
            assert_eq!(m.texel_towards(-photon.direction), lit as usize);
            assert!(
                ((photon.flux - light.power()) / light.power())
                    .abs()
                    .max_element()
                    < 1e-4
            );
        }
    }
}
