//! The TOML format's BSDF materials (`plastic`, `uber`, `substrate`, `translucent`,
//! `conductor`, `rough_glass`, `thin_glass`, `coated_diffuse`, `coated_conductor`,
//! `diffuse_transmission`) as [`Model`]s: roughness given as the Trowbridge–Reitz α itself
//! (one number, or `[u, v]`), no remapping. Owns those tables' fields and defaults; must not
//! evaluate a BSDF.

use super::SceneError;
use super::document::Document;
use super::format::ColourSpec;
use super::metals::named_metal;
use crate::bsdf::Model;
use glam::{Vec2, Vec3};
use serde::Deserialize;

/// A roughness: one α, or α along u and v.
#[derive(Deserialize, Clone, Copy)]
#[serde(untagged)]
pub(crate) enum Roughness {
    Isotropic(f32),
    Anisotropic([f32; 2]),
}

impl Roughness {
    fn alpha(this: Option<Roughness>, default: f32) -> Vec2 {
        match this {
            None => Vec2::splat(default),
            Some(Roughness::Isotropic(a)) => Vec2::splat(a),
            Some(Roughness::Anisotropic([u, v])) => Vec2::new(u, v),
        }
    }
}

/// Every field any BSDF type has; [`read`] lets each type have its own only.
#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub(crate) struct BsdfSpec {
    pub kd: Option<ColourSpec>,
    pub reflectance: Option<ColourSpec>,
    pub ks: Option<[f32; 3]>,
    pub kr: Option<[f32; 3]>,
    pub kt: Option<[f32; 3]>,
    pub opacity: Option<[f32; 3]>,
    pub reflect: Option<[f32; 3]>,
    pub transmit: Option<[f32; 3]>,
    pub transmittance: Option<[f32; 3]>,
    pub reflect_tint: Option<[f32; 3]>,
    pub transmit_tint: Option<[f32; 3]>,
    pub albedo: Option<[f32; 3]>,
    pub roughness: Option<Roughness>,
    pub interface_roughness: Option<Roughness>,
    pub conductor_roughness: Option<Roughness>,
    pub ior: Option<f32>,
    pub eta: Option<[f32; 3]>,
    pub k: Option<[f32; 3]>,
    pub metal: Option<String>,
    pub thickness: Option<f32>,
    pub g: Option<f32>,
}

/// The fields each type takes, besides `type`.
fn fields_of(kind: &str) -> &'static [&'static str] {
    match kind {
        "plastic" | "substrate" => &["kd", "ks", "roughness"],
        "uber" => &["kd", "ks", "kr", "kt", "opacity", "roughness", "ior"],
        "translucent" => &["kd", "ks", "reflect", "transmit", "roughness"],
        "conductor" => &["metal", "eta", "k", "reflectance", "roughness"],
        "rough_glass" => &["ior", "roughness", "reflect_tint", "transmit_tint"],
        "thin_glass" => &["ior"],
        "coated_diffuse" => &[
            "reflectance",
            "roughness",
            "ior",
            "thickness",
            "albedo",
            "g",
        ],
        "coated_conductor" => &[
            "interface_roughness",
            "ior",
            "thickness",
            "albedo",
            "g",
            "metal",
            "eta",
            "k",
            "reflectance",
            "conductor_roughness",
        ],
        _ => &["reflectance", "transmittance"],
    }
}

/// Refuses a field that type `kind` does not take, naming it and the ones it does.
pub(crate) fn check_fields(
    doc: &Document,
    path: &str,
    kind: &str,
    given: impl Iterator<Item = String>,
) -> Result<(), SceneError> {
    let allowed = fields_of(kind);
    for field in given {
        if field != "type" && !allowed.contains(&field.as_str()) {
            return Err(doc.error(
                &format!("{path}.{field}"),
                format!(
                    "unknown field for a `{kind}` material (it takes {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    Ok(())
}

/// The model of a material of type `kind`; `colour` reads the (possibly textured) diffuse
/// colour `kd` or `reflectance`, with its default.
/// Reads a (possibly textured) colour field with its default.
pub(crate) type ColourReader<'a> =
    dyn FnMut(&str, Option<&ColourSpec>, f32) -> Result<Vec3, SceneError> + 'a;

pub(crate) fn model(
    kind: &str,
    spec: &BsdfSpec,
    colour: &mut ColourReader,
    refuse: &dyn Fn(&str, String) -> SceneError,
) -> Result<Model, SceneError> {
    let rgb = |c: Option<[f32; 3]>, default: f32| c.map_or(Vec3::splat(default), Vec3::from_array);
    let mut diffuse = |name: &str, default: f32| {
        let given = if name == "kd" {
            spec.kd.as_ref()
        } else {
            spec.reflectance.as_ref()
        };
        colour(name, given, default)
    };
    let ior = spec.ior.unwrap_or(1.5);
    let conductor = |spec: &BsdfSpec| -> Result<(Vec3, Vec3), SceneError> {
        if let Some(name) = &spec.metal {
            return named_metal(name).ok_or_else(|| {
                refuse(
                    "metal",
                    format!("`{name}` is not a metal dpm knows (Cu, Au, Ag, Al)"),
                )
            });
        }
        if let Some(Some(r)) = spec.reflectance.as_ref().map(|c| match c {
            ColourSpec::Rgb(rgb) => Some(Vec3::from_array(*rgb)),
            ColourSpec::Texture(_) => None,
        }) {
            let r = r.clamp(Vec3::ZERO, Vec3::splat(0.9999));
            return Ok((Vec3::ONE, 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5)));
        }
        match (spec.eta, spec.k) {
            (None, None) => Ok(named_metal("Cu").expect("copper is known")),
            (eta, k) => Ok((rgb(eta, 1.0), rgb(k, 0.0))),
        }
    };
    Ok(match kind {
        "plastic" => Model::Plastic {
            kd: diffuse("kd", 0.25)?,
            ks: rgb(spec.ks, 0.25),
            alpha: Roughness::alpha(spec.roughness, 0.1),
        },
        "substrate" => Model::Substrate {
            kd: diffuse("kd", 0.5)?,
            ks: rgb(spec.ks, 0.5),
            alpha: Roughness::alpha(spec.roughness, 0.1),
        },
        "uber" => Model::Uber {
            kd: diffuse("kd", 0.25)?,
            ks: rgb(spec.ks, 0.25),
            kr: rgb(spec.kr, 0.0),
            kt: rgb(spec.kt, 0.0),
            alpha: Roughness::alpha(spec.roughness, 0.1),
            eta: ior,
            opacity: rgb(spec.opacity, 1.0),
        },
        "translucent" => Model::Translucent {
            kd: diffuse("kd", 0.25)?,
            ks: rgb(spec.ks, 0.25),
            reflect: rgb(spec.reflect, 0.5),
            transmit: rgb(spec.transmit, 0.5),
            alpha: Roughness::alpha(spec.roughness, 0.1),
        },
        "conductor" => {
            let (eta, k) = conductor(spec)?;
            Model::Conductor {
                eta,
                k,
                alpha: Roughness::alpha(spec.roughness, 0.1),
            }
        }
        "rough_glass" => Model::Dielectric {
            eta: ior,
            alpha: Roughness::alpha(spec.roughness, 0.1),
            reflect_tint: rgb(spec.reflect_tint, 1.0),
            transmit_tint: rgb(spec.transmit_tint, 1.0),
        },
        "thin_glass" => Model::ThinDielectric { eta: ior },
        "coated_diffuse" => Model::CoatedDiffuse {
            reflectance: diffuse("reflectance", 0.5)?,
            alpha: Roughness::alpha(spec.roughness, 0.0),
            eta: ior,
            thickness: spec.thickness.unwrap_or(0.01),
            albedo: rgb(spec.albedo, 0.0),
            g: spec.g.unwrap_or(0.0),
        },
        "coated_conductor" => {
            let (conductor_eta, conductor_k) = conductor(spec)?;
            Model::CoatedConductor {
                interface_alpha: Roughness::alpha(spec.interface_roughness, 0.0),
                interface_eta: ior,
                thickness: spec.thickness.unwrap_or(0.01),
                albedo: rgb(spec.albedo, 0.0),
                g: spec.g.unwrap_or(0.0),
                conductor_eta,
                conductor_k,
                conductor_alpha: Roughness::alpha(spec.conductor_roughness, 0.0),
            }
        }
        _ => Model::DiffuseTransmission {
            reflectance: diffuse("reflectance", 0.25)?,
            transmittance: rgb(spec.transmittance, 0.25),
        },
    })
}
