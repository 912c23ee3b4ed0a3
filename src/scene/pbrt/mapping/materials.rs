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
use crate::bsdf::{Axes, ModelParameter, Remap};
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
        // The textures read, by parameter name, each once; the material takes their typical
        // values.
        let textured = RefCell::new(Vec::<(String, Texture)>::new());
        let record = |name: &str, texture: Texture| {
            let mut textured = textured.borrow_mut();
            if !textured.iter().any(|(n, _)| n == name) {
                textured.push((name.to_string(), texture));
            }
        };
        let colour = |name: &str, default: f32| -> Result<Vec3, SceneError> {
            match self.parameter_if_given(params, "Material", name, TextureType::Colour)? {
                None => Ok(Vec3::splat(default)),
                Some(Texture::Constant(c)) => Ok(c),
                Some(t) => {
                    let typical = t.typical().clamp(Vec3::ZERO, Vec3::ONE);
                    record(name, t);
                    Ok(typical)
                }
            }
        };
        let unbounded = |name: &str, default: f32| -> Result<Vec3, SceneError> {
            match self.parameter_of_either_type(params, "Material", name)? {
                None => Ok(Vec3::splat(default)),
                Some(Texture::Constant(c)) => Ok(c),
                Some(t) => {
                    let typical = t.typical();
                    record(name, t);
                    Ok(typical)
                }
            }
        };
        // A float (roughness, an index, a thickness): a texture's typical value.
        let float = |name: &str| -> Result<Option<f32>, SceneError> {
            match self.parameter_if_given(params, "Material", name, TextureType::Float)? {
                None => Ok(None),
                Some(Texture::Constant(c)) => Ok(Some(c.x)),
                Some(t) => {
                    let typical = t.typical().x;
                    record(name, t);
                    Ok(Some(typical))
                }
            }
        };
        // An index of refraction: a texture's typical value at least 1.
        let index = |name: &str| -> Result<Option<f32>, SceneError> {
            let textured = params.texture(name).map_err(p)?.is_some();
            Ok(float(name)?.map(|x| if textured { x.max(1.0) } else { x }))
        };
        let read = super::glossy::Readers {
            colour: &colour,
            unbounded: &unbounded,
            float: &float,
            index: &index,
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
        // pbrt-v3's glass, smooth or rough (a subsurface material's surface too).
        let glass = |ior: f32, rough: &[&str]| -> Result<Mapped, SceneError> {
            Ok(if roughness(rough)? > 0.0 {
                exact(Material::Bsdf(
                    self.glossy_model("glass", params, at, &read, ior)?,
                ))
            } else {
                params.bool("remaproughness").map_err(p)?;
                exact(Material::Glass {
                    ior,
                    reflect_tint: colour("Kr", 1.0)?,
                    transmit_tint: colour("Kt", 1.0)?,
                })
            })
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
                glass(ior, &["roughness", "uroughness", "vroughness"])?
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
                    exact(Material::Bsdf(
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
                // A textured η or k varies over the surface: a conductor model, however smooth.
                let textured_index = params.texture("eta").map_err(p)?.is_some()
                    || params.texture("k").map_err(p)?.is_some();
                if rough == 0.0 && !textured_index {
                    params.bool("remaproughness").map_err(p)?;
                    let reflectance = if params.texture("reflectance").map_err(p)?.is_some() {
                        colour("reflectance", 1.0)?
                    } else {
                        self.conductor_reflectance(params, at)?
                    };
                    exact(Material::Mirror { tint: reflectance })
                } else {
                    exact(Material::Bsdf(
                        self.glossy_model(kind, params, at, &read, 1.0)?,
                    ))
                }
            }
            kind if super::glossy::is_glossy_kind(kind) => {
                let eta = (index("eta")?).unwrap_or(1.5);
                exact(Material::Bsdf(
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
            kind if super::subsurface::is_subsurface(kind) => {
                // The boundary; the medium under it is read with the shape
                // (`Mapper::subsurface_medium`).
                for name in super::subsurface::MEDIUM_PARAMETERS {
                    params.mark_used(name);
                }
                glass(index("eta")?.unwrap_or(1.33), &["uroughness", "vroughness"])?
            }
            "disney" => {
                return Err(at.error(
                    "Material",
                    format!("material \"{kind}\" has no part dpm can render (dpm has diffuse, mirror and glass)"),
                ));
            }
            "interface" | "" | "none" => {
                return Err(at.error(
                    "Material",
                    format!("material \"{kind}\" only bounds a medium: an area light or a mix cannot take it"),
                ));
            }
            other => {
                return Err(at.error("Material", format!("\"{other}\" is not a pbrt material")));
            }
        };
        let remap = super::glossy::remap(params, kind)?;
        // pbrt-v4's diffuse transmitter scales both its colours by `scale`.
        let scale = match kind {
            "diffusetransmission" => float("scale")?.unwrap_or(1.0),
            _ => 1.0,
        };
        let mut textures = Vec::new();
        for (name, texture) in textured.into_inner() {
            let Some(parameter) = textured_parameter(&mapped.material, &name, params, remap) else {
                continue;
            };
            let texture = match name.as_str() {
                "reflectance" | "transmittance" if scale != 1.0 => Texture::Scale(
                    Box::new(texture),
                    Box::new(Texture::Constant(Vec3::splat(scale))),
                ),
                _ => texture,
            };
            textures.push((parameter, texture));
        }
        let (material, textures) = as_diffuse_if_lambert(mapped.material, textures);
        let approximation = (mapped.approximation).or_else(|| match &material {
            Material::Bsdf(model) => approximation(kind, model),
            _ => None,
        });
        let mapped = Mapped {
            material,
            textures,
            approximation,
        };
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
/// by the quicker path), when its textures, if any, give that lobe's colour and nothing else.
fn as_diffuse_if_lambert(
    material: Material,
    textures: Vec<(TexturedParameter, Texture)>,
) -> (Material, Vec<(TexturedParameter, Texture)>) {
    let Material::Bsdf(mut model) = material else {
        return (material, textures);
    };
    let Some(albedo) = crate::bsdf::Bsdf::new(&model).lambert_only() else {
        return (material, textures);
    };
    let diffuse = TexturedParameter::Model(ModelParameter::Diffuse);
    // The textures set the model's diffuse colour, which must then be the lobe's whole albedo
    // (not scaled by uber's opacity or translucent's `reflect`).
    let only_diffuse_colour = textures.iter().all(|(p, _)| *p == diffuse)
        && model.diffuse_mut().is_some_and(|kd| *kd == albedo);
    if !textures.is_empty() && !only_diffuse_colour {
        return (material, textures);
    }
    let textures = (textures.into_iter())
        .map(|(_, t)| (TexturedParameter::Albedo, t))
        .collect();
    (Material::Diffuse { albedo }, textures)
}

/// Which of `material`'s parameters the pbrt parameter `name` became, by explicit names only
/// (a textured parameter dpm does not vary over a surface, matte's `sigma` say, keeps its
/// typical value). A roughness carries `remap` and its axes: `uroughness` and `vroughness`
/// take precedence over `roughness`.
fn textured_parameter(
    material: &Material,
    name: &str,
    params: &ParamList,
    remap: Remap,
) -> Option<TexturedParameter> {
    use crate::bsdf::Model;
    use ModelParameter as P;
    Some(match (material, name) {
        (Material::Diffuse { .. }, "Kd" | "reflectance") => TexturedParameter::Albedo,
        (Material::Mirror { .. }, "Kr" | "reflectance") => TexturedParameter::Tint,
        (Material::Glass { .. }, "Kr") => TexturedParameter::ReflectTint,
        (Material::Glass { .. }, "Kt") => TexturedParameter::TransmitTint,
        (Material::Glass { .. }, "index" | "eta") => TexturedParameter::Ior,
        (Material::Bsdf(model), name) => TexturedParameter::Model(match (model, name) {
            (_, name) if name.ends_with("roughness") => roughness_parameter(name, params, remap)?,
            (Model::Conductor { .. }, "eta") | (_, "conductor.eta") => P::ConductorEta,
            (Model::Conductor { .. }, "k") | (_, "conductor.k") => P::ConductorK,
            (Model::Conductor { .. }, "reflectance") | (_, "conductor.reflectance") => {
                P::ConductorReflectance
            }
            (_, "Kd" | "reflectance") => P::Diffuse,
            (_, "Ks") => P::Specular,
            (_, "Kr") => P::Reflection,
            (_, "Kt") => P::Transmission,
            (_, "opacity") => P::Opacity,
            (_, "reflect") => P::Reflect,
            (_, "transmit" | "transmittance") => P::Transmit,
            // uber reads `index` before `eta`.
            (Model::Uber { .. }, "eta") if params.at("index").is_some() => return None,
            (_, "index" | "eta" | "interface.eta") => P::Eta,
            (_, "thickness") => P::Thickness,
            _ => return None,
        }),
        _ => return None,
    })
}

/// The roughness a parameter named `[interface.|conductor.][u|v]roughness` gives; `None` for
/// an isotropic roughness both of whose axes are given on their own.
fn roughness_parameter(name: &str, params: &ParamList, remap: Remap) -> Option<ModelParameter> {
    let rest = name.strip_suffix("roughness")?;
    let (prefix, axes) = match rest.strip_suffix('u') {
        Some(prefix) => (prefix, Axes::U),
        None => match rest.strip_suffix('v') {
            Some(prefix) => (prefix, Axes::V),
            None => (rest, Axes::Both),
        },
    };
    if !matches!(prefix, "" | "interface." | "conductor.") {
        return None;
    }
    let given = |axis: &str| params.at(&format!("{prefix}{axis}roughness")).is_some();
    let axes = match (axes, given("u"), given("v")) {
        (Axes::Both, true, true) => return None,
        (Axes::Both, true, false) => Axes::V,
        (Axes::Both, false, true) => Axes::U,
        (axes, _, _) => axes,
    };
    Some(ModelParameter::Roughness {
        axes,
        remap,
        conductor: prefix == "conductor.",
    })
}

fn named_glass(name: &str) -> Option<f32> {
    NAMED_GLASSES.iter().find(|g| g.0 == name).map(|g| g.1)
}
