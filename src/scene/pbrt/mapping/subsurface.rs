//! pbrt's `subsurface` and `kdsubsurface` materials as dpm renders them: the material's
//! dielectric boundary (`eta`, default 1.33; `Kr`, `Kt`; `uroughness`/`vroughness`) becomes
//! glass ([`super::materials`]), and what pbrt's tabulated BSSRDF approximates, the light
//! scattered under the surface, becomes a homogeneous medium inside every shape that wears it,
//! walked by photons like any other medium (`Medium::subsurface` keeps its events out of the
//! bounce count). `subsurface` reads pbrt-v3's whole-milk defaults, a `name` from the measured
//! table (whose σ′s it takes as σs, and then `g` = 0, as pbrt-v3 enforces), `sigma_a`,
//! `sigma_s`, and `scale` multiplying both. `kdsubsurface` turns `Kd`, the diffuse reflectance
//! seen from outside, and `mfp` (times `scale`) into σs and σa by inverting the diffuse
//! reflectance of the classical dipole (Jensen et al. 2001) where pbrt-v3 inverts its photon
//! beam diffusion table. Owns that reading; must not build media for rendering.

use super::super::parser::Item;
use super::media_presets::preset;
use super::{Mapper, param_error, value_error};
use crate::scene::dipole::dipole_albedo;
use crate::scene::{Medium, MediumKind, SceneError};
use glam::Vec3;

/// pbrt-v3's default coefficients of `subsurface` (whole milk, per mm).
const SIGMA_A: Vec3 = Vec3::new(0.0011, 0.0024, 0.014);
const SIGMA_S: Vec3 = Vec3::new(2.55, 3.21, 3.77);

/// Whether a pbrt material kind scatters under its surface.
pub(super) fn is_subsurface(kind: &str) -> bool {
    matches!(kind, "subsurface" | "kdsubsurface")
}

/// The parameters the medium takes (the material reads the rest).
pub(super) const MEDIUM_PARAMETERS: &[&str] =
    &["name", "sigma_a", "sigma_s", "scale", "g", "mfp", "Kd"];

impl Mapper<'_> {
    /// The medium under the surface of the material `item` (`subsurface`/`kdsubsurface`),
    /// named by its kind and measured medium.
    pub(super) fn subsurface_medium(&mut self, item: &Item) -> Result<Medium, SceneError> {
        let name = match item.params.string("name").ok().flatten() {
            Some(measured) => format!("{} \"{measured}\"", item.kind),
            None => item.kind.clone(),
        };
        let directive = "Material";
        let p = |e| param_error(directive, e);
        let colour = |field: &str| -> Result<Option<Vec3>, SceneError> {
            if item.params.texture(field).map_err(p)?.is_some() {
                return Err(item.at.error(
                    directive,
                    format!("\"{field}\" given by a texture would vary the medium under the surface, which dpm's homogeneous media cannot; give a colour"),
                ));
            }
            let v = item.params.colour(field).map_err(p)?;
            match v {
                Some(v) if !v.is_finite() || v.min_element() < 0.0 => Err(value_error(
                    item,
                    directive,
                    field,
                    format!("{v} must be finite and not negative"),
                )),
                v => Ok(v),
            }
        };
        let scale = item.params.float("scale").map_err(p)?.unwrap_or(1.0);
        if !scale.is_finite() || scale <= 0.0 {
            return Err(value_error(
                item,
                directive,
                "scale",
                format!("{scale} must be positive"),
            ));
        }
        let mut g = super::media::asymmetry(item, directive)?;
        let (sigma_a, sigma_s) = if item.kind == "kdsubsurface" {
            let eta = item.params.float("eta").map_err(p)?.unwrap_or(1.33);
            let kd = colour("Kd")?.unwrap_or(Vec3::splat(0.5));
            let mfp = colour("mfp")?.unwrap_or(Vec3::ONE) * scale;
            if mfp.min_element() <= 0.0 {
                return Err(value_error(
                    item,
                    directive,
                    "mfp",
                    format!("{mfp} must be positive"),
                ));
            }
            let albedo = Vec3::from_array(kd.to_array().map(|r| dipole_albedo(r, eta)));
            ((Vec3::ONE - albedo) / mfp, albedo / mfp)
        } else {
            let (mut a, mut s) = (SIGMA_A, SIGMA_S);
            if let Some(preset_name) = item.params.string("name").map_err(p)?
                && !preset_name.is_empty()
            {
                match preset(&preset_name) {
                    Some(found) => {
                        (a, s) = found;
                        g = 0.0;
                    }
                    None => self.warn(
                        &item.at,
                        format!("Material \"subsurface\": no measured medium is named \"{preset_name}\"; whole milk's coefficients apply, as pbrt-v3 does"),
                    ),
                }
            }
            (
                colour("sigma_a")?.unwrap_or(a) * scale,
                colour("sigma_s")?.unwrap_or(s) * scale,
            )
        };
        Ok(Medium {
            name,
            defined_at: item.at.to_string(),
            g,
            bounded_by: 0,
            subsurface: true,
            kind: MediumKind::Homogeneous { sigma_a, sigma_s },
        })
    }
}
