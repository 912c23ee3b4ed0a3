//! pbrt's materials beyond diffuse, mirror and smooth glass as [`Model`]s: pbrt-v3's `plastic`,
//! `uber`, `substrate`, `translucent`, rough `metal` and `glass`; pbrt-v4's rough `conductor`
//! and `dielectric`, `thindielectric`, `coateddiffuse`, `coatedconductor` and
//! `diffusetransmission`, with each dialect's defaults and roughness mapping (`remaproughness`:
//! pbrt-v3's polynomial in ln r, pbrt-v4's √r). Owns those parameter tables; must not evaluate
//! a BSDF.

use super::super::Place;
use super::super::params::ParamList;
use super::{Mapper, param_error};
use crate::bsdf::{Model, Remap};
use crate::scene::SceneError;
use glam::{Vec2, Vec3};

/// How a material's colours and floats are read (textures become their typical values,
/// recorded by the caller).
pub(super) struct Readers<'a> {
    /// A colour in [0, 1], with its default.
    pub colour: &'a dyn Fn(&str, f32) -> Result<Vec3, SceneError>,
    /// A colour that is no reflectance (a conductor's η and k): unclamped, and a float texture
    /// may give it.
    pub unbounded: &'a dyn Fn(&str, f32) -> Result<Vec3, SceneError>,
    pub float: &'a dyn Fn(&str) -> Result<Option<f32>, SceneError>,
    /// An index of refraction: as `float`, a texture's typical value at least 1.
    pub index: &'a dyn Fn(&str) -> Result<Option<f32>, SceneError>,
}

/// How material `kind` turns its roughness into α: pbrt-v4's materials by √r, pbrt-v3's by
/// its polynomial, either not at all when `remaproughness` is false.
pub(super) fn remap(params: &ParamList, kind: &str) -> Result<Remap, SceneError> {
    let remap = (params.bool("remaproughness"))
        .map_err(|e| param_error("Material", e))?
        .unwrap_or(true);
    let v4 = matches!(
        kind,
        "conductor" | "dielectric" | "coateddiffuse" | "coatedconductor"
    );
    Ok(match (remap, v4) {
        (false, _) => Remap::None,
        (true, true) => Remap::PbrtV4,
        (true, false) => Remap::PbrtV3,
    })
}

/// Whether `kind` is one of the materials mapped here (rough metals and glass are asked about
/// by their caller, which knows the roughness).
pub(super) fn is_glossy_kind(kind: &str) -> bool {
    matches!(
        kind,
        "plastic"
            | "uber"
            | "substrate"
            | "translucent"
            | "thindielectric"
            | "coateddiffuse"
            | "coatedconductor"
            | "diffusetransmission"
    )
}

impl Mapper<'_> {
    /// The model of material `kind` (see [`is_glossy_kind`]; also rough `metal`, `conductor`,
    /// `glass` and `dielectric`, whose index `eta` the caller has read).
    pub(super) fn glossy_model(
        &self,
        kind: &str,
        params: &ParamList,
        at: &Place,
        read: &Readers,
        eta: f32,
    ) -> Result<Model, SceneError> {
        let colour = read.colour;
        let alpha = |iso: &str, default: f32| self.alpha(params, read, iso, default, kind);
        Ok(match kind {
            "plastic" => Model::Plastic {
                kd: colour("Kd", 0.25)?,
                ks: colour("Ks", 0.25)?,
                alpha: alpha("roughness", 0.1)?,
            },
            "uber" => Model::Uber {
                kd: colour("Kd", 0.25)?,
                ks: colour("Ks", 0.25)?,
                kr: colour("Kr", 0.0)?,
                kt: colour("Kt", 0.0)?,
                alpha: alpha("roughness", 0.1)?,
                eta: (read.index)("index")?
                    .or((read.index)("eta")?)
                    .unwrap_or(1.5),
                opacity: colour("opacity", 1.0)?,
            },
            "substrate" => Model::Substrate {
                kd: colour("Kd", 0.5)?,
                ks: colour("Ks", 0.5)?,
                alpha: alpha("roughness", 0.1)?,
            },
            "translucent" => Model::Translucent {
                kd: colour("Kd", 0.25)?,
                ks: colour("Ks", 0.25)?,
                reflect: colour("reflect", 0.5)?,
                transmit: colour("transmit", 0.5)?,
                alpha: alpha("roughness", 0.1)?,
            },
            "metal" | "conductor" => {
                let (eta, k) = self.conductor_eta_k(params, at, read, "")?;
                let default = if kind == "metal" { 0.01 } else { 0.0 };
                Model::Conductor {
                    eta,
                    k,
                    alpha: alpha("roughness", default)?,
                }
            }
            "glass" | "dielectric" => Model::Dielectric {
                eta,
                alpha: alpha("roughness", 0.0)?,
                reflect_tint: colour("Kr", 1.0)?,
                transmit_tint: colour("Kt", 1.0)?,
            },
            "thindielectric" => Model::ThinDielectric { eta },
            "coateddiffuse" => Model::CoatedDiffuse {
                reflectance: colour("reflectance", 0.5)?,
                alpha: alpha("roughness", 0.0)?,
                eta,
                thickness: (read.float)("thickness")?.unwrap_or(0.01),
                albedo: colour("albedo", 0.0)?,
                g: (read.float)("g")?.unwrap_or(0.0),
            },
            "coatedconductor" => {
                let (conductor_eta, conductor_k) =
                    self.conductor_eta_k(params, at, read, "conductor.")?;
                Model::CoatedConductor {
                    interface_alpha: alpha("interface.roughness", 0.0)?,
                    interface_eta: (read.index)("interface.eta")?.unwrap_or(1.5),
                    thickness: (read.float)("thickness")?.unwrap_or(0.01),
                    albedo: colour("albedo", 0.0)?,
                    g: (read.float)("g")?.unwrap_or(0.0),
                    conductor_eta,
                    conductor_k,
                    conductor_alpha: alpha("conductor.roughness", 0.0)?,
                }
            }
            "diffusetransmission" => {
                let scale = (read.float)("scale")?.unwrap_or(1.0);
                Model::DiffuseTransmission {
                    reflectance: (scale * colour("reflectance", 0.25)?).min(Vec3::ONE),
                    transmittance: (scale * colour("transmittance", 0.25)?).min(Vec3::ONE),
                }
            }
            other => unreachable!("{other} is not a glossy material"),
        })
    }

    /// The Trowbridge–Reitz α along u and v of a material whose isotropic roughness is named
    /// `iso` (`uroughness`/`vroughness`, with the same prefix, take precedence), `default`
    /// when absent; mapped as the material's dialect maps it unless `remaproughness` is false.
    /// A roughness of 0 stays 0: smooth.
    fn alpha(
        &self,
        params: &ParamList,
        read: &Readers,
        iso: &str,
        default: f32,
        kind: &str,
    ) -> Result<Vec2, SceneError> {
        let prefix = iso.strip_suffix("roughness").unwrap_or("");
        let isotropic = (read.float)(iso)?;
        let u = (read.float)(&format!("{prefix}uroughness"))?
            .or(isotropic)
            .unwrap_or(default);
        let v = (read.float)(&format!("{prefix}vroughness"))?
            .or(isotropic)
            .unwrap_or(default);
        let remap = remap(params, kind)?;
        Ok(Vec2::new(remap.alpha(u), remap.alpha(v)))
    }
}
