//! pbrt's `MakeNamedMedium` as dpm reads it: a `homogeneous` medium and a density grid
//! (pbrt-v3's `heterogeneous`, pbrt-v4's `uniformgrid`), with each version's defaults (pbrt-v3
//! starts from whole milk's coefficients, pbrt-v4 from σa = σs = 1), a `preset` of measured
//! media (which `sigma_a` and `sigma_s` override in pbrt-v3 and do not in pbrt-v4), `scale`
//! multiplying both,
//! `g` the Henyey–Greenstein asymmetry, a grid placed by the transform in force times
//! Translate(p0) · Scale(p1 − p0). Bad values exit 2 naming their field. Owns that reading;
//! must not build media for rendering.

use super::super::parser::{Item, MediumItem, ShapeItem};
use super::{Mapper, param_error, value_error};
use crate::scene::pbrt::Dialect;
use crate::scene::{Medium, MediumId, MediumInterface, MediumKind, SceneError, Shape};
use glam::{Mat4, Vec3};

/// pbrt-v3's default coefficients (whole milk, per mm, Jensen et al. 2001).
const WHOLE_MILK_SIGMA_A: Vec3 = Vec3::new(0.0011, 0.0024, 0.014);
const WHOLE_MILK_SIGMA_S: Vec3 = Vec3::new(2.55, 3.21, 3.77);

impl Mapper<'_> {
    /// The medium `medium` defines, or `None` (with a warning) for a type dpm does not read.
    pub(super) fn medium(&mut self, medium: &MediumItem) -> Result<Option<Medium>, SceneError> {
        let item = &medium.item;
        let directive = "MakeNamedMedium";
        let p = |e| param_error(directive, e);
        let grid = match item.kind.as_str() {
            "homogeneous" => false,
            "heterogeneous" | "uniformgrid" => true,
            "nanovdb" => {
                return Err(item.at.error(
                    directive,
                    format!("\"{}\": nanovdb media are not supported", medium.name),
                ));
            }
            other => {
                self.warn(
                    &item.at,
                    format!(
                        "{directive} \"{}\": type \"{other}\" is not read",
                        medium.name
                    ),
                );
                return Ok(None);
            }
        };
        let (mut sigma_a, mut sigma_s) = match self.dialect.0 {
            Dialect::V3 => (WHOLE_MILK_SIGMA_A, WHOLE_MILK_SIGMA_S),
            Dialect::V4 => (Vec3::ONE, Vec3::ONE),
        };
        // pbrt-v3: a preset replaces the defaults and sigma_a, sigma_s override it; pbrt-v4:
        // a preset wins.
        let mut preset_wins = false;
        if let Some(name) = item.params.string("preset").map_err(p)? {
            match super::media_presets::preset(&name) {
                Some((a, s)) => {
                    (sigma_a, sigma_s) = (a, s);
                    preset_wins = self.dialect.0 == Dialect::V4;
                }
                None => self.warn(
                    &item.at,
                    format!("{directive} \"{}\": no preset is named \"{name}\"; the defaults apply, as pbrt-v3 does", medium.name),
                ),
            }
        }
        for (name, value) in [("sigma_a", &mut sigma_a), ("sigma_s", &mut sigma_s)] {
            if preset_wins {
                item.params.mark_used(name);
                continue;
            }
            if let Some(v) = item.params.colour(name).map_err(p)? {
                if !v.is_finite() || v.min_element() < 0.0 {
                    return Err(value_error(
                        item,
                        directive,
                        name,
                        format!("{v} must be finite and not negative"),
                    ));
                }
                *value = v;
            }
        }
        let scale = item.params.float("scale").map_err(p)?.unwrap_or(1.0);
        if !scale.is_finite() || scale < 0.0 {
            return Err(value_error(
                item,
                directive,
                "scale",
                format!("{scale} must be finite and not negative"),
            ));
        }
        let g = asymmetry(item, directive)?;
        let (sigma_a, sigma_s) = (sigma_a * scale, sigma_s * scale);
        let kind = if grid {
            self.density_grid(medium, sigma_a, sigma_s)?
        } else {
            MediumKind::Homogeneous { sigma_a, sigma_s }
        };
        self.unused(item, directive);
        Ok(Some(Medium {
            name: medium.name.clone(),
            defined_at: item.at.to_string(),
            g,
            bounded_by: 0,
            subsurface: false,
            kind,
        }))
    }

    fn density_grid(
        &mut self,
        medium: &MediumItem,
        sigma_a: Vec3,
        sigma_s: Vec3,
    ) -> Result<MediumKind, SceneError> {
        let item = &medium.item;
        let directive = "MakeNamedMedium";
        let p = |e| param_error(directive, e);
        let mut size = [1u32; 3];
        for (axis, name) in ["nx", "ny", "nz"].into_iter().enumerate() {
            if let Some(n) = item.params.integer(name).map_err(p)? {
                if !(1..=1 << 16).contains(&n) {
                    return Err(value_error(
                        item,
                        directive,
                        name,
                        format!("{n} is not from 1 to 65536"),
                    ));
                }
                size[axis] = n as u32;
            }
        }
        let count = size.iter().map(|&n| n as u64).product::<u64>();
        let density = item.params.floats("density").map_err(p)?.ok_or_else(|| {
            item.at.error(
                directive,
                format!("\"{}\": a grid medium needs \"float density\"", medium.name),
            )
        })?;
        if density.len() as u64 != count {
            return Err(value_error(
                item,
                directive,
                "density",
                format!(
                    "{} values for a {}×{}×{} grid ({count})",
                    density.len(),
                    size[0],
                    size[1],
                    size[2]
                ),
            ));
        }
        if let Some(i) = density.iter().position(|d| !d.is_finite() || *d < 0.0) {
            return Err(value_error(
                item,
                directive,
                "density",
                format!("value {i} ({}) must be finite and not negative", density[i]),
            ));
        }
        let p0 = item.params.vec3("p0").map_err(p)?.unwrap_or(Vec3::ZERO);
        let p1 = item.params.vec3("p1").map_err(p)?.unwrap_or(Vec3::ONE);
        if !(p0.is_finite() && p1.is_finite() && (p1 - p0).min_element() > 0.0) {
            return Err(value_error(
                item,
                directive,
                "p1",
                format!("the box {p0} to {p1} is empty"),
            ));
        }
        if item.kind == "heterogeneous" {
            let sigma_t = sigma_a + sigma_s;
            if sigma_t.max_element() - sigma_t.min_element() > 1e-6 * sigma_t.max_element() {
                return Err(value_error(
                    item,
                    directive,
                    "sigma_s",
                    format!(
                        "σa + σs = {sigma_t} differs between channels, which pbrt-v3's heterogeneous medium refuses"
                    ),
                ));
            }
        }
        let grid_to_world = medium.ctm * Mat4::from_translation(p0) * Mat4::from_scale(p1 - p0);
        Ok(MediumKind::Grid {
            sigma_a,
            sigma_s,
            size,
            density,
            grid_to_world,
        })
    }
}

/// The Henyey–Greenstein `g` of `item` (default 0), refused outside (−1, 1).
pub(super) fn asymmetry(item: &Item, directive: &str) -> Result<f32, SceneError> {
    let g = (item.params.float("g")).map_err(|e| param_error(directive, e))?;
    let g = g.unwrap_or(0.0);
    if g.is_nan() || g.abs() >= 1.0 {
        return Err(value_error(
            item,
            directive,
            "g",
            format!("{g} is not between −1 and 1"),
        ));
    }
    Ok(g)
}

/// The medium called `name` among those read (`None` for "" or a medium not read).
pub(super) fn named(name: &str, media: &[Medium]) -> Option<MediumId> {
    if name.is_empty() {
        return None;
    }
    (media.iter().position(|m| m.name == name)).map(|i| i as MediumId)
}

/// The `MediumInterface` in force at `shape`, as pbrt orients it: outside where the
/// geometric normal points.
pub(super) fn interface_of(shape: &ShapeItem, media: &[Medium]) -> MediumInterface {
    MediumInterface {
        inside: named(&shape.media.0, media),
        outside: named(&shape.media.1, media),
    }
}

/// `interface` for `placed`, one of the shapes `item` made: a sphere keeps its normal
/// outward whatever pbrt's `ReverseOrientation` and a mirroring transform say (a mesh's
/// winding follows them), so there its sides are swapped where pbrt's normal points in.
pub(super) fn oriented(
    interface: MediumInterface,
    placed: &Shape,
    item: &ShapeItem,
) -> MediumInterface {
    let mirrored = glam::Mat3::from_mat4(item.ctm).determinant() < 0.0;
    match placed {
        Shape::Sphere { .. } if item.reverse_orientation ^ mirrored => MediumInterface {
            inside: interface.outside,
            outside: interface.inside,
        },
        _ => interface,
    }
}
