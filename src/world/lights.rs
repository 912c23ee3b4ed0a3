//! Lights as light transport sees them: emitting photons (optionally aimed at a bounding sphere,
//! for caustic photons), sampling incident light at a surface point for direct lighting, and the
//! radiance of a visible emitter. Owns the sampling densities; must not trace rays.

use super::BoundingSphere;
use crate::sampling::{Rng, cone_solid_angle, cosine_hemisphere, uniform_cone, uniform_sphere};
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

/// The cone from `origin` that just holds the sphere `aim`: its unit axis and the cosine of its
/// half-angle. `None` without an aim or from inside the sphere.
fn aim_cone(aim: Option<BoundingSphere>, origin: Vec3) -> Option<(Vec3, f32)> {
    let b = aim?;
    let to = b.center - origin;
    let d2 = to.length_squared();
    if d2 <= b.radius * b.radius {
        return None;
    }
    let cos_max = (1.0 - b.radius * b.radius / d2).max(0.0).sqrt();
    Some((to / d2.sqrt(), cos_max))
}

/// Emits one photon. With `aim`, directions are drawn only towards that sphere (when the
/// emission point is outside it) and the flux is weighted by the solid angle kept.
pub fn emit(light: &Light, aim: Option<BoundingSphere>, rng: &mut Rng) -> Emission {
    match light {
        Light::Point { position, power } => match aim_cone(aim, *position) {
            Some((axis, cos_max)) => Emission {
                origin: *position,
                direction: uniform_cone(axis, cos_max, rng.next_2d()),
                flux: *power * (cone_solid_angle(cos_max) / (4.0 * PI)),
            },
            None => Emission {
                origin: *position,
                direction: uniform_sphere(rng.next_2d()),
                flux: *power,
            },
        },
        Light::Sphere {
            center,
            radius,
            power,
        } => {
            let normal = uniform_sphere(rng.next_2d());
            surface_emission(*center + *radius * normal, normal, *power, aim, rng)
        }
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            power,
        } => {
            let (s, t) = rng.next_2d();
            let (_, normal) = quad_area_normal(*edge_u, *edge_v);
            surface_emission(
                *corner + s * *edge_u + t * *edge_v,
                normal,
                *power,
                aim,
                rng,
            )
        }
    }
}

/// Lambertian emission from a point on an area light (area pdf already folded into `power`).
fn surface_emission(
    origin: Vec3,
    normal: Vec3,
    power: Vec3,
    aim: Option<BoundingSphere>,
    rng: &mut Rng,
) -> Emission {
    match aim_cone(aim, origin) {
        Some((axis, cos_max)) => {
            // When the whole cone lies behind the surface (half of an aimed sphere light) the
            // photon carries nothing: skip drawing its direction. The test is
            // n·axis < -(sin_max + δ) with δ = 1e-3, squared to spare a square root
            // ((sin + δ)² < sin² + 3δ): every photon that could carry flux goes on below.
            let along = normal.dot(axis);
            if along < 0.0 && along * along > 1.0 - cos_max * cos_max + 3e-3 {
                return Emission {
                    origin,
                    direction: axis,
                    flux: Vec3::ZERO,
                };
            }
            // flux = L cosθ / (pdf_A pdf_ω) with L = Φ/(πA): Φ cosθ Ω / π.
            let direction = uniform_cone(axis, cos_max, rng.next_2d());
            let cos = direction.dot(normal).max(0.0);
            Emission {
                origin,
                direction,
                flux: power * (cos * cone_solid_angle(cos_max) / PI),
            }
        }
        None => Emission {
            origin,
            direction: cosine_hemisphere(normal, rng.next_2d()),
            flux: power,
        },
    }
}

/// Samples light arriving at `x` from `light` (one sample). `None` when no light can arrive.
pub fn sample_incident(light: &Light, x: Vec3, rng: &mut Rng) -> Option<IncidentSample> {
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
            let direction = uniform_cone(axis, cos_max, rng.next_2d());
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
            let (s, t) = rng.next_2d();
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
                if let Some(s) = sample_incident(&light, Vec3::ZERO, &mut rng) {
                    direct += s.irradiance * s.direction.z.max(0.0);
                }
            }
            direct /= n as f32;
            // Flux through the disc of radius 0.2 at z = 0 from photons (plane z = 0 facing +z).
            let r = 0.2f32;
            let mut flux = Vec3::ZERO;
            let m = 2_000_000;
            for i in 0..m {
                let mut rng = Rng::for_index(2, Stream::CausticPhotons, i);
                let e = emit(&light, None, &mut rng);
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

    /// Aiming photons at a sphere keeps the flux that reaches it unbiased.
    #[test]
    fn aimed_emission_preserves_the_flux_into_the_target() {
        let target = BoundingSphere {
            center: Vec3::new(0.0, 0.0, 0.0),
            radius: 0.3,
        };
        for light in lights() {
            let hits = |aim: Option<BoundingSphere>, seed: u64| {
                let m = 1_000_000;
                let mut flux = Vec3::ZERO;
                for i in 0..m {
                    let mut rng = Rng::for_index(seed, Stream::CausticPhotons, i);
                    let e = emit(&light, aim, &mut rng);
                    let oc = e.origin - target.center;
                    let b = oc.dot(e.direction);
                    let c = oc.length_squared() - target.radius * target.radius;
                    if b < 0.0 && b * b - c > 0.0 {
                        flux += e.flux;
                    }
                }
                flux / m as f32
            };
            let aimed = hits(Some(target), 3);
            let plain = hits(None, 4);
            let rel = (aimed - plain).abs().max_element() / plain.max_element();
            assert!(rel < 0.03, "{light:?}: aimed {aimed} vs plain {plain}");
        }
    }
}
