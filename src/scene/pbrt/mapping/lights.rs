//! pbrt's lights as dpm's. pbrt gives a point or spot light's intensity `I` (W/sr), an area
//! light's radiance `L`, a distant light's irradiance, each times `scale` (pbrt-v4's `power`
//! gives the flux itself); dpm's lights carry their total flux, so the conversions below are
//! the integrals of pbrt's emission: 4π·I for a point, A·π·L for a one-sided emitter. Owns the
//! conversions; must not place shapes (it asks [`super::shapes`] for an emitter's geometry).

use super::super::Dialect;
use super::super::parser::{Item, ShapeItem};
use super::shapes::Geometry;
use super::{Mapper, param_error, value_error};
use crate::scene::{Light, SceneError, SpotFalloff, check_light};
use glam::{Mat4, Vec3};
use std::f32::consts::PI;

impl Mapper<'_> {
    /// `I` or `L` (default 1; an rgb, a constant spectrum or a blackbody) times `scale` (a
    /// spectrum in pbrt-v3, a float in pbrt-v4).
    pub(super) fn emission(&self, item: &Item, name: &str) -> Result<Vec3, SceneError> {
        let p = |e| param_error("LightSource", e);
        let dialect = self.dialect.0;
        let value = item.params.emission(name, dialect).map_err(p)?;
        let scale = item.params.emission("scale", dialect).map_err(p)?;
        let (value, scale) = (value.unwrap_or(Vec3::ONE), scale.unwrap_or(Vec3::ONE));
        Ok(value * scale)
    }

    /// pbrt-v4's `power`, when given: the light's total flux, whatever `I` or `L` say.
    fn given_power(&self, item: &Item) -> Result<Option<f32>, SceneError> {
        item.params
            .float("power")
            .map_err(|e| param_error("LightSource", e))
    }

    pub(super) fn light(&mut self, item: &Item, ctm: &Mat4) -> Result<Light, SceneError> {
        let p = |e| param_error("LightSource", e);
        let point = |name: &str, default: Vec3| -> Result<Vec3, SceneError> {
            let v = item.params.vec3(name).map_err(p)?;
            Ok(ctm.transform_point3(v.map_or(default, |v| v)))
        };
        let light = match item.kind.as_str() {
            "point" => {
                let position = point("from", Vec3::ZERO)?;
                let intensity = self.emission(item, "I")?;
                let power = match self.given_power(item)? {
                    Some(phi) => normalised(intensity) * phi,
                    None => intensity * (4.0 * PI),
                };
                Light::Point { position, power }
            }
            "spot" => {
                let from = point("from", Vec3::ZERO)?;
                let to = point("to", Vec3::Z)?;
                let direction = (to - from).normalize_or_zero();
                if direction == Vec3::ZERO {
                    return Err(item.at.error(
                        "LightSource",
                        "spot: \"from\" and \"to\" are the same point",
                    ));
                }
                let cone = item.params.float("coneangle").map_err(p)?.unwrap_or(30.0);
                // pbrt-v3 names the band "conedeltaangle" (its "conedelta" is an unused
                // parameter, so the default holds), pbrt-v4 "conedelta".
                let delta_name = match self.dialect.0 {
                    Dialect::V3 => "conedeltaangle",
                    Dialect::V4 => "conedelta",
                };
                let delta = item.params.float(delta_name).map_err(p)?.unwrap_or(5.0);
                if !(cone > 0.0 && cone <= 180.0) {
                    return Err(value_error(
                        item,
                        "LightSource",
                        "coneangle",
                        format!("coneangle {cone} is not in (0, 180]"),
                    ));
                }
                let start = (cone - delta).clamp(0.0, cone);
                // pbrt-v3 shapes the edge with (cos θ − cos α)/(cos β − cos α) to the 4th,
                // pbrt-v4 with a smoothstep.
                let falloff = match self.dialect.0 {
                    Dialect::V3 => SpotFalloff::Quartic,
                    Dialect::V4 => SpotFalloff::Smoothstep,
                };
                let intensity = self.emission(item, "I")?;
                let power = match self.given_power(item)? {
                    Some(phi) => normalised(intensity) * phi,
                    None => intensity * falloff.solid_angle(cone, start),
                };
                Light::Spot {
                    position: from,
                    direction,
                    cone_angle_degrees: cone,
                    falloff_start_degrees: start,
                    falloff,
                    power,
                }
            }
            "distant" => {
                let from = point("from", Vec3::ZERO)?;
                let to = point("to", Vec3::Z)?;
                let direction = (to - from).normalize_or_zero();
                if direction == Vec3::ZERO {
                    return Err(item.at.error(
                        "LightSource",
                        "distant: \"from\" and \"to\" are the same point",
                    ));
                }
                let irradiance = match item.params.float("illuminance").map_err(p)? {
                    Some(e) => normalised(self.emission(item, "L")?) * e,
                    None => self.emission(item, "L")?,
                };
                Light::Distant {
                    direction,
                    irradiance,
                }
            }
            "infinite" => {
                item.params.integer("samples").map_err(p)?;
                item.params.integer("nsamples").map_err(p)?;
                if let Some(image) = ["mapname", "filename"]
                    .into_iter()
                    .find(|&image| item.params.at(image).is_some())
                {
                    let light = self.environment_map(item, image, ctm)?;
                    return self.checked(item, "LightSource", light);
                }
                // pbrt-v4's illuminance E sets the radiance so that an upward surface gets E.
                let radiance = match item.params.float("illuminance").map_err(p)? {
                    Some(e) => normalised(self.emission(item, "L")?) * (e / PI),
                    None => self.emission(item, "L")?,
                };
                Light::Environment { radiance }
            }
            "goniometric" | "projection" => {
                return Err(item.at.error(
                    "LightSource",
                    format!(
                        "light \"{}\" needs an image, which dpm does not read",
                        item.kind
                    ),
                ));
            }
            other => {
                return Err(item
                    .at
                    .error("LightSource", format!("\"{other}\" is not a pbrt light")));
            }
        };
        self.checked(item, "LightSource", light)
    }

    /// An `AreaLightSource "diffuse"` on `shape`: a sphere emitter, a quad emitter for a
    /// two-triangle parallelogram, else a mesh emitter.
    pub(super) fn area_light(
        &mut self,
        shape: &ShapeItem,
        area: &Item,
    ) -> Result<Light, SceneError> {
        if area.kind != "diffuse" {
            return Err(area.at.error(
                "AreaLightSource",
                format!("\"{}\": dpm's area lights are diffuse emitters", area.kind),
            ));
        }
        let p = |e| param_error("AreaLightSource", e);
        if area.params.at("filename").is_some() {
            return Err(value_error(
                area,
                "AreaLightSource",
                "filename",
                "image emitters are not supported".into(),
            ));
        }
        let two_sided = area.params.bool("twosided").map_err(p)?.unwrap_or(false);
        let radiance = self.emission(area, "L")?;
        let given = self.given_power(area)?;
        let sides = if two_sided { 2.0 } else { 1.0 };
        let flux = |area_m2: f32| match given {
            Some(phi) => normalised(radiance) * phi,
            None => radiance * (PI * area_m2 * sides),
        };
        let light = match self.geometry(shape)? {
            Geometry::Sphere { center, radius, .. } => {
                if shape.reverse_orientation {
                    return Err(shape.item.at.error(
                        "Shape",
                        "a sphere light turned inside out (ReverseOrientation) is not supported",
                    ));
                }
                let power = match given {
                    Some(phi) => normalised(radiance) * phi,
                    None => radiance * (PI * 4.0 * PI * radius * radius),
                };
                Light::Sphere {
                    center,
                    radius,
                    power,
                }
            }
            Geometry::Curves(_) => {
                return Err(shape.item.at.error(
                    "AreaLightSource",
                    "an area light on a curve is not supported: dpm's area lights are spheres and triangle meshes",
                ));
            }
            Geometry::Triangles(mesh) if mesh.cutout.is_some() => {
                return Err(shape.item.at.error(
                    "Shape",
                    "\"alpha\" on an area light: dpm's emitters are not cut out (cut the mesh instead)",
                ));
            }
            Geometry::Triangles(mut mesh) => {
                // An emitter is flat-shaded, as a TOML mesh light.
                mesh.normals = None;
                let area_m2: f32 = mesh
                    .triangles
                    .iter()
                    .map(|&[a, b, c]| {
                        let p = |i: u32| mesh.positions[i as usize];
                        0.5 * (p(b) - p(a)).cross(p(c) - p(a)).length()
                    })
                    .sum();
                match (two_sided, parallelogram(&mesh.positions, &mesh.triangles)) {
                    (false, Some((corner, edge_u, edge_v))) => Light::Quad {
                        corner,
                        edge_u,
                        edge_v,
                        power: flux(area_m2),
                    },
                    _ => Light::Mesh {
                        mesh,
                        power: flux(area_m2),
                        two_sided,
                    },
                }
            }
        };
        self.checked(area, "AreaLightSource", light)
    }

    fn checked(&self, item: &Item, directive: &str, light: Light) -> Result<Light, SceneError> {
        check_light(&light).map_err(|why| {
            item.at
                .error(directive, format!("light \"{}\": {why}", item.kind))
        })?;
        Ok(light)
    }
}

/// `c` scaled to unit luminance: pbrt-v4's `power` sets the photometric flux and keeps the
/// colour's ratios.
fn normalised(c: Vec3) -> Vec3 {
    let y = c.dot(Vec3::new(0.2126, 0.7152, 0.0722));
    if y > 0.0 { c / y } else { c }
}

/// Two triangles that make one parallelogram, as (corner, edge_u, edge_v) with
/// `edge_u × edge_v` along their winding's normal. The corner is the first vertex of the
/// first triangle that starts a diagonal, so `[a b c] [a c d]` gives corner a, edges b − a
/// and d − a: the same quad the TOML format builds.
fn parallelogram(positions: &[Vec3], triangles: &[[u32; 3]]) -> Option<(Vec3, Vec3, Vec3)> {
    let [t0, t1] = triangles else { return None };
    if positions.len() != 4 {
        return None;
    }
    let p = |i: u32| positions[i as usize];
    // Turn t0 so its one corner not in t1 sits in the middle: x → y → z, then t1's own w.
    let k = (0..3).find(|&k| !t1.contains(&t0[(k + 1) % 3]))?;
    let (x, y, z) = (t0[k], t0[(k + 1) % 3], t0[(k + 2) % 3]);
    let w = *t1.iter().find(|i| !t0.contains(i))?;
    if !(t1.contains(&x) && t1.contains(&z)) {
        return None;
    }
    let (edge_u, edge_v) = (p(y) - p(x), p(w) - p(x));
    let size = edge_u.length().max(edge_v.length());
    let closes = (p(x) + edge_u + edge_v - p(z)).length() <= 1e-5 * size;
    // t1 must wind the same way as t0 (x → z → w).
    let same_winding = [x, z, w]
        .iter()
        .zip([z, w, x].iter())
        .all(|(a, b)| (0..3).any(|j| t1[j] == *a && t1[(j + 1) % 3] == *b));
    (closes && same_winding).then_some((p(x), edge_u, edge_v))
}
