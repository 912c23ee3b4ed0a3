//! Lights as light transport sees them: emitting photons (optionally aimed at a bounding sphere,
//! for caustic photons), sampling incident light at a surface point for direct lighting, and the
//! radiance of a visible emitter. Owns the sampling densities; must not trace rays.

use super::BoundingSphere;
use super::aim::{PreparedUnion, UnionOfCones, cone_towards};
use super::aim_grid::{AimGrid, CellDraw};
use crate::sampling::{
    Rng, basis, cone_solid_angle, cosine_hemisphere, cosine_hemisphere_in, uniform_cone,
    uniform_disc, uniform_sphere,
};
use crate::scene::Light;
use glam::Vec3;
use std::f32::consts::PI;

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
    /// margin that keeps the light's own surface out of the test.
    pub distance: f32,
    /// Irradiance contribution on a surface facing `direction` (already divided by the pdf),
    /// before the receiver's cosine: multiply by `max(0, n·direction)`.
    pub irradiance: Vec3,
}

pub fn power(light: &Light) -> Vec3 {
    match light {
        Light::Point { power, .. } | Light::Sphere { power, .. } | Light::Quad { power, .. } => {
            *power
        }
    }
}

/// Luminance-like weight used to split photons among lights.
pub fn weight(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.2126, 0.7152, 0.0722)).max(0.0)
}

fn quad_area_normal(edge_u: Vec3, edge_v: Vec3) -> (f32, Vec3) {
    let c = edge_u.cross(edge_v);
    (c.length(), c.normalize_or(Vec3::Z))
}

/// Radiance leaving a visible area light towards a viewer on the side of `normal`.
pub fn emitted_radiance(light: &Light, cos_out: f32) -> Vec3 {
    match light {
        Light::Point { .. } => Vec3::ZERO,
        Light::Sphere { radius, power, .. } => *power / (PI * 4.0 * PI * radius * radius),
        Light::Quad {
            edge_u,
            edge_v,
            power,
            ..
        } => {
            if cos_out <= 0.0 {
                return Vec3::ZERO;
            }
            *power / (PI * quad_area_normal(*edge_u, *edge_v).0)
        }
    }
}

/// The cone, from the centre of a sphere light (centre `center`, radius `radius`), that holds
/// every segment from the light to the sphere `target`: its unit axis and the cosine of its
/// half-angle. `None` when the two spheres are too close for a cone.
///
/// A segment's ends lie within r and R of the two centres, so it runs within θ of the axis
/// between them, sin θ = (r + R) / D. Light that reaches the target leaves in those directions.
#[inline(always)]
fn light_to_target_cone(target: &BoundingSphere, center: Vec3, radius: f32) -> Option<(Vec3, f32)> {
    // The cone from the light's centre towards the target grown by the light's radius.
    let grown = BoundingSphere {
        center: target.center,
        radius: target.radius + radius,
    };
    cone_towards(&grown, center)
}

/// Emission from one light towards its targets, with all that stays the same from photon to
/// photon worked out once: the tracer draws millions of photons from each light. With targets,
/// directions are drawn only towards them (when the emission point is outside them all, see
/// [`UnionOfCones`] and [`AimGrid`]) and the flux is weighted by the solid angle kept.
#[derive(Clone, Debug)]
pub struct LightEmitter {
    source: Source,
    aim: Vec<BoundingSphere>,
}

#[derive(Clone, Debug)]
enum Source {
    /// Directions from the cones towards the targets, or from the whole sphere; `flux` is
    /// that of the whole sphere of directions, Φ / 4π per steradian when aimed.
    Point {
        position: Vec3,
        cones: Option<PreparedUnion>,
        flux: Vec3,
    },
    /// Aimed: a direction from the cones that hold the targets (see [`light_to_target_cone`]),
    /// then a point of the light's disc as seen from that direction, lifted onto the side of
    /// the sphere that faces it. A sphere of uniform radiance L shows the area πr² in every
    /// direction, so a photon carries L πr² / pdf(ω) = Φ / (4π pdf(ω)), and none is drawn
    /// behind the surface it leaves. Not aimed: a point, then a cosine-weighted direction.
    Sphere {
        center: Vec3,
        radius: f32,
        toward_targets: Option<PreparedUnion>,
        power: Vec3,
    },
    /// Aimed: directions from the cones of the point's cell ([`AimGrid`]), or from the point's
    /// own cones in cells too close to a target. Not aimed: a cosine-weighted direction.
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        normal: Vec3,
        /// The tangents of `normal` ([`basis`]), for unaimed photons.
        tangents: (Vec3, Vec3),
        power: Vec3,
        grid: Option<AimGrid>,
    },
}

impl LightEmitter {
    pub fn new(light: &Light, aim: &[BoundingSphere]) -> Self {
        let source = match *light {
            Light::Point { position, power } => {
                let cones = UnionOfCones::towards(aim, position).map(UnionOfCones::prepared);
                Source::Point {
                    position,
                    cones,
                    flux: if cones.is_some() {
                        power / (4.0 * PI)
                    } else {
                        power
                    },
                }
            }
            Light::Sphere {
                center,
                radius,
                power,
            } => {
                let cones: Option<Vec<_>> = (aim.iter())
                    .map(|target| light_to_target_cone(target, center, radius))
                    .collect();
                Source::Sphere {
                    center,
                    radius,
                    toward_targets: cones
                        .and_then(UnionOfCones::new)
                        .map(UnionOfCones::prepared),
                    power,
                }
            }
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                power,
            } => {
                let normal = quad_area_normal(edge_u, edge_v).1;
                Source::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    normal,
                    tangents: basis(normal),
                    power,
                    grid: AimGrid::new(corner, edge_u, edge_v, normal, aim),
                }
            }
        };
        Self {
            source,
            aim: aim.to_vec(),
        }
    }

    /// One photon, drawn from `rng`.
    #[inline(always)]
    pub fn emit(&self, rng: &mut Rng) -> Emission {
        // The prepared unions by reference: they are large, and a copy per photon showed.
        match self.source {
            Source::Point {
                position,
                ref cones,
                flux,
            } => match cones {
                Some(cones) => {
                    let (direction, weight) = cones.sample(rng);
                    Emission {
                        origin: position,
                        direction,
                        flux: flux * weight,
                    }
                }
                None => Emission {
                    origin: position,
                    direction: uniform_sphere(rng.next_2d()),
                    flux,
                },
            },
            Source::Sphere {
                center,
                radius,
                toward_targets: Some(ref cones),
                power,
            } => {
                let (direction, weight) = cones.sample(rng);
                let (t, b) = basis(direction);
                let (x, y) = uniform_disc(rng.next_2d());
                let lift = (1.0 - x * x - y * y).max(0.0).sqrt();
                Emission {
                    origin: center + radius * (t * x + b * y + direction * lift),
                    direction,
                    flux: power * (weight / (4.0 * PI)),
                }
            }
            Source::Sphere {
                center,
                radius,
                toward_targets: None,
                power,
            } => {
                let normal = uniform_sphere(rng.next_2d());
                surface_emission(center + radius * normal, normal, power, &self.aim, rng)
            }
            Source::Quad {
                corner,
                edge_u,
                edge_v,
                normal,
                tangents,
                power,
                ref grid,
            } => {
                let (s, t) = rng.next_2d();
                let origin = corner + s * edge_u + t * edge_v;
                let Some(grid) = grid else {
                    // Unaimed: as `surface_emission` without targets.
                    return Emission {
                        origin,
                        direction: cosine_hemisphere_in(tangents, normal, rng.next_2d()),
                        flux: power,
                    };
                };
                match grid.draw(s, t, origin, rng) {
                    CellDraw::Aimed(direction, weight) => {
                        lambertian_aimed(origin, normal, power, direction, weight)
                    }
                    CellDraw::Nothing => Emission {
                        origin,
                        direction: normal,
                        flux: Vec3::ZERO,
                    },
                    CellDraw::PerPoint => surface_emission(origin, normal, power, &self.aim, rng),
                }
            }
        }
    }
}

/// Lambertian emission from a point on an area light (area pdf already folded into `power`).
#[inline(always)]
fn surface_emission(
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
        return Emission {
            origin,
            direction: normal,
            flux: Vec3::ZERO,
        };
    }
    let (direction, weight) = cones.sample(rng);
    lambertian_aimed(origin, normal, power, direction, weight)
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

/// Samples light arriving at `x` from `light` (one sample). `None` when no light can arrive.
pub fn sample_incident(light: &Light, x: Vec3, u: (f32, f32)) -> Option<IncidentSample> {
    match light {
        Light::Point { position, power } => {
            let to = *position - x;
            let d2 = to.length_squared();
            (d2 > 0.0).then(|| {
                let distance = d2.sqrt();
                IncidentSample {
                    direction: to / distance,
                    distance,
                    irradiance: *power / (4.0 * PI * d2),
                }
            })
        }
        Light::Sphere {
            center,
            radius,
            power,
        } => {
            let to = *center - x;
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
            let radiance = emitted_radiance(light, 1.0);
            let _ = power;
            Some(IncidentSample {
                direction,
                distance,
                irradiance: radiance * cone_solid_angle(cos_max),
            })
        }
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            ..
        } => {
            let (s, t) = u;
            let p = *corner + s * *edge_u + t * *edge_v;
            let (area, normal) = quad_area_normal(*edge_u, *edge_v);
            let to = p - x;
            let d2 = to.length_squared();
            let distance = d2.sqrt();
            let direction = to / distance;
            let cos_light = -direction.dot(normal);
            (cos_light > 0.0 && d2 > 0.0).then(|| IncidentSample {
                direction,
                distance,
                irradiance: emitted_radiance(light, cos_light) * (cos_light * area / d2),
            })
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Stream;

    fn lights() -> Vec<Light> {
        vec![
            Light::Point {
                position: Vec3::new(0.0, 0.0, 2.0),
                power: Vec3::new(4.0, 2.0, 1.0),
            },
            Light::Sphere {
                center: Vec3::new(0.3, 0.0, 2.0),
                radius: 0.25,
                power: Vec3::splat(3.0),
            },
            Light::Quad {
                corner: Vec3::new(-0.5, -0.5, 2.0),
                edge_u: Vec3::new(0.0, 1.0, 0.0),
                edge_v: Vec3::new(1.0, 0.0, 0.0),
                power: Vec3::splat(5.0),
            },
        ]
    }

    /// Irradiance at the origin on a +z surface: photon flux through a small disc vs sampling.
    #[test]
    fn emission_and_incident_sampling_agree_on_irradiance() {
        for light in lights() {
            let n = 400_000;
            let mut direct = Vec3::ZERO;
            for i in 0..n {
                let mut rng = Rng::for_index(1, Stream::Pixels, i);
                if let Some(s) = sample_incident(&light, Vec3::ZERO, rng.next_2d()) {
                    direct += s.irradiance * s.direction.z.max(0.0);
                }
            }
            direct /= n as f32;
            // Flux through the disc of radius 0.2 at z = 0 from photons (plane z = 0 facing +z).
            let r = 0.2f32;
            let mut flux = Vec3::ZERO;
            let m = 2_000_000;
            let emitter = LightEmitter::new(&light, &[]);
            for i in 0..m {
                let mut rng = Rng::for_index(2, Stream::CausticPhotons, i);
                let e = emitter.emit(&mut rng);
                if e.direction.z < 0.0 {
                    let t = -e.origin.z / e.direction.z;
                    let p = e.origin + t * e.direction;
                    if p.truncate().length() < r {
                        flux += e.flux;
                    }
                }
            }
            let photon_e = flux / (m as f32 * PI * r * r);
            let rel = (photon_e - direct).abs().max_element() / direct.max_element();
            assert!(
                rel < 0.03,
                "{light:?}: photons {photon_e} vs sampling {direct}"
            );
        }
    }

    /// Aiming photons at spheres keeps the flux that reaches each of them unbiased, for one
    /// target and for two (the second apart from the first, as the Cornell box's are).
    #[test]
    fn aimed_emission_preserves_the_flux_into_the_targets() {
        let sphere = |x: f32, y: f32, z: f32, radius: f32| BoundingSphere {
            center: Vec3::new(x, y, z),
            radius,
        };
        // Far from the lights (a sphere light's cone has sin θ = 0.27), near them (0.79), and
        // a far target with a second one off to the side.
        let aims = [
            vec![sphere(0.0, 0.0, 0.0, 0.3)],
            vec![sphere(0.0, 0.2, 1.4, 0.3)],
            vec![sphere(0.0, 0.0, 0.0, 0.3), sphere(1.2, 0.3, 0.4, 0.25)],
        ];
        for light in lights() {
            for aim in &aims {
                // Flux per photon into each target, along rays that enter it.
                let into = |aim: &[BoundingSphere], seed: u64| {
                    let m = 1_000_000;
                    let mut flux = vec![Vec3::ZERO; aim.len()];
                    let emitter = LightEmitter::new(&light, aim);
                    for i in 0..m {
                        let mut rng = Rng::for_index(seed, Stream::CausticPhotons, i);
                        let e = emitter.emit(&mut rng);
                        for (target, flux) in aim.iter().zip(&mut flux) {
                            let oc = e.origin - target.center;
                            let b = oc.dot(e.direction);
                            let c = oc.length_squared() - target.radius * target.radius;
                            if b < 0.0 && b * b - c > 0.0 {
                                *flux += e.flux / m as f32;
                            }
                        }
                    }
                    flux
                };
                let aimed = into(aim, 3);
                // Unaimed photons, counted against the same targets.
                let plain = {
                    let mut flux = vec![Vec3::ZERO; aim.len()];
                    let emitter = LightEmitter::new(&light, &[]);
                    for (k, target) in aim.iter().enumerate() {
                        let m = 1_000_000;
                        for i in 0..m {
                            let mut rng = Rng::for_index(4, Stream::CausticPhotons, i);
                            let e = emitter.emit(&mut rng);
                            let oc = e.origin - target.center;
                            let b = oc.dot(e.direction);
                            let c = oc.length_squared() - target.radius * target.radius;
                            if b < 0.0 && b * b - c > 0.0 {
                                flux[k] += e.flux / m as f32;
                            }
                        }
                    }
                    flux
                };
                for (aimed, plain) in aimed.iter().zip(&plain) {
                    let rel = (*aimed - *plain).abs().max_element() / plain.max_element();
                    assert!(
                        rel < 0.03,
                        "{light:?}, {} targets: aimed {aimed} vs plain {plain}",
                        aim.len()
                    );
                }
            }
        }
    }

    /// Every segment from a sphere light to the aimed sphere lies in the cone that aimed sphere
    /// lights draw their directions from.
    #[test]
    fn the_cone_from_a_sphere_light_holds_every_segment_to_the_aim() {
        let (center, radius) = (Vec3::new(0.3, -0.2, 2.0), 0.25);
        let mut rng = Rng::for_index(9, Stream::CausticPhotons, 0);
        let mut tested = 0;
        for k in 0..200 {
            let aim = BoundingSphere {
                center: uniform_sphere(rng.next_2d()) * (0.3 + 0.02 * k as f32),
                radius: 0.05 + 0.002 * k as f32,
            };
            let Some((axis, cos_max)) = light_to_target_cone(&aim, center, radius) else {
                assert!(radius + aim.radius >= (aim.center - center).length());
                continue;
            };
            for _ in 0..500 {
                // Points on both surfaces, where the segments lean furthest from the axis.
                let x = center + radius * uniform_sphere(rng.next_2d());
                let y = aim.center + aim.radius * uniform_sphere(rng.next_2d());
                let d = (y - x).normalize();
                assert!(d.dot(axis) >= cos_max - 1e-5, "{x} -> {y} leaves the cone");
                tested += 1;
            }
        }
        assert!(tested > 50_000, "only {tested} segments tested");
    }

    /// Aimed photons of a sphere light leave from its surface, outwards, and carry equal flux.
    #[test]
    fn aimed_sphere_light_photons_leave_its_surface_outwards() {
        let light = lights()[1].clone();
        let Light::Sphere { center, radius, .. } = light else {
            unreachable!()
        };
        let aim = [BoundingSphere {
            center: Vec3::ZERO,
            radius: 0.3,
        }];
        let mut flux = None;
        let emitter = LightEmitter::new(&light, &aim);
        for i in 0..10_000 {
            let mut rng = Rng::for_index(5, Stream::CausticPhotons, i);
            let e = emitter.emit(&mut rng);
            let n = (e.origin - center) / radius;
            assert!((n.length() - 1.0).abs() < 1e-5, "origin off the sphere");
            assert!(e.direction.dot(n) >= -1e-6, "leaves inwards");
            assert_eq!(*flux.get_or_insert(e.flux), e.flux);
        }
    }
}
