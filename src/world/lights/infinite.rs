//! Lights at infinity: a distant light (parallel light of irradiance E travelling along one
//! direction) and a constant environment (radiance L from every direction). Owns where their
//! photons start and what they carry, and the light they send to a point; must not trace rays.
//!
//! Photons start on a disc across their direction, of the radius R of the scene's bounding
//! sphere, just outside it on the side the light comes from, so every ray that can meet the
//! scene starts on the disc. A distant light sends E·πR² through the disc, so a photon from a
//! uniform point of it carries Φ = E·πR². The environment sends L·πR² per steradian through
//! the disc across each direction, Φ = L·4π·πR² in all; a photon (a uniform direction, then a
//! uniform point of its disc) carries that much. Aimed at specular targets, a photon starts
//! instead on the targets' own discs (their bounding spheres seen along its direction): a
//! disc picked by area, a uniform point of it; it stands for the area of all the discs over
//! the number holding its point (the same counting as [`crate::world::aim::UnionOfCones`]'s),
//! and the rays through the rest of the scene's disc, which cannot meet a target, are never
//! drawn.

use super::{Emission, IncidentSample};
use crate::sampling::{Rng, basis, cosine_hemisphere, uniform_cone, uniform_disc, uniform_sphere};
use crate::world::BoundingSphere;
use glam::Vec3;
use std::f32::consts::PI;

/// How far out of the scene's bounding sphere, in its radii, photons start.
const START_DISTANCE: f32 = 1.01;

/// The discs photons of a light at infinity start on, for any direction.
#[derive(Clone, Debug)]
pub(super) struct StartDiscs {
    scene: BoundingSphere,
    /// Where to aim caustic photons (empty: nowhere in particular).
    targets: Vec<BoundingSphere>,
    /// The targets' disc areas summed up to and including each.
    cumulative: Vec<f32>,
}

impl StartDiscs {
    pub(super) fn new(scene: BoundingSphere, aim: &[BoundingSphere]) -> Self {
        let mut sum = 0.0;
        let cumulative = aim
            .iter()
            .map(|t| {
                sum += PI * t.radius * t.radius;
                sum
            })
            .collect();
        Self {
            scene,
            targets: aim.to_vec(),
            cumulative,
        }
    }

    /// The area the scene's disc has.
    fn scene_area(&self) -> f32 {
        PI * self.scene.radius * self.scene.radius
    }

    /// A photon's start travelling along unit `direction` (with `tangents` its [`basis`]), and
    /// the area it stands for.
    #[inline]
    pub(super) fn start(
        &self,
        direction: Vec3,
        tangents: (Vec3, Vec3),
        rng: &mut Rng,
    ) -> (Vec3, f32) {
        let (t, b) = tangents;
        let center = self.scene.center;
        let back = direction * (START_DISTANCE * self.scene.radius);
        let Some(&total) = self.cumulative.last() else {
            let (x, y) = uniform_disc(rng.next_2d());
            let point = center + self.scene.radius * (x * t + y * b);
            return (point - back, self.scene_area());
        };
        // The targets' centres projected onto the plane through the scene's centre.
        let projected = |target: &BoundingSphere| {
            target.center - direction * (target.center - center).dot(direction)
        };
        let pick = rng.next_f32() * total;
        let k = (self.cumulative.iter())
            .position(|&c| pick < c)
            .unwrap_or(self.targets.len() - 1);
        let (x, y) = uniform_disc(rng.next_2d());
        let point = projected(&self.targets[k]) + self.targets[k].radius * (x * t + y * b);
        // The disc it was drawn from counts whatever rounding says of it.
        let holding = 1
            + (self.targets.iter().enumerate())
                .filter(|&(j, target)| {
                    j != k
                        && point.distance_squared(projected(target))
                            <= target.radius * target.radius
                })
                .count();
        (point - back, total / holding as f32)
    }
}

/// A distant light: parallel light along `direction`.
#[derive(Clone, Debug)]
pub(super) struct Distant {
    direction: Vec3,
    irradiance: Vec3,
    scene: BoundingSphere,
}

impl Distant {
    pub(super) fn new(direction: Vec3, irradiance: Vec3, scene: BoundingSphere) -> Self {
        Self {
            direction: direction.normalize_or(Vec3::NEG_Y),
            irradiance,
            scene,
        }
    }

    /// E·πR²: the flux through the scene's disc.
    pub(super) fn power(&self) -> Vec3 {
        self.irradiance * (PI * self.scene.radius * self.scene.radius)
    }

    /// The unit direction towards the light.
    pub(super) fn towards(&self) -> Vec3 {
        -self.direction
    }

    /// Light from the one direction it comes from, unoccluded to infinity.
    pub(super) fn incident(&self) -> IncidentSample {
        IncidentSample {
            direction: -self.direction,
            distance: f32::INFINITY,
            irradiance: self.irradiance,
            pdf: f32::INFINITY,
        }
    }
}

/// A distant light's photons.
#[derive(Clone, Debug)]
pub(super) struct DistantEmitter {
    light: Distant,
    tangents: (Vec3, Vec3),
    discs: StartDiscs,
}

impl DistantEmitter {
    pub(super) fn new(light: &Distant, aim: &[BoundingSphere]) -> Self {
        Self {
            tangents: basis(light.direction),
            discs: StartDiscs::new(light.scene, aim),
            light: light.clone(),
        }
    }

    #[inline(always)]
    pub(super) fn emit(&self, rng: &mut Rng) -> Emission {
        let direction = self.light.direction;
        let (origin, area) = self.discs.start(direction, self.tangents, rng);
        Emission {
            origin,
            direction,
            flux: self.light.irradiance * area,
        }
    }
}

/// A constant environment.
#[derive(Clone, Debug)]
pub(super) struct Environment {
    radiance: Vec3,
    scene: BoundingSphere,
}

impl Environment {
    pub(super) fn new(radiance: Vec3, scene: BoundingSphere) -> Self {
        Self { radiance, scene }
    }

    pub(super) fn radiance(&self) -> Vec3 {
        self.radiance
    }

    /// L·4π·πR²: the flux through the scene's disc, over every direction.
    pub(super) fn power(&self) -> Vec3 {
        self.radiance * (4.0 * PI * PI * self.scene.radius * self.scene.radius)
    }

    /// Light arriving at a point with unit normal `n`: a cosine-weighted direction, which
    /// brings L π (once multiplied by the cosine, as every sample is).
    pub(super) fn incident(&self, n: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        let direction = cosine_hemisphere(n, u);
        let cos = direction.dot(n);
        (cos > 0.0).then(|| IncidentSample {
            direction,
            distance: f32::INFINITY,
            irradiance: self.radiance * (PI / cos),
            pdf: cos / PI,
        })
    }

    /// [`Environment::incident`] for a receiver whose shading normal is far from `n`: half
    /// the directions cosine-weighted, half uniform over the hemisphere, so a grazing one
    /// (which a shading normal lying in the face weighs fully) never brings more than 4πL.
    pub(super) fn incident_wide(&self, n: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        let direction = if u.0 < 0.5 {
            cosine_hemisphere(n, (2.0 * u.0, u.1))
        } else {
            uniform_cone(n, 0.0, (2.0 * u.0 - 1.0, u.1))
        };
        let cos = direction.dot(n);
        let pdf = 0.5 * cos / PI + 0.25 / PI;
        (cos > 0.0).then(|| IncidentSample {
            direction,
            distance: f32::INFINITY,
            irradiance: self.radiance / pdf,
            pdf,
        })
    }
}

/// An environment's photons: a uniform direction, then a start on its disc.
#[derive(Clone, Debug)]
pub(super) struct EnvironmentEmitter {
    radiance: Vec3,
    discs: StartDiscs,
}

impl EnvironmentEmitter {
    pub(super) fn new(light: &Environment, aim: &[BoundingSphere]) -> Self {
        Self {
            radiance: light.radiance,
            discs: StartDiscs::new(light.scene, aim),
        }
    }

    #[inline(always)]
    pub(super) fn emit(&self, rng: &mut Rng) -> Emission {
        let direction = uniform_sphere(rng.next_2d());
        let (origin, area) = self.discs.start(direction, basis(direction), rng);
        Emission {
            origin,
            direction,
            flux: self.radiance * (4.0 * PI * area),
        }
    }
}
