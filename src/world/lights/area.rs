//! Area lights: diffuse emitters over a sphere, a parallelogram (quad) or a triangle mesh,
//! uniform radiance L = Φ / (π A) over their surface (Φ / (2π A) a side for a two-sided mesh).
//! Owns picking points on them (a mesh by area, through a cumulative table), their
//! cosine-weighted and aimed photons, and the light they send to a point; must not trace rays.
//!
//! Aiming a mesh light: each photon builds the cones towards the targets from its own point
//! (as a sphere light whose targets are too near for one cone does), which is exact: no
//! direction that can reach a target is left out, and none outside the cones is drawn. A quad
//! light does the same from its cells ([`AimGrid`]) instead, to save the per-photon cones; a
//! mesh's triangles are too many for a grid each.

use super::{Emission, IncidentSample};
use crate::sampling::{
    Rng, basis, cone_solid_angle, cosine_hemisphere, cosine_hemisphere_in, uniform_cone,
    uniform_disc, uniform_sphere,
};
use crate::scene::TriangleMesh;
use crate::world::BoundingSphere;
use crate::world::aim::{UnionOfCones, cone_towards};
use crate::world::aim_grid::{AimGrid, CellDraw};
use crate::world::aim_guide::AimedCones;
use glam::Vec3;
use std::f32::consts::PI;

pub(super) fn quad_area_normal(edge_u: Vec3, edge_v: Vec3) -> (f32, Vec3) {
    let c = edge_u.cross(edge_v);
    (c.length(), c.normalize_or(Vec3::Z))
}

/// The radiance of a sphere light of `power` and `radius`, in every direction.
pub(super) fn sphere_radiance(radius: f32, power: Vec3) -> Vec3 {
    power / (PI * 4.0 * PI * radius * radius)
}

/// Light arriving at `x` from a sphere light: a direction in the cone the sphere fills.
pub(super) fn sphere_incident(
    center: Vec3,
    radius: f32,
    power: Vec3,
    x: Vec3,
    u: (f32, f32),
) -> Option<IncidentSample> {
    let to = center - x;
    let d2 = to.length_squared();
    if d2 <= radius * radius {
        return None;
    }
    let dist_c = d2.sqrt();
    let axis = to / dist_c;
    let cos_max = (1.0 - radius * radius / d2).max(0.0).sqrt();
    let direction = uniform_cone(axis, cos_max, u);
    // Distance to the near intersection with the light sphere.
    let b = direction.dot(to);
    let disc = (b * b - (d2 - radius * radius)).max(0.0);
    // Embree's sphere hits are less precise than its triangle hits: stop half a radius
    // short, where nothing but the light itself can be.
    let distance = b - disc.sqrt() - 0.5 * radius;
    Some(IncidentSample {
        direction,
        distance,
        irradiance: sphere_radiance(radius, power) * cone_solid_angle(cos_max),
        pdf: 1.0 / cone_solid_angle(cos_max),
    })
}

/// Light arriving at `x` from the point `p` of a flat emitter of radiance `radiance` facing
/// `normal` (both sides when `two_sided`), drawn with density 1 / `area` over the emitter.
#[inline]
fn flat_incident(
    p: Vec3,
    normal: Vec3,
    area: f32,
    radiance: Vec3,
    two_sided: bool,
    x: Vec3,
) -> Option<IncidentSample> {
    let to = p - x;
    let d2 = to.length_squared();
    let distance = d2.sqrt();
    let direction = to / distance;
    let cos_light = -direction.dot(normal);
    let cos_light = if two_sided {
        cos_light.abs()
    } else {
        cos_light
    };
    (cos_light > 0.0 && d2 > 0.0).then(|| IncidentSample {
        direction,
        distance,
        irradiance: radiance * (cos_light * area / d2),
        pdf: d2 / (cos_light * area),
    })
}

/// Light arriving at `x` from a quad light: a point drawn uniformly over it.
pub(super) fn quad_incident(
    corner: Vec3,
    edge_u: Vec3,
    edge_v: Vec3,
    power: Vec3,
    x: Vec3,
    (s, t): (f32, f32),
) -> Option<IncidentSample> {
    let (area, normal) = quad_area_normal(edge_u, edge_v);
    let p = corner + s * edge_u + t * edge_v;
    flat_incident(p, normal, area, power / (PI * area), false, x)
}

/// The cone, from the centre of a sphere light (centre `center`, radius `radius`), that holds
/// every segment from the light to the sphere `target`: its unit axis and the cosine of its
/// half-angle. `None` when the two spheres are too close for a cone.
///
/// A segment's ends lie within r and R of the two centres, so it runs within θ of the axis
/// between them, sin θ = (r + R) / D. Light that reaches the target leaves in those directions.
#[inline(always)]
pub(super) fn light_to_target_cone(
    target: &BoundingSphere,
    center: Vec3,
    radius: f32,
) -> Option<(Vec3, f32)> {
    // The cone from the light's centre towards the target grown by the light's radius.
    let grown = BoundingSphere {
        center: target.center,
        radius: target.radius + radius,
    };
    cone_towards(&grown, center)
}

/// A sphere light's photons. Aimed: a direction from the cones that hold the targets (see
/// [`light_to_target_cone`]), then a point of the light's disc as seen from that direction,
/// lifted onto the side of the sphere that faces it. A sphere of uniform radiance L shows the
/// area πr² in every direction, so a photon carries L πr² / pdf(ω) = Φ / (4π pdf(ω)), and
/// none is drawn behind the surface it leaves. Not aimed (or a target too near for one cone):
/// a point, then a cosine-weighted (or per-point aimed) direction.
#[derive(Clone, Debug)]
pub(super) struct SphereEmitter {
    center: Vec3,
    radius: f32,
    toward_targets: Option<AimedCones>,
    power: Vec3,
}

impl SphereEmitter {
    pub(super) fn cones_mut(&mut self) -> Option<&mut AimedCones> {
        self.toward_targets.as_mut()
    }

    pub(super) fn cones(&self) -> Option<&AimedCones> {
        self.toward_targets.as_ref()
    }

    pub(super) fn new(center: Vec3, radius: f32, power: Vec3, aim: &[BoundingSphere]) -> Self {
        let cones: Option<Vec<_>> = (aim.iter())
            .map(|target| light_to_target_cone(target, center, radius))
            .collect();
        Self {
            center,
            radius,
            toward_targets: cones
                .and_then(UnionOfCones::new)
                .map(|union| AimedCones::new(union.prepared())),
            power,
        }
    }

    #[inline(always)]
    pub(super) fn emit(&self, aim: &[BoundingSphere], rng: &mut Rng) -> Emission {
        let Some(cones) = &self.toward_targets else {
            let normal = uniform_sphere(rng.next_2d());
            return surface_emission(
                self.center + self.radius * normal,
                normal,
                self.power,
                aim,
                rng,
            );
        };
        let (direction, weight) = cones.sample(rng);
        let (t, b) = basis(direction);
        let (x, y) = uniform_disc(rng.next_2d());
        let lift = (1.0 - x * x - y * y).max(0.0).sqrt();
        Emission {
            origin: self.center + self.radius * (t * x + b * y + direction * lift),
            direction,
            flux: self.power * (weight / (4.0 * PI)),
        }
    }
}

/// A quad light's photons. Aimed: directions from the cones of the point's cell
/// ([`AimGrid`]), or from the point's own cones in cells too close to a target. Not aimed: a
/// cosine-weighted direction.
#[derive(Clone, Debug)]
pub(super) struct QuadEmitter {
    corner: Vec3,
    edge_u: Vec3,
    edge_v: Vec3,
    normal: Vec3,
    /// The tangents of `normal` ([`basis`]), for unaimed photons.
    tangents: (Vec3, Vec3),
    power: Vec3,
    grid: Option<AimGrid>,
}

impl QuadEmitter {
    pub(super) fn new(
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        power: Vec3,
        aim: &[BoundingSphere],
    ) -> Self {
        let normal = quad_area_normal(edge_u, edge_v).1;
        Self {
            corner,
            edge_u,
            edge_v,
            normal,
            tangents: basis(normal),
            power,
            grid: AimGrid::new(corner, edge_u, edge_v, normal, aim),
        }
    }

    #[inline(always)]
    pub(super) fn emit(&self, aim: &[BoundingSphere], rng: &mut Rng) -> Emission {
        let (s, t) = rng.next_2d();
        let (normal, power) = (self.normal, self.power);
        let origin = self.corner + s * self.edge_u + t * self.edge_v;
        let Some(grid) = &self.grid else {
            // Unaimed: as `surface_emission` without targets.
            return Emission {
                origin,
                direction: cosine_hemisphere_in(self.tangents, normal, rng.next_2d()),
                flux: power,
            };
        };
        match grid.draw(s, t, origin, rng) {
            CellDraw::Aimed(direction, weight) => {
                lambertian_aimed(origin, normal, power, direction, weight)
            }
            CellDraw::Nothing => nothing_from(origin, normal),
            CellDraw::PerPoint => surface_emission(origin, normal, power, aim, rng),
        }
    }
}

/// A photon that carries nothing (and so is never traced).
#[inline(always)]
fn nothing_from(origin: Vec3, normal: Vec3) -> Emission {
    Emission {
        origin,
        direction: normal,
        flux: Vec3::ZERO,
    }
}

/// Lambertian emission from a point on an area light (area pdf already folded into `power`).
#[inline(always)]
pub(super) fn surface_emission(
    origin: Vec3,
    normal: Vec3,
    power: Vec3,
    aim: &[BoundingSphere],
    rng: &mut Rng,
) -> Emission {
    let cosine_weighted = |rng: &mut Rng| Emission {
        origin,
        direction: cosine_hemisphere(normal, rng.next_2d()),
        flux: power,
    };
    // Unaimed (the global map's photons): not even an empty union to write.
    if aim.is_empty() {
        return cosine_weighted(rng);
    }
    // Built in place: a union returned by value is copied whole (168 bytes) per photon.
    let mut cones = UnionOfCones::empty();
    if !cones.aim(aim, origin) {
        return cosine_weighted(rng);
    }
    // When every cone lies behind the surface (half of an aimed sphere light) the photon
    // carries nothing: skip drawing its direction.
    if cones.behind(normal) {
        return nothing_from(origin, normal);
    }
    let (direction, weight) = cones.sample(rng);
    lambertian_aimed(origin, normal, power, direction, weight)
}

/// [`surface_emission`] from a surface that emits on both sides, each with half the power:
/// unaimed, a side picked with probability 1/2 (so the photon carries `power` again); aimed,
/// a direction from the cones and the side it leaves by.
#[inline(always)]
fn two_sided_emission(
    origin: Vec3,
    normal: Vec3,
    power: Vec3,
    aim: &[BoundingSphere],
    rng: &mut Rng,
) -> Emission {
    let mut cones = UnionOfCones::empty();
    if aim.is_empty() || !cones.aim(aim, origin) {
        let side = if rng.next_f32() < 0.5 {
            normal
        } else {
            -normal
        };
        return Emission {
            origin,
            direction: cosine_hemisphere(side, rng.next_2d()),
            flux: power,
        };
    }
    let (direction, weight) = cones.sample(rng);
    let side = if direction.dot(normal) >= 0.0 {
        normal
    } else {
        -normal
    };
    lambertian_aimed(origin, side, 0.5 * power, direction, weight)
}

/// A photon of a Lambertian area light sent along an aimed `direction` that stands for the
/// solid angle `weight` (one over its density; area pdf already folded into `power`):
/// flux = L cosθ / (pdf_A pdf_ω) with L = Φ/(πA), so Φ cosθ / (π pdf_ω).
#[inline(always)]
fn lambertian_aimed(
    origin: Vec3,
    normal: Vec3,
    power: Vec3,
    direction: Vec3,
    weight: f32,
) -> Emission {
    let cos = direction.dot(normal).max(0.0);
    Emission {
        origin,
        direction,
        flux: power * (cos * weight / PI),
    }
}

/// One triangle of a mesh light: a corner, the edges from it and the unit normal they span.
#[derive(Clone, Copy, Debug)]
struct Triangle {
    corner: Vec3,
    edge_1: Vec3,
    edge_2: Vec3,
    normal: Vec3,
}

impl Triangle {
    /// The point the pair `(u, v)` picks, uniformly over the triangle.
    #[inline]
    fn point(&self, (u, v): (f32, f32)) -> Vec3 {
        let root = u.sqrt();
        let (b1, b2) = (root * (1.0 - v), root * v);
        self.corner + b1 * self.edge_1 + b2 * self.edge_2
    }
}

/// A mesh light's triangles, drawn by area.
#[derive(Clone, Debug)]
pub(super) struct MeshLight {
    triangles: Vec<Triangle>,
    /// The triangles' areas summed up to and including each, over the total (the last is 1).
    cumulative: Vec<f32>,
    area: f32,
    power: Vec3,
    two_sided: bool,
}

impl MeshLight {
    pub(super) fn area(&self) -> f32 {
        self.area
    }

    pub(super) fn triangle_count(&self) -> usize {
        self.triangles.len()
    }

    pub(super) fn two_sided(&self) -> bool {
        self.two_sided
    }

    pub(super) fn new(mesh: &TriangleMesh, power: Vec3, two_sided: bool) -> Self {
        let triangles: Vec<Triangle> = (mesh.triangles.iter())
            .map(|t| {
                let [p0, p1, p2] = t.map(|i| mesh.positions[i as usize]);
                let (edge_1, edge_2) = (p1 - p0, p2 - p0);
                Triangle {
                    corner: p0,
                    edge_1,
                    edge_2,
                    normal: edge_1.cross(edge_2).normalize_or(Vec3::Z),
                }
            })
            .collect();
        // Summed in f64: a big mesh's small triangles would vanish in an f32 running sum.
        let areas: Vec<f64> = (triangles.iter())
            .map(|t| 0.5 * t.edge_1.as_dvec3().cross(t.edge_2.as_dvec3()).length())
            .collect();
        let total: f64 = areas.iter().sum();
        let mut running = 0.0;
        let cumulative = areas
            .iter()
            .map(|a| {
                running += a;
                (running / total) as f32
            })
            .collect();
        // A mesh without area (which `check_light` refuses) emits nothing rather than NaN.
        let usable = total > 0.0 && total.is_finite();
        Self {
            triangles: if usable { triangles } else { Vec::new() },
            cumulative: if usable { cumulative } else { Vec::new() },
            area: total as f32,
            power: if usable { power } else { Vec3::ZERO },
            two_sided,
        }
    }

    pub(super) fn power(&self) -> Vec3 {
        self.power
    }

    /// The centroid of the largest triangle (none for a mesh without area).
    pub(super) fn largest_triangle_centroid(&self) -> Option<Vec3> {
        let area = |t: &Triangle| t.edge_1.cross(t.edge_2).length();
        let largest = (self.triangles.iter()).max_by(|a, b| area(a).total_cmp(&area(b)))?;
        Some(largest.corner + (largest.edge_1 + largest.edge_2) / 3.0)
    }

    /// A sphere round each triangle, or one round them all past `most` triangles (none for
    /// a mesh without area, which emits nothing).
    pub(super) fn bounding_spheres(&self, most: usize) -> Vec<BoundingSphere> {
        let corners = |t: &Triangle| [t.corner, t.corner + t.edge_1, t.corner + t.edge_2];
        let around = |points: &mut dyn Iterator<Item = Vec3>| {
            let first = points.next()?;
            let (lo, hi) = points.fold((first, first), |(lo, hi), p| (lo.min(p), hi.max(p)));
            Some(BoundingSphere::around_box(lo, hi))
        };
        if self.triangles.len() <= most {
            (self.triangles.iter())
                .filter_map(|t| around(&mut corners(t).into_iter()))
                .collect()
        } else {
            around(&mut self.triangles.iter().flat_map(corners))
                .into_iter()
                .collect()
        }
    }

    /// Radiance leaving a side that emits.
    fn radiance(&self) -> Vec3 {
        if self.triangles.is_empty() {
            return Vec3::ZERO;
        }
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        self.power / (sides * PI * self.area)
    }

    /// Radiance towards a viewer at `cos_out` from the triangle's normal.
    pub(super) fn emitted_radiance(&self, cos_out: f32) -> Vec3 {
        if self.two_sided || cos_out > 0.0 {
            self.radiance()
        } else {
            Vec3::ZERO
        }
    }

    /// A point drawn uniformly over the mesh's area, and its triangle's normal. The first
    /// number picks the triangle and is stretched back onto [0, 1) within it, so a
    /// stratified pair stays stratified over the mesh.
    #[inline]
    fn sample_point(&self, (u, v): (f32, f32)) -> (Vec3, Vec3) {
        let last = self.cumulative.len() - 1;
        let k = self.cumulative.partition_point(|&c| c <= u).min(last);
        let below = if k == 0 { 0.0 } else { self.cumulative[k - 1] };
        let width = self.cumulative[k] - below;
        let u = if width > 0.0 {
            ((u - below) / width).clamp(0.0, 1.0)
        } else {
            u
        };
        let t = &self.triangles[k];
        (t.point((u, v)), t.normal)
    }

    /// Light arriving at `x`: a point drawn uniformly over the mesh.
    pub(super) fn incident(&self, x: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        if self.triangles.is_empty() {
            return None;
        }
        let (p, normal) = self.sample_point(u);
        flat_incident(p, normal, self.area, self.radiance(), self.two_sided, x)
    }

    /// Light arriving at `x` from triangle `k` alone: a point drawn uniformly over it (the
    /// light tree picks the triangle).
    pub(super) fn incident_on(&self, k: usize, x: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
        let t = self.triangles.get(k)?;
        let area = self.triangle_area(k);
        flat_incident(
            t.point(u),
            t.normal,
            area,
            self.radiance(),
            self.two_sided,
            x,
        )
    }

    /// Triangle `k`'s area.
    pub(super) fn triangle_area(&self, k: usize) -> f32 {
        let t = &self.triangles[k];
        0.5 * t.edge_1.cross(t.edge_2).length()
    }

    /// The whole mesh's bounds for the light tree: its box, its normals every way.
    pub(super) fn bounds(&self, phi: f32) -> super::tree::LightBounds {
        let corners = (self.triangles.iter())
            .flat_map(|t| [t.corner, t.corner + t.edge_1, t.corner + t.edge_2]);
        let (lo, hi) = corners.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p), hi.max(p))
        });
        super::tree::LightBounds::everywhere(lo, hi, phi)
    }

    /// Each triangle's bounds for the light tree, its power its share of the mesh's.
    pub(super) fn triangle_bounds(&self, phi: f32) -> Vec<super::tree::LightBounds> {
        (self.triangles.iter().enumerate())
            .map(|(k, t)| {
                let corners = [t.corner, t.corner + t.edge_1, t.corner + t.edge_2];
                let lo = corners[0].min(corners[1]).min(corners[2]);
                let hi = corners[0].max(corners[1]).max(corners[2]);
                let share = phi * self.triangle_area(k) / self.area;
                super::tree::LightBounds::flat(lo, hi, share, t.normal, self.two_sided)
            })
            .collect()
    }

    /// A photon from a point drawn by area, cosine-weighted or aimed from that point.
    #[inline(always)]
    pub(super) fn emit(&self, aim: &[BoundingSphere], rng: &mut Rng) -> Emission {
        if self.triangles.is_empty() {
            return nothing_from(Vec3::ZERO, Vec3::Y);
        }
        let (origin, normal) = self.sample_point(rng.next_2d());
        if self.two_sided {
            two_sided_emission(origin, normal, self.power, aim, rng)
        } else {
            surface_emission(origin, normal, self.power, aim, rng)
        }
    }
}
