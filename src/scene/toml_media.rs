//! Participating media in the TOML format (docs/scene-format.md, `[media.NAME]`): each
//! medium's table, and the `medium`, `inside` and `outside` names that the camera, the lights
//! and the objects carry, taken out of their tables before those are read (so the rest of the
//! format knows nothing of media). Owns that reading and its checks, each error naming its
//! field; must not build media for rendering.

use super::document::{Document, Value, child_path};
use super::{Medium, MediumKind};
use super::{MediumId, MediumInterface, SceneError};
use glam::{Mat4, Vec3};
use serde::Deserialize;
use toml::de::DeValue;

const MEDIUM_TYPES: [&str; 2] = ["homogeneous", "grid"];

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct HomogeneousSpec {
    sigma_a: [f32; 3],
    sigma_s: [f32; 3],
    #[serde(default)]
    g: f32,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GridSpec {
    sigma_a: [f32; 3],
    sigma_s: [f32; 3],
    #[serde(default)]
    g: f32,
    size: [u32; 3],
    density: Vec<f32>,
    #[serde(default)]
    p0: [f32; 3],
    #[serde(default = "unit")]
    p1: [f32; 3],
}

fn unit() -> [f32; 3] {
    [1.0; 3]
}

/// The `[media.NAME]` tables, in name order; empty when there are none.
pub(crate) fn read_media(doc: &Document) -> Result<Vec<Medium>, SceneError> {
    let Some(value) = doc.root().get("media") else {
        return Ok(Vec::new());
    };
    let DeValue::Table(table) = value.get_ref() else {
        return Err(doc.error("media", "expected a table of named media"));
    };
    let mut media = Vec::new();
    for (name, value) in table.iter() {
        let name = name.get_ref().to_string();
        let path = child_path("media", &name);
        let (kind, fields) = doc.tagged(&path, value, &MEDIUM_TYPES)?;
        let field = |f: &str| child_path(&path, f);
        let (g, kind) = match kind {
            "homogeneous" => {
                let spec: HomogeneousSpec = doc.deserialize(&fields)?;
                let (sigma_a, sigma_s) = coefficients(doc, &path, spec.sigma_a, spec.sigma_s)?;
                (spec.g, MediumKind::Homogeneous { sigma_a, sigma_s })
            }
            _ => {
                let spec: GridSpec = doc.deserialize(&fields)?;
                let (sigma_a, sigma_s) = coefficients(doc, &path, spec.sigma_a, spec.sigma_s)?;
                let sigma_t = sigma_a + sigma_s;
                if sigma_t.max_element() - sigma_t.min_element() > 1e-6 * sigma_t.max_element() {
                    return Err(doc.error(
                        &field("sigma_a"),
                        "a grid's sigma_a + sigma_s must be the same in every channel",
                    ));
                }
                let count = spec.size.iter().map(|&n| n as usize).product::<usize>();
                if count == 0 || spec.density.len() != count {
                    return Err(doc.error(
                        &field("density"),
                        format!(
                            "{} values for a {}×{}×{} grid (x fastest, then y, then z)",
                            spec.density.len(),
                            spec.size[0],
                            spec.size[1],
                            spec.size[2]
                        ),
                    ));
                }
                if let Some(i) = spec
                    .density
                    .iter()
                    .position(|d| !(d.is_finite() && *d >= 0.0))
                {
                    return Err(doc.error(
                        &field("density"),
                        format!(
                            "value {i} is {}: densities are finite and not negative",
                            spec.density[i]
                        ),
                    ));
                }
                let (p0, p1) = (Vec3::from_array(spec.p0), Vec3::from_array(spec.p1));
                if !(p0.is_finite() && p1.is_finite() && (p1 - p0).min_element() > 0.0) {
                    return Err(doc.error(&field("p1"), "p1 must lie beyond p0 on every axis"));
                }
                let grid_to_world = Mat4::from_translation(p0) * Mat4::from_scale(p1 - p0);
                (
                    spec.g,
                    MediumKind::Grid {
                        sigma_a,
                        sigma_s,
                        size: spec.size,
                        density: spec.density,
                        grid_to_world,
                    },
                )
            }
        };
        if g.is_nan() || g.abs() >= 1.0 {
            return Err(doc.error(&field("g"), format!("{g}: the asymmetry g lies in (−1, 1)")));
        }
        media.push(Medium {
            name,
            defined_at: doc.place(&path),
            g,
            bounded_by: 0,
            subsurface: false,
            kind,
        });
    }
    Ok(media)
}

fn coefficients(
    doc: &Document,
    path: &str,
    sigma_a: [f32; 3],
    sigma_s: [f32; 3],
) -> Result<(Vec3, Vec3), SceneError> {
    for (name, v) in [("sigma_a", sigma_a), ("sigma_s", sigma_s)] {
        if v.iter().any(|c| !(c.is_finite() && *c >= 0.0)) {
            return Err(doc.error(
                &child_path(path, name),
                format!("{v:?}: coefficients are finite and not negative"),
            ));
        }
    }
    Ok((Vec3::from_array(sigma_a), Vec3::from_array(sigma_s)))
}

/// `value` (a table) without its string field `key`, and that string if it was there.
pub(crate) fn take_name<'t>(
    doc: &Document<'t>,
    path: &str,
    value: &Value<'t>,
    key: &str,
) -> Result<(Value<'t>, Option<String>), SceneError> {
    let DeValue::Table(table) = value.get_ref() else {
        return Ok((value.clone(), None));
    };
    let Some(found) = table.get(key) else {
        return Ok((value.clone(), None));
    };
    let Some(name) = found.get_ref().as_str() else {
        return Err(doc.error(
            &child_path(path, key),
            "expected the name of a medium (a string)",
        ));
    };
    let name = name.to_string();
    let mut rest = table.clone();
    rest.remove(key);
    Ok((
        toml::Spanned::new(value.span(), DeValue::Table(rest)),
        Some(name),
    ))
}

/// The medium `name` at field `path` names: `None` for "" (vacuum).
pub(crate) fn resolve(
    doc: &Document,
    path: &str,
    name: Option<&str>,
    media: &[Medium],
) -> Result<Option<MediumId>, SceneError> {
    match name {
        None | Some("") => Ok(None),
        Some(name) => match media.iter().position(|m| m.name == name) {
            Some(i) => Ok(Some(i as MediumId)),
            None => {
                let known: Vec<&str> = media.iter().map(|m| m.name.as_str()).collect();
                Err(doc.error(
                    path,
                    format!(
                        "unknown medium `{name}` (defined: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ),
                ))
            }
        },
    }
}

/// An object's `inside` and `outside` media.
pub(crate) fn interface(
    doc: &Document,
    path: &str,
    (inside, outside): (Option<&str>, Option<&str>),
    media: &[Medium],
) -> Result<MediumInterface, SceneError> {
    Ok(MediumInterface {
        inside: resolve(doc, &child_path(path, "inside"), inside, media)?,
        outside: resolve(doc, &child_path(path, "outside"), outside, media)?,
    })
}
