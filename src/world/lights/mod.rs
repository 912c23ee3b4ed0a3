//! Lights as light transport sees them: emitting photons (optionally aimed at bounding spheres,
//! for caustic photons), sampling incident light at a surface point for direct lighting, the
//! radiance of a visible emitter, and the radiance of the sky an escaping ray sees. Owns the
//! sampling densities; must not trace rays.
//!
//! Inside: `point` holds point and spot lights, `area` the sphere, quad and mesh emitters,
//! `infinite` the distant light and the environment, whose photons start on discs outside the
//! scene's bounding sphere, `environment_map` an image environment's importance sampling. A [`LightSource`] is one scene light prepared once per world; a
//! [`LightEmitter`] is one light's photons prepared once per map (aimed or not).

mod area;
mod environment_map;
mod infinite;
mod point;
pub mod sampler;
#[cfg(test)]
mod tests;
pub mod tree;

use super::BoundingSphere;
use super::aim_guide::{AimedCones, ConeCells};
use crate::sampling::Rng;
use crate::scene::Light;
use glam::Vec3;
use std::sync::Arc;

/// One emitted photon before the caller divides by the number emitted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Emission {
    pub origin: Vec3,
    pub direction: Vec3,
    /// Flux carried when this is the only photon emitted from the light.
    pub flux: Vec3,
}

/// A sample of incident light for direct lighting at a point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IncidentSample {
    /// Unit direction towards the light.
    pub direction: Vec3,
    /// How far a shadow ray towards the light must be clear: the sampled light point, less a
    /// margin that keeps the light's own surface out of the test; infinite for lights at
    /// infinity.
    pub distance: f32,
    /// Irradiance contribution on a surface facing `direction` (already divided by the pdf),
    /// before the receiver's cosine: multiply by `max(0, n·direction)`.
    pub irradiance: Vec3,
    /// The solid-angle density the direction was drawn with; infinite for a point, spot or
    /// distant light (for weighting it against a BSDF's samples).
    pub pdf: f32,
}

/// Luminance-like weight used to split photons among lights.
pub fn weight(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722)).max(0.0)
}

/// A light's shape: where its light comes from, for the pilot rays' visibility tests.
#[derive(Clone, Debug, PartialEq)]
pub enum LightShape {
    /// A point or spot light (invisible to the eye).
    Point(Vec3),
    /// A distant light (invisible to the eye): the unit direction towards it.
    Direction(Vec3),
    Sphere(BoundingSphere),
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
    },
    /// A mesh light: a sphere round each triangle, or one round them all past
    /// [`MESH_SPHERES`] triangles, and a point of its largest triangle (none of either for a
    /// mesh without area, which emits nothing).
    Mesh {
        spheres: Vec<BoundingSphere>,
        point: Option<Vec3>,
    },
    /// The environment: light from every direction.
    Everywhere,
}

/// Triangles of a mesh light past which the light tree holds it as one entry.
pub const TREE_TRIANGLES_MAX: usize = 65_536;

/// Triangles past which a mesh light's shape is one sphere round them all.
pub const MESH_SPHERES: usize = 64;

/// A scene light with what every sample of it shares worked out once: a spot's intensity, a
/// mesh's table of triangle areas, the scene's bounding sphere for the lights at infinity.
#[derive(Clone, Debug)]
pub struct LightSource(Kind);

#[derive(Clone, Debug)]
enum Kind {
    Point {
        position: Vec3,
        power: Vec3,
    },
    Spot(point::Spot),
    Sphere {
        center: Vec3,
        radius: f32,
        power: Vec3,
    },
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        power: Vec3,
    },
    /// Shared with the emitters built from it: a big mesh's table is not copied per map.
    Mesh(Arc<area::MeshLight>),
    Distant(infinite::Distant),
    Environment(infinite::Environment),
    EnvironmentMap(environment_map::EnvironmentMapLight),
}

impl LightSource {
    /// `light` in a scene whose geometry lies within `scene`.
    pub fn new(light: &Light, scene: BoundingSphere) -> Self {
        Self(match *light {
            Light::Point { position, power } => Kind::Point { position, power },
            Light::Sphere {
                center,
                radius,
                power,
            } => Kind::Sphere {
                center,
                radius,
                power,
            },
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                power,
            } => Kind::Quad {
                corner,
                edge_u,
                edge_v,
                power,
            },
            Light::Spot {
                position,
                direction,
                cone_angle_degrees,
                falloff_start_degrees,
                falloff,
                power,
            } => Kind::Spot(point::Spot::new(
                position,
                direction,
                cone_angle_degrees,
                falloff_start_degrees,
                falloff,
                power,
            )),
            Light::Distant {
                direction,
                irradiance,
            } => Kind::Distant(infinite::Distant::new(direction, irradiance, scene)),
            Light::Environment { radiance } => {
                Kind::Environment(infinite::Environment::new(radiance, scene))
            }
            Light::EnvironmentMap(ref map) => {
                Kind::EnvironmentMap(environment_map::EnvironmentMapLight::new(map, scene))
            }
            Light::Mesh {
                ref mesh,
                power,
                two_sided,
            } => Kind::Mesh(Arc::new(area::MeshLight::new(mesh, power, two_sided))),
        })
    }

    /// Total flux in watts per channel: for the lights at infinity, what crosses the scene's
    /// bounding sphere (E·πR² for a distant light, L·4π·πR² for the environment).
    pub fn power(&self) -> Vec3 {
        match &self.0 {
            Kind::Point { power, .. } | Kind::Sphere { power, .. } | Kind::Quad { power, .. } => {
                *power
            }
            Kind::Spot(spot) => spot.power(),
            Kind::Mesh(mesh) => mesh.power(),
            Kind::Distant(distant) => distant.power(),
            Kind::Environment(environment) => environment.power(),
            Kind::EnvironmentMap(map) => map.power(),
        }
    }

    /// Whether light arrives from it along one direction only (a point, a spot, a distant
    /// light), so that one shadow ray says all there is.
    pub fn is_delta(&self) -> bool {
        matches!(
            self.0,
            Kind::Point { .. } | Kind::Spot(_) | Kind::Distant(_)
        )
    }

    /// Radiance leaving a visible area light towards a viewer at `cos_out` from its surface's
    /// normal (zero for lights with no surface).
    pub fn emitted_radiance(&self, cos_out: f32) -> Vec3 {
        match &self.0 {
            Kind::Sphere { radius, power, .. } => area::sphere_radiance(*radius, *power),
            Kind::Quad {
                edge_u,
                edge_v,
                power,
                ..
            } => {
                if cos_out <= 0.0 {
                    return Vec3::ZERO;
                }
                *power / (std::f32::consts::PI * area::quad_area_normal(*edge_u, *edge_v).0)
            }
            Kind::Mesh(mesh) => mesh.emitted_radiance(cos_out),
            Kind::Point { .. }
            | Kind::Spot(_)
            | Kind::Distant(_)
            | Kind::Environment(_)
            | Kind::EnvironmentMap(_) => Vec3::ZERO,
        }
    }

    /// The point a small light's light comes from (a point or spot light's position, a
    /// sphere light's centre), around which a camera ray through a medium samples its
    /// scattering points equiangularly; `None` for the others.
    pub fn center(&self) -> Option<Vec3> {
        match &self.0 {
            Kind::Point { position, .. } => Some(*position),
            Kind::Spot(spot) => Some(spot.position()),
            Kind::Sphere { center, .. } => Some(*center),
            _ => None,
        }
    }

    /// A spot light's cone (apex, unit axis, cosine of the half-angle past which it is
    /// dark): no light of it leaves outside.
    pub fn cone(&self) -> Option<(Vec3, Vec3, f32)> {
        match &self.0 {
            Kind::Spot(spot) => Some(spot.cone()),
            _ => None,
        }
    }

    /// Where this light's light comes from, as the pilot rays see it.
    pub fn shape(&self) -> LightShape {
        match &self.0 {
            Kind::Point { position, .. } => LightShape::Point(*position),
            Kind::Spot(spot) => LightShape::Point(spot.position()),
            Kind::Sphere { center, radius, .. } => LightShape::Sphere(BoundingSphere {
                center: *center,
                radius: *radius,
            }),
            Kind::Quad {
                corner,
                edge_u,
                edge_v,
                ..
            } => LightShape::Quad {
                corner: *corner,
                edge_u: *edge_u,
                edge_v: *edge_v,
            },
            Kind::Mesh(mesh) => LightShape::Mesh {
                spheres: mesh.bounding_spheres(MESH_SPHERES),
                point: mesh.largest_triangle_centroid(),
            },
            Kind::Distant(distant) => LightShape::Direction(distant.towards()),
            Kind::Environment(_) | Kind::EnvironmentMap(_) => LightShape::Everywhere,
        }
    }

    /// Radiance a ray that leaves the scene sees from this light whatever its direction (a
    /// constant environment's).
    pub fn radiance_at_infinity(&self) -> Vec3 {
        match &self.0 {
            Kind::Environment(environment) => environment.radiance(),
            _ => Vec3::ZERO,
        }
    }

    /// Whether what a ray leaving the scene sees of this light depends on its direction (an
    /// image environment).
    pub fn has_directional_sky(&self) -> bool {
        matches!(self.0, Kind::EnvironmentMap(_))
    }

    /// Radiance a ray leaving the scene along the unit `direction` sees from an image
    /// environment (zero from every other light).
    #[inline]
    pub fn sky_radiance(&self, direction: Vec3) -> Vec3 {
        match &self.0 {
            Kind::EnvironmentMap(map) => map.radiance(direction),
            _ => Vec3::ZERO,
        }
    }

    /// Samples light arriving at `x`, a surface point with unit normal `n`, from this light
    /// (one sample, from the pair `u`). `None` when no light can arrive that way.
    pub fn sample_incident(&self, x: Vec3, n: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        match &self.0 {
            Kind::Point { position, power } => point::point_incident(*position, *power, x),
            Kind::Spot(spot) => spot.incident(x),
            Kind::Sphere {
                center,
                radius,
                power,
            } => area::sphere_incident(*center, *radius, *power, x, u),
            Kind::Quad {
                corner,
                edge_u,
                edge_v,
                power,
            } => area::quad_incident(*corner, *edge_u, *edge_v, *power, x, u),
            Kind::Mesh(mesh) => mesh.incident(x, u),
            Kind::Distant(distant) => Some(distant.incident()),
            Kind::Environment(environment) => environment.incident(n, u),
            Kind::EnvironmentMap(map) => map.incident(n, u),
        }
    }
}

/// The solid-angle density of a point drawn uniformly over a flat emitter of `area` (both
/// sides when `two_sided`), seen along `dir` at `distance` where its normal is
/// `light_normal`.
fn flat_pdf((dir, distance): (Vec3, f32), light_normal: Vec3, area: f32, two_sided: bool) -> f32 {
    let cos = -dir.dot(light_normal);
    let cos = if two_sided { cos.abs() } else { cos };
    if cos > 0.0 && area > 0.0 {
        distance * distance / (cos * area)
    } else {
        0.0
    }
}

/// The light tree's view of the lights.
impl LightSource {
    /// What the light tree holds of this light: one entry, or one per triangle of a mesh;
    /// none for the lights at infinity, which every point sees alike.
    pub fn tree_entries(&self) -> Vec<tree::LightBounds> {
        let phi = weight(self.power());
        match &self.0 {
            Kind::Point { position, .. } => {
                vec![tree::LightBounds::everywhere(*position, *position, phi)]
            }
            Kind::Spot(spot) => vec![spot.bounds()],
            Kind::Sphere { center, radius, .. } => vec![tree::LightBounds::everywhere(
                *center - *radius,
                *center + *radius,
                phi,
            )],
            Kind::Quad {
                corner,
                edge_u,
                edge_v,
                ..
            } => {
                let corners = [*corner, *corner + *edge_u, *corner + *edge_v];
                let far = *corner + *edge_u + *edge_v;
                let lo = corners.iter().fold(far, |a, c| a.min(*c));
                let hi = corners.iter().fold(far, |a, c| a.max(*c));
                let normal = area::quad_area_normal(*edge_u, *edge_v).1;
                vec![tree::LightBounds::flat(lo, hi, phi, normal, false)]
            }
            Kind::Mesh(mesh) if self.drawn_by_triangle() => mesh.triangle_bounds(phi),
            Kind::Mesh(mesh) => vec![mesh.bounds(phi)],
            Kind::Distant(_) | Kind::Environment(_) | Kind::EnvironmentMap(_) => Vec::new(),
        }
    }

    /// [`LightSource::sample_incident`] from triangle `part` of a mesh light alone (`None`:
    /// the whole light, as for every other kind).
    pub fn sample_incident_part(
        &self,
        x: Vec3,
        n: Vec3,
        u: (f32, f32),
        part: Option<u32>,
    ) -> Option<IncidentSample> {
        match (&self.0, part) {
            (Kind::Mesh(mesh), Some(k)) => mesh.incident_on(k as usize, x, u),
            _ => self.sample_incident(x, n, u),
        }
    }

    /// [`LightSource::incident_pdf`] for [`LightSource::sample_incident_part`]'s draws.
    pub fn incident_pdf_part(
        &self,
        x: Vec3,
        n: Vec3,
        (dir, distance): (Vec3, f32),
        light_normal: Vec3,
        part: Option<u32>,
    ) -> f32 {
        match (&self.0, part) {
            (Kind::Mesh(mesh), Some(k)) if (k as usize) < mesh.triangle_count() => {
                let area = mesh.triangle_area(k as usize);
                flat_pdf((dir, distance), light_normal, area, mesh.two_sided())
            }
            _ => self.incident_pdf(x, n, dir, distance, light_normal),
        }
    }

    /// Whether the light tree holds this light's triangles one by one: a mesh light of at
    /// most [`TREE_TRIANGLES_MAX`] triangles (a bigger one is one entry, drawn by area as
    /// ever: its tree would cost more than it saves).
    pub fn drawn_by_triangle(&self) -> bool {
        matches!(&self.0, Kind::Mesh(mesh) if mesh.triangle_count() <= TREE_TRIANGLES_MAX)
    }
}

impl LightSource {
    /// [`LightSource::sample_incident`] at a receiver that weighs light by the cosine to a
    /// shading normal far from its surface's `n` (pbrt's matte with such "N"): a uniform
    /// environment then also draws directions uniformly over the hemisphere (see
    /// [`infinite::Environment::incident_wide`]), where the cosine to `n` alone gives grazing
    /// directions unbounded weights (a floor whose normals lie in it sparkled). The same
    /// expectation; other lights sample as ever.
    pub fn sample_incident_wide(&self, x: Vec3, n: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        match &self.0 {
            Kind::Environment(environment) => environment.incident_wide(n, u),
            _ => self.sample_incident(x, n, u),
        }
    }

    /// Samples light arriving at `x`, a point inside a medium (no surface, so every
    /// direction counts): environments over the whole sphere, other lights as at a surface.
    pub fn sample_incident_in_medium(&self, x: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        match &self.0 {
            Kind::Environment(environment) => Some(environment.incident_sphere(u)),
            Kind::EnvironmentMap(map) => map.incident_sphere(u),
            _ => self.sample_incident(x, Vec3::Z, u),
        }
    }

    /// The solid-angle density with which [`LightSource::sample_incident`] at `x` (normal `n`)
    /// draws the unit direction `dir`, given that a ray along it meets this light at distance
    /// `distance` where its surface's normal is `light_normal` (anything for the lights at
    /// infinity): what a BSDF sample that found the light weighs itself against. Zero for a
    /// point, spot or distant light, which no such ray can find.
    pub fn incident_pdf(
        &self,
        x: Vec3,
        n: Vec3,
        dir: Vec3,
        distance: f32,
        light_normal: Vec3,
    ) -> f32 {
        let flat =
            |area: f32, two_sided: bool| flat_pdf((dir, distance), light_normal, area, two_sided);
        match &self.0 {
            Kind::Point { .. } | Kind::Spot(_) | Kind::Distant(_) => 0.0,
            Kind::Sphere { center, radius, .. } => {
                let to = *center - x;
                let d2 = to.length_squared();
                if d2 <= radius * radius {
                    return 0.0;
                }
                let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
                if dir.dot(to) < cos_max * d2.sqrt() {
                    return 0.0;
                }
                1.0 / crate::sampling::cone_solid_angle(cos_max)
            }
            Kind::Quad { edge_u, edge_v, .. } => {
                flat(area::quad_area_normal(*edge_u, *edge_v).0, false)
            }
            Kind::Mesh(mesh) => flat(mesh.area(), mesh.two_sided()),
            Kind::Environment(_) => dir.dot(n).max(0.0) / std::f32::consts::PI,
            Kind::EnvironmentMap(map) => {
                let cos = dir.dot(n);
                if cos <= 0.0 {
                    0.0
                } else {
                    0.5 * cos / std::f32::consts::PI + 0.5 * map.pdf(dir)
                }
            }
        }
    }
}

/// Emission from one light towards its targets, with all that stays the same from photon to
/// photon worked out once: the tracer draws millions of photons from each light. With targets,
/// directions are drawn only towards them (when the emission point is outside them all, see
/// [`super::aim::UnionOfCones`] and [`super::aim_grid::AimGrid`]) and the flux is weighted by
/// the solid angle kept; lights at infinity start their photons on the targets' discs. A
/// point, spot or sphere light may then be guided ([`LightEmitter::guide`]): its directions
/// spread over its cones by the cells a render learnt ([`super::aim_guide`]).
#[derive(Clone, Debug)]
pub struct LightEmitter {
    source: Source,
    aim: Vec<BoundingSphere>,
}

#[derive(Clone, Debug)]
enum Source {
    Point(point::PointEmitter),
    Spot(point::SpotEmitter),
    Sphere(area::SphereEmitter),
    Quad(area::QuadEmitter),
    Mesh(Arc<area::MeshLight>),
    Distant(infinite::DistantEmitter),
    Environment(infinite::EnvironmentEmitter),
    EnvironmentMap(environment_map::EnvironmentMapEmitter),
}

impl LightEmitter {
    pub fn new(light: &LightSource, aim: &[BoundingSphere]) -> Self {
        let source = match &light.0 {
            Kind::Point { position, power } => {
                Source::Point(point::PointEmitter::new(*position, *power, aim))
            }
            Kind::Spot(spot) => Source::Spot(point::SpotEmitter::new(spot, aim)),
            Kind::Sphere {
                center,
                radius,
                power,
            } => Source::Sphere(area::SphereEmitter::new(*center, *radius, *power, aim)),
            Kind::Quad {
                corner,
                edge_u,
                edge_v,
                power,
            } => Source::Quad(area::QuadEmitter::new(
                *corner, *edge_u, *edge_v, *power, aim,
            )),
            Kind::Mesh(mesh) => Source::Mesh(Arc::clone(mesh)),
            Kind::Distant(distant) => Source::Distant(infinite::DistantEmitter::new(distant, aim)),
            Kind::Environment(environment) => {
                Source::Environment(infinite::EnvironmentEmitter::new(environment, aim))
            }
            Kind::EnvironmentMap(map) => {
                Source::EnvironmentMap(environment_map::EnvironmentMapEmitter::new(map, aim))
            }
        };
        Self {
            source,
            aim: aim.to_vec(),
        }
    }

    /// For a light at infinity, sends `share` of the photons through each `extra` sphere's
    /// disc as well as over the whole scene (the start's area weighs it back); other lights
    /// are left as they are.
    pub fn share_with(&mut self, extra: &[(BoundingSphere, f32)]) {
        match &mut self.source {
            Source::Distant(e) => e.share_discs(extra),
            Source::Environment(e) => e.share_discs(extra),
            Source::EnvironmentMap(e) => e.share_discs(extra),
            _ => {}
        }
    }

    /// The cones this light aims its photons through when they come from one point (a point,
    /// spot or sphere light; the sphere's from its centre): what a caustic guide
    /// ([`super::aim_guide`]) is learnt on and steers. `None` for lights aimed otherwise (per
    /// cell of a quad, per triangle, from infinity) or not aimed at all.
    pub fn aimed_cones(&self) -> Option<&AimedCones> {
        match &self.source {
            Source::Point(point) => point.cones(),
            Source::Spot(spot) => spot.cones(),
            Source::Sphere(sphere) => sphere.cones(),
            Source::Quad(_)
            | Source::Mesh(_)
            | Source::Distant(_)
            | Source::Environment(_)
            | Source::EnvironmentMap(_) => None,
        }
    }

    /// Guides this light's aimed photons by `cells`, learnt on its [`LightEmitter::aimed_cones`];
    /// false (and unguided) for a light without them.
    pub fn guide(&mut self, cells: Arc<ConeCells>) -> bool {
        let cones = match &mut self.source {
            Source::Point(point) => point.cones_mut(),
            Source::Spot(spot) => spot.cones_mut(),
            Source::Sphere(sphere) => sphere.cones_mut(),
            Source::Quad(_)
            | Source::Mesh(_)
            | Source::Distant(_)
            | Source::Environment(_)
            | Source::EnvironmentMap(_) => None,
        };
        cones.map(|c| c.guide(cells)).is_some()
    }

    /// One photon, drawn from `rng`.
    #[inline(always)]
    pub fn emit(&self, rng: &mut Rng) -> Emission {
        // The emitters by reference: their prepared unions are large, and a copy per photon
        // showed.
        match &self.source {
            Source::Point(point) => point.emit(rng),
            Source::Spot(spot) => spot.emit(rng),
            Source::Sphere(sphere) => sphere.emit(&self.aim, rng),
            Source::Quad(quad) => quad.emit(&self.aim, rng),
            Source::Mesh(mesh) => mesh.emit(&self.aim, rng),
            Source::Distant(distant) => distant.emit(rng),
            Source::Environment(environment) => environment.emit(rng),
            Source::EnvironmentMap(map) => map.emit(rng),
        }
    }
}
