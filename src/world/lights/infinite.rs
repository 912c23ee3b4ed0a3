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
    /// When set, each target's share of the photons (summing to 1), `cumulative` summing
    /// them instead of the areas: a start may then stand for less area on a target that
    /// draws more than its area's share.
    shares: Vec<f32>,
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
            shares: Vec::new(),
        }
    }

    /// Discs over the whole scene that send `share` of their photons through each of
    /// `extra` as well (a medium far smaller than the scene): still every start the scene's
    /// disc holds, each standing for the area its density gives.
    pub(super) fn sharing(&self, extra: &[(BoundingSphere, f32)]) -> Self {
        let rest = 1.0 - extra.iter().map(|e| e.1).sum::<f32>();
        let mut targets = vec![self.scene];
        let mut shares = vec![rest.max(0.0)];
        for &(sphere, share) in extra {
            targets.push(sphere);
            shares.push(share);
        }
        let mut sum = 0.0;
        let cumulative = (shares.iter())
            .map(|s| {
                sum += s;
                sum
            })
            .collect();
        Self {
            scene: self.scene,
            targets,
            cumulative,
            shares,
        }
    }

    /// [`StartDiscs::start`] over shared discs: the disc by its share, and the area one over
    /// the density every disc holding the point gives it.
    fn start_shared(&self, direction: Vec3, tangents: (Vec3, Vec3), rng: &mut Rng) -> (Vec3, f32) {
        let (k, point) = self.picked(direction, tangents, rng);
        let density: f32 = (self.targets.iter().zip(&self.shares).enumerate())
            .filter(|&(j, (target, _))| j == k || self.holds(target, direction, point))
            .map(|(_, (target, share))| share / (PI * target.radius * target.radius))
            .sum();
        let total = self.cumulative.last().copied().unwrap_or(1.0);
        (point - self.back(direction), total / density)
    }

    /// How far behind the scene's centre, along `direction`, its photons start.
    fn back(&self, direction: Vec3) -> Vec3 {
        direction * (START_DISTANCE * self.scene.radius)
    }

    /// `target`'s centre projected along `direction` onto the plane through the scene's
    /// centre.
    fn projected(&self, target: &BoundingSphere, direction: Vec3) -> Vec3 {
        target.center - direction * (target.center - self.scene.center).dot(direction)
    }

    /// Whether `target`'s disc, seen along `direction`, holds `point` of that plane.
    fn holds(&self, target: &BoundingSphere, direction: Vec3, point: Vec3) -> bool {
        point.distance_squared(self.projected(target, direction)) <= target.radius * target.radius
    }

    /// A target picked by `cumulative` and a uniform point of its disc (on the plane through
    /// the scene's centre).
    fn picked(&self, direction: Vec3, (t, b): (Vec3, Vec3), rng: &mut Rng) -> (usize, Vec3) {
        let total = self.cumulative.last().copied().unwrap_or(1.0);
        let pick = rng.next_f32() * total;
        let k = (self.cumulative.iter())
            .position(|&c| pick < c)
            .unwrap_or(self.targets.len() - 1);
        let (x, y) = uniform_disc(rng.next_2d());
        let target = &self.targets[k];
        (
            k,
            self.projected(target, direction) + target.radius * (x * t + y * b),
        )
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
        if !self.shares.is_empty() {
            return self.start_shared(direction, tangents, rng);
        }
        let Some(&total) = self.cumulative.last() else {
            let (t, b) = tangents;
            let (x, y) = uniform_disc(rng.next_2d());
            let point = self.scene.center + self.scene.radius * (x * t + y * b);
            return (point - self.back(direction), self.scene_area());
        };
        let (k, point) = self.picked(direction, tangents, rng);
        // The disc it was drawn from counts whatever rounding says of it.
        let holding = 1
            + (self.targets.iter().enumerate())
                .filter(|&(j, target)| j != k && self.holds(target, direction, point))
                .count();
        (point - self.back(direction), total / holding as f32)
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

    pub(super) fn share_discs(&mut self, extra: &[(BoundingSphere, f32)]) {
        self.discs = self.discs.sharing(extra);
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

    /// Light arriving at a point in a medium, from every direction alike: a uniform
    /// direction over the sphere, bringing 4πL.
    pub(super) fn incident_sphere(&self, u: (f32, f32)) -> IncidentSample {
        IncidentSample {
            direction: uniform_sphere(u),
            distance: f32::INFINITY,
            irradiance: self.radiance * (4.0 * PI),
            pdf: 0.25 / PI,
        }
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

    pub(super) fn share_discs(&mut self, extra: &[(BoundingSphere, f32)]) {
        self.discs = self.discs.sharing(extra);
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
