//! The TOML format's BSDF materials (`plastic`, `uber`, `substrate`, `translucent`,
//! `conductor`, `rough_glass`, `thin_glass`, `coated_diffuse`, `coated_conductor`,
//! `diffuse_transmission`) as [`Model`]s: roughness given as the Trowbridge–Reitz α itself
//! (one number, or `[u, v]`), no remapping. Owns those tables' fields and defaults; must not
//! evaluate a BSDF.

use super::SceneError;
use super::document::Document;
use super::format::ColourSpec;
use super::metals::named_metal;
use crate::bsdf::{Model, ModelParameter};
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
    pub ks: Option<ColourSpec>,
    pub kr: Option<ColourSpec>,
    pub kt: Option<ColourSpec>,
    pub opacity: Option<ColourSpec>,
    pub reflect: Option<ColourSpec>,
    pub transmit: Option<ColourSpec>,
    pub transmittance: Option<ColourSpec>,
    pub reflect_tint: Option<ColourSpec>,
    pub transmit_tint: Option<ColourSpec>,
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

/// Reads a (possibly textured) colour field: its name, its value if given, its default, and
/// the model parameter a texture there gives.
pub(crate) type ColourReader<'a> =
    dyn FnMut(&str, Option<&ColourSpec>, f32, ModelParameter) -> Result<Vec3, SceneError> + 'a;

impl BsdfSpec {
    /// The colour field `name`, if given.
    fn colour_field(&self, name: &str) -> Option<&ColourSpec> {
        match name {
            "kd" => self.kd.as_ref(),
            "reflectance" => self.reflectance.as_ref(),
            "ks" => self.ks.as_ref(),
            "kr" => self.kr.as_ref(),
            "kt" => self.kt.as_ref(),
            "opacity" => self.opacity.as_ref(),
            "reflect" => self.reflect.as_ref(),
            "transmit" => self.transmit.as_ref(),
            "transmittance" => self.transmittance.as_ref(),
            "reflect_tint" => self.reflect_tint.as_ref(),
            "transmit_tint" => self.transmit_tint.as_ref(),
            _ => None,
        }
    }
}

/// The model of a material of type `kind`; `read` reads its colour fields (textured or not).
pub(crate) fn model(
    kind: &str,
    spec: &BsdfSpec,
    read: &mut ColourReader,
    refuse: &dyn Fn(&str, String) -> SceneError,
) -> Result<Model, SceneError> {
    use ModelParameter as P;
    let rgb = |c: Option<[f32; 3]>, default: f32| c.map_or(Vec3::splat(default), Vec3::from_array);
    let mut colour = |name: &str, default: f32, parameter: ModelParameter| {
        read(name, spec.colour_field(name), default, parameter)
    };
    let ior = spec.ior.unwrap_or(1.5);
    let (eta, k) = match kind {
        "conductor" | "coated_conductor" => conductor(
            spec,
            &mut |name, parameter| colour(name, 1.0, parameter),
            refuse,
        )?,
        _ => (Vec3::ONE, Vec3::ZERO),
    };
    Ok(match kind {
        "plastic" => Model::Plastic {
            kd: colour("kd", 0.25, P::Diffuse)?,
            ks: colour("ks", 0.25, P::Specular)?,
            alpha: Roughness::alpha(spec.roughness, 0.1),
        },
        "substrate" => Model::Substrate {
            kd: colour("kd", 0.5, P::Diffuse)?,
            ks: colour("ks", 0.5, P::Specular)?,
            alpha: Roughness::alpha(spec.roughness, 0.1),
        },
        "uber" => Model::Uber {
            kd: colour("kd", 0.25, P::Diffuse)?,
            ks: colour("ks", 0.25, P::Specular)?,
            kr: colour("kr", 0.0, P::Reflection)?,
            kt: colour("kt", 0.0, P::Transmission)?,
            alpha: Roughness::alpha(spec.roughness, 0.1),
            eta: ior,
            opacity: colour("opacity", 1.0, P::Opacity)?,
        },
        "translucent" => Model::Translucent {
            kd: colour("kd", 0.25, P::Diffuse)?,
            ks: colour("ks", 0.25, P::Specular)?,
            reflect: colour("reflect", 0.5, P::Reflect)?,
            transmit: colour("transmit", 0.5, P::Transmit)?,
            alpha: Roughness::alpha(spec.roughness, 0.1),
        },
        "conductor" => Model::Conductor {
            eta,
            k,
            alpha: Roughness::alpha(spec.roughness, 0.1),
        },
        "rough_glass" => Model::Dielectric {
            eta: ior,
            alpha: Roughness::alpha(spec.roughness, 0.1),
            reflect_tint: colour("reflect_tint", 1.0, P::Reflection)?,
            transmit_tint: colour("transmit_tint", 1.0, P::Transmission)?,
        },
        "thin_glass" => Model::ThinDielectric { eta: ior },
        "coated_diffuse" => Model::CoatedDiffuse {
            reflectance: colour("reflectance", 0.5, P::Diffuse)?,
            alpha: Roughness::alpha(spec.roughness, 0.0),
            eta: ior,
            thickness: spec.thickness.unwrap_or(0.01),
            albedo: rgb(spec.albedo, 0.0),
            g: spec.g.unwrap_or(0.0),
        },
        "coated_conductor" => Model::CoatedConductor {
            interface_alpha: Roughness::alpha(spec.interface_roughness, 0.0),
            interface_eta: ior,
            thickness: spec.thickness.unwrap_or(0.01),
            albedo: rgb(spec.albedo, 0.0),
            g: spec.g.unwrap_or(0.0),
            conductor_eta: eta,
            conductor_k: k,
            conductor_alpha: Roughness::alpha(spec.conductor_roughness, 0.0),
        },
        _ => Model::DiffuseTransmission {
            reflectance: colour("reflectance", 0.25, P::Diffuse)?,
            transmittance: colour("transmittance", 0.25, P::Transmit)?,
        },
    })
}

/// A conductor's (η, k): a named `metal`, a (possibly textured) normal-incidence
/// `reflectance` (η = 1, k = 2√r/√(1 − r)), `eta` and `k`, or copper.
fn conductor(
    spec: &BsdfSpec,
    reflectance: &mut dyn FnMut(&str, ModelParameter) -> Result<Vec3, SceneError>,
    refuse: &dyn Fn(&str, String) -> SceneError,
) -> Result<(Vec3, Vec3), SceneError> {
    let rgb = |c: Option<[f32; 3]>, default: f32| c.map_or(Vec3::splat(default), Vec3::from_array);
    if let Some(name) = &spec.metal {
        return named_metal(name).ok_or_else(|| {
            refuse(
                "metal",
                format!("`{name}` is not a metal dpm knows (Cu, Au, Ag, Al)"),
            )
        });
    }
    if spec.reflectance.is_some() {
        let r = reflectance("reflectance", ModelParameter::ConductorReflectance)?;
        let r = r.clamp(Vec3::ZERO, Vec3::splat(0.9999));
        return Ok((Vec3::ONE, 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5)));
    }
    match (spec.eta, spec.k) {
        (None, None) => Ok(named_metal("Cu").expect("copper is known")),
        (eta, k) => Ok((rgb(eta, 1.0), rgb(k, 0.0))),
    }
}
