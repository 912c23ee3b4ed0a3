//! pbrt's materials as dpm's three: `matte`/`diffuse` → diffuse, `mirror` and smooth
//! `conductor`/`metal` → mirror (tinted by their reflectance), `glass`/`dielectric` →
//! glass. Materials with more lobes than dpm has (`uber`, `plastic`, `substrate`,
//! `coateddiffuse`, rough metals) become their diffuse part with one warning, or an error
//! under `--strict`. A colour or index given as a texture ([`super::textures`]) becomes a
//! textured parameter of the material. Owns that table; must not read files.

use super::super::Place;
use super::super::params::ParamList;
use super::textures::TextureType;
use super::{Mapper, param_error};
use crate::scene::{Material, SceneError, Texture, TexturedParameter};
use glam::Vec3;
use std::cell::RefCell;

/// Refractive indices at the d line (587.6 nm) of the named glasses pbrt-v4 ships, from
/// Schott's catalogue.
const NAMED_GLASSES: &[(&str, f32)] = &[
    ("glass-BK7", 1.5168),
    ("glass-BAF10", 1.6700),
    ("glass-FK51A", 1.4866),
    ("glass-LASF9", 1.8503),
];

/// What a pbrt material became.
pub(super) struct Mapped {
    pub material: Material,
    /// Why this is an approximation, when it is one.
    pub approximation: Option<String>,
    /// The parameters of `material` that textures give (`material` holds their typical
    /// values).
    pub textures: Vec<(TexturedParameter, Texture)>,
}

impl Mapper<'_> {
    pub(super) fn material(
        &mut self,
        kind: &str,
        params: &ParamList,
        at: &Place,
    ) -> Result<Mapped, SceneError> {
        let p = |e| param_error("Material", e);
        // The textures read, by parameter name; the material takes their typical values.
        let textured = RefCell::new(Vec::<(String, Texture)>::new());
        let colour = |name: &str, default: f32| -> Result<Vec3, SceneError> {
            match self.parameter_if_given(params, "Material", name, TextureType::Colour)? {
                None => Ok(Vec3::splat(default)),
                Some(Texture::Constant(c)) => Ok(c),
                Some(t) => {
                    let typical = t.typical().clamp(Vec3::ZERO, Vec3::ONE);
                    textured.borrow_mut().push((name.to_string(), t));
                    Ok(typical)
                }
            }
        };
        // An index of refraction, which a float texture may give.
        let index = |name: &str| -> Result<Option<f32>, SceneError> {
            match self.parameter_if_given(params, "Material", name, TextureType::Float)? {
                None => Ok(None),
                Some(Texture::Constant(c)) => Ok(Some(c.x)),
                Some(t) => {
                    let typical = t.typical().x.max(1.0);
                    textured.borrow_mut().push((name.to_string(), t));
                    Ok(Some(typical))
                }
            }
        };
        // A float dpm only compares with 0 (roughness, sigma): a texture's typical value.
        let float = |name: &str| -> Result<Option<f32>, SceneError> {
            Ok(self
                .parameter_if_given(params, "Material", name, TextureType::Float)?
                .map(|t| t.typical().x))
        };
        let read = super::glossy::Readers {
            colour: &colour,
            float: &float,
        };
        let exact = |material| Mapped {
            material,
            approximation: None,
            textures: Vec::new(),
        };
        let roughness = |names: &[&str]| -> Result<f32, SceneError> {
            let mut r: f32 = 0.0;
            for name in names {
                r = r.max(float(name)?.unwrap_or(0.0));
            }
            Ok(r)
        };
        let mapped = match kind {
            "matte" => {
                let albedo = colour("Kd", 0.5)?;
                let sigma = float("sigma")?.unwrap_or(0.0);
                Mapped {
                    material: Material::Diffuse { albedo },
                    approximation: (sigma != 0.0).then(|| {
                        format!(
                            "matte \"sigma\" {sigma}: Oren–Nayar roughness is rendered as Lambert"
                        )
                    }),
                    textures: Vec::new(),
                }
            }
            "diffuse" => exact(Material::Diffuse {
                albedo: colour("reflectance", 0.5)?,
            }),
            "mirror" => {
                let tint = colour("Kr", 0.9)?;
                exact(Material::Mirror { tint })
            }
            "glass" => {
                let ior = match index("index")? {
                    Some(x) => x,
                    None => index("eta")?.unwrap_or(1.5),
                };
                if roughness(&["roughness", "uroughness", "vroughness"])? > 0.0 {
                    exact(as_material(
                        self.glossy_model(kind, params, at, &read, ior)?,
                    ))
                } else {
                    params.bool("remaproughness").map_err(p)?;
                    exact(Material::Glass {
                        ior,
                        reflect_tint: colour("Kr", 1.0)?,
                        transmit_tint: colour("Kt", 1.0)?,
                    })
                }
            }
            "dielectric" | "thindielectric" => {
                let ior =
                    match params.spectrum_name("eta") {
                        Some(name) => {
                            named_glass(&name).ok_or_else(|| {
                                at.error(
                            "Material \"spectrum eta\"",
                            format!(
                                "\"{name}\" is not a glass dpm knows ({}); give a float eta",
                                NAMED_GLASSES.iter().map(|g| g.0).collect::<Vec<_>>().join(", ")
                            ),
                        )
                            })?
                        }
                        None => match index("eta")? {
                            Some(x) => x,
                            None => params.colour("eta").map_err(p)?.map_or(1.5, |c| c.x),
                        },
                    };
                let rough = roughness(&["roughness", "uroughness", "vroughness"])?;
                if kind == "thindielectric" || rough > 0.0 {
                    exact(as_material(
                        self.glossy_model(kind, params, at, &read, ior)?,
                    ))
                } else {
                    params.bool("remaproughness").map_err(p)?;
                    exact(Material::clear_glass(ior))
                }
            }
            "conductor" | "metal" => {
                let default_roughness = if kind == "metal" { 0.01 } else { 0.0 };
                let rough = match float("roughness")? {
                    Some(r) => r.max(roughness(&["uroughness", "vroughness"])?),
                    None if params.at("uroughness").is_some()
                        || params.at("vroughness").is_some() =>
                    {
                        roughness(&["uroughness", "vroughness"])?
                    }
                    None => default_roughness,
                };
                if rough == 0.0 {
                    params.bool("remaproughness").map_err(p)?;
                    let reflectance = if params.texture("reflectance").map_err(p)?.is_some() {
                        colour("reflectance", 1.0)?
                    } else {
                        self.conductor_reflectance(params, at)?
                    };
                    exact(Material::Mirror { tint: reflectance })
                } else {
                    exact(as_material(
                        self.glossy_model(kind, params, at, &read, 1.0)?,
                    ))
                }
            }
            kind if super::glossy::is_glossy_kind(kind) => {
                let eta = (float("eta")?).unwrap_or(1.5);
                exact(as_material(
                    self.glossy_model(kind, params, at, &read, eta)?,
                ))
            }
            "fourier" | "measured" => {
                return Err(at.error(
                    "Material",
                    format!("material \"{kind}\" is a measured BSDF (tabulated data), which dpm does not render; give the object an analytic material"),
                ));
            }
            "hair" => {
                return Err(at.error(
                    "Material",
                    "material \"hair\" (pbrt's hair scattering model) is not supported; give the curves a diffuse material",
                ));
            }
            "subsurface" | "kdsubsurface" => {
                return Err(at.error(
                    "Material",
                    format!("material \"{kind}\" scatters light in a participating medium under the surface, and dpm has no media; use glass or a diffuse material"),
                ));
            }
            "mix" | "disney" => {
                return Err(at.error(
                    "Material",
                    format!("material \"{kind}\" has no part dpm can render (dpm has diffuse, mirror and glass)"),
                ));
            }
            "interface" | "" | "none" => {
                return Err(at.error(
                    "Material",
                    format!("material \"{kind}\" (a medium boundary) is not supported: dpm has no participating media"),
                ));
            }
            other => {
                return Err(at.error("Material", format!("\"{other}\" is not a pbrt material")));
            }
        };
        let mut mapped = mapped;
        if let Material::Bsdf(model) = &mapped.material {
            mapped.approximation = mapped.approximation.or_else(|| approximation(kind, model));
        }
        mapped.textures = (textured.into_inner().into_iter())
            .filter_map(|(name, texture)| {
                textured_parameter(&mapped.material, &name).map(|parameter| (parameter, texture))
            })
            .collect();
        for ignored in ["bumpmap", "displacement", "normalmap"] {
            if params.at(ignored).is_some() {
                self.warn(at, format!("material \"{kind}\": \"{ignored}\" is ignored"));
                params.mark_used(ignored);
            }
        }
        Ok(mapped)
    }
}

/// Why dpm's model of pbrt material `kind` is an approximation, when it is one
/// (docs/materials.md measures each against pbrt-v4's random walk).
fn approximation(kind: &str, model: &crate::bsdf::Model) -> Option<String> {
    use crate::bsdf::Model;
    match model {
        Model::CoatedDiffuse { albedo, .. } | Model::CoatedConductor { albedo, .. }
            if albedo.max_element() > 0.0 =>
        {
            Some(format!(
                "material \"{kind}\": the medium between coat and base (\"albedo\", \"g\") is not modelled; the layer only attenuates"
            ))
        }
        Model::CoatedConductor { .. } => Some(format!(
            "material \"{kind}\": light the coat returns to the conductor is followed at the angle it left, not scattered (up to 0.14 of the albedo on a rough bright metal)"
        )),
        _ => None,
    }
}

/// A model that is one Lambert lobe and nothing else is a diffuse material (the same image,
/// by the quicker path).
fn as_material(model: crate::bsdf::Model) -> Material {
    match crate::bsdf::Bsdf::new(&model).lambert_only() {
        Some(albedo) => Material::Diffuse { albedo },
        None => Material::Bsdf(model),
    }
}

/// Which of `material`'s parameters the pbrt parameter `name` became.
fn textured_parameter(material: &Material, name: &str) -> Option<TexturedParameter> {
    Some(match (material, name) {
        (Material::Diffuse { .. }, _) => TexturedParameter::Albedo,
        (Material::Mirror { .. }, _) => TexturedParameter::Tint,
        (Material::Glass { .. }, "Kr") => TexturedParameter::ReflectTint,
        (Material::Glass { .. }, "Kt") => TexturedParameter::TransmitTint,
        (Material::Glass { .. }, _) => TexturedParameter::Ior,
        (Material::Bsdf(_), "Kd" | "reflectance") => TexturedParameter::Albedo,
        // Other textured parameters of a BSDF model take their typical value.
        (Material::Bsdf(_), _) => return None,
    })
}

fn named_glass(name: &str) -> Option<f32> {
    NAMED_GLASSES.iter().find(|g| g.0 == name).map(|g| g.1)
}
