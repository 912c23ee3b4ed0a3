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

/// Normal-incidence reflectance (linear sRGB) of the metals pbrt names, for a smooth
/// conductor given by a named η/k spectrum.
const NAMED_METALS: &[(&str, [f32; 3])] = &[
    ("Cu", [0.955, 0.638, 0.538]),
    ("Au", [1.000, 0.766, 0.336]),
    ("Ag", [0.972, 0.960, 0.915]),
    ("Al", [0.913, 0.922, 0.924]),
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
        let exact = |material| Mapped {
            material,
            approximation: None,
            textures: Vec::new(),
        };
        let diffuse_part = |name: &str, default: f32| -> Result<Mapped, SceneError> {
            let albedo = colour(name, default)?;
            Ok(Mapped {
                material: Material::Diffuse { albedo },
                approximation: Some(format!(
                    "material \"{kind}\" is rendered as its diffuse part ({name} = {}); dpm \
                     has no glossy or coated lobes",
                    rgb_text(albedo)
                )),
                textures: Vec::new(),
            })
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
                let rough = roughness(&["uroughness", "vroughness"])?;
                params.bool("remaproughness").map_err(p)?;
                let material = Material::Glass {
                    ior,
                    reflect_tint: colour("Kr", 1.0)?,
                    transmit_tint: colour("Kt", 1.0)?,
                };
                Mapped {
                    material,
                    approximation: (rough > 0.0)
                        .then(|| format!("glass roughness {rough} is rendered as smooth glass")),
                    textures: Vec::new(),
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
                params.bool("remaproughness").map_err(p)?;
                let mut why = (rough > 0.0)
                    .then(|| format!("{kind} roughness {rough} is rendered as smooth glass"));
                if kind == "thindielectric" {
                    why = Some("thindielectric is rendered as a solid dielectric".into());
                }
                Mapped {
                    material: Material::clear_glass(ior),
                    approximation: why,
                    textures: Vec::new(),
                }
            }
            "conductor" | "metal" => {
                let reflectance = if params.texture("reflectance").map_err(p)?.is_some() {
                    colour("reflectance", 1.0)?
                } else {
                    self.conductor_reflectance(params, at)?
                };
                let default_roughness = if kind == "metal" { 0.01 } else { 0.0 };
                let rough = match float("roughness")? {
                    Some(r) => r.max(roughness(&["uroughness", "vroughness"])?),
                    None => {
                        let r = roughness(&["uroughness", "vroughness"])?;
                        if params.at("uroughness").is_some() || params.at("vroughness").is_some() {
                            r
                        } else {
                            default_roughness
                        }
                    }
                };
                params.bool("remaproughness").map_err(p)?;
                if rough == 0.0 {
                    exact(Material::Mirror { tint: reflectance })
                } else {
                    Mapped {
                        material: Material::Diffuse {
                            albedo: reflectance.min(Vec3::ONE),
                        },
                        approximation: Some(format!(
                            "{kind} with roughness {rough} is rendered as diffuse with its \
                             normal-incidence reflectance {}; dpm has no glossy lobe",
                            rgb_text(reflectance)
                        )),
                        textures: Vec::new(),
                    }
                }
            }
            "uber" | "plastic" | "translucent" => diffuse_part("Kd", 0.25)?,
            "substrate" => diffuse_part("Kd", 0.5)?,
            "coateddiffuse" => diffuse_part("reflectance", 0.5)?,
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
            "mix" | "disney" | "coatedconductor" | "diffusetransmission" => {
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
        mapped.textures = (textured.into_inner().into_iter())
            .map(|(name, texture)| (textured_parameter(&mapped.material, &name), texture))
            .collect();
        for ignored in ["bumpmap", "displacement", "normalmap"] {
            if params.at(ignored).is_some() {
                self.warn(at, format!("material \"{kind}\": \"{ignored}\" is ignored"));
                params.mark_used(ignored);
            }
        }
        Ok(mapped)
    }

    /// A smooth conductor's colour: `reflectance`, else F0 from constant η and k (pbrt-v4's
    /// default conductor is copper).
    fn conductor_reflectance(&self, params: &ParamList, at: &Place) -> Result<Vec3, SceneError> {
        let p = |e| param_error("Material", e);
        if let Some(r) = params.colour("reflectance").map_err(p)? {
            return Ok(r);
        }
        let named = |param: &str| params.spectrum_name(param);
        let (eta_name, k_name) = (named("eta"), named("k"));
        let is_file = |n: &Option<String>| n.as_ref().is_some_and(|n| n.ends_with(".spd"));
        if is_file(&eta_name) || is_file(&k_name) {
            // Sampled spectra from files: each to RGB through the CIE 1931 functions, as pbrt-v3
            // turns them into RGB, then F0 per channel.
            let rgb = |name: &Option<String>, default: f32| -> Result<Vec3, SceneError> {
                match name {
                    Some(file) => self.spectrum_file_rgb(file, at),
                    None => Ok(Vec3::splat(default)),
                }
            };
            let (eta, k) = (rgb(&eta_name, 1.0)?, rgb(&k_name, 0.0)?);
            let one = Vec3::ONE;
            return Ok(((eta - one) * (eta - one) + k * k) / ((eta + one) * (eta + one) + k * k));
        }
        if eta_name.is_some() || k_name.is_some() {
            let name = eta_name.or(k_name).unwrap_or_default();
            let metal = name
                .strip_prefix("metal-")
                .and_then(|rest| rest.split('-').next())
                .unwrap_or("");
            return NAMED_METALS
                .iter()
                .find(|(m, _)| *m == metal)
                .map(|(_, f0)| Vec3::from_array(*f0))
                .ok_or_else(|| {
                    at.error(
                        "Material \"spectrum eta\"",
                        format!("\"{name}\" is not a metal dpm knows (metal-Cu, -Au, -Ag, -Al); give rgb eta and k or a reflectance"),
                    )
                });
        }
        let eta = params.colour("eta").map_err(p)?;
        let k = params.colour("k").map_err(p)?;
        Ok(match (eta, k) {
            (None, None) => Vec3::from_array(NAMED_METALS[0].1),
            (eta, k) => {
                let eta = eta.unwrap_or(Vec3::ONE);
                let k = k.unwrap_or(Vec3::ZERO);
                let one = Vec3::ONE;
                ((eta - one) * (eta - one) + k * k) / ((eta + one) * (eta + one) + k * k)
            }
        })
    }
}

impl Mapper<'_> {
    /// A pbrt `.spd` file (wavelength in nm and value, a pair a line, `#` comments) as linear
    /// sRGB: linear between samples, held past the ends.
    fn spectrum_file_rgb(&self, file: &str, at: &Place) -> Result<Vec3, SceneError> {
        let path = super::super::parser::Parser::resolve(&self.folder, file);
        let refuse = |m: String| {
            at.error(
                "Material \"spectrum\"",
                format!("`{}`: {m}", path.display()),
            )
        };
        let bytes = self
            .files
            .read(&path)
            .map_err(|e| refuse(format!("cannot read it: {e}")))?;
        let text = String::from_utf8_lossy(&bytes);
        let numbers: Vec<f64> = (text.lines())
            .map(|l| l.split('#').next().unwrap_or(""))
            .flat_map(str::split_whitespace)
            .map(|w| {
                w.parse::<f64>()
                    .map_err(|_| refuse(format!("`{w}` is not a number")))
            })
            .collect::<Result<_, _>>()?;
        if numbers.len() < 2
            || !numbers.len().is_multiple_of(2)
            || numbers.iter().any(|x| !x.is_finite())
        {
            return Err(refuse(
                "is not (wavelength, value) pairs of finite numbers".into(),
            ));
        }
        let samples: Vec<(f64, f64)> = numbers.chunks_exact(2).map(|p| (p[0], p[1])).collect();
        if samples.windows(2).any(|w| w[1].0 <= w[0].0) {
            return Err(refuse("its wavelengths do not increase".into()));
        }
        let value = |lambda: f64| {
            let i = samples.partition_point(|s| s.0 < lambda);
            match i {
                0 => samples[0].1,
                i if i == samples.len() => samples[i - 1].1,
                i => {
                    let (a, b) = (samples[i - 1], samples[i]);
                    a.1 + (b.1 - a.1) * (lambda - a.0) / (b.0 - a.0)
                }
            }
        };
        // Normalised so that a constant spectrum gives its value in every channel.
        let white = crate::spectrum::xyz_to_linear_srgb(crate::spectrum::spectrum_xyz(|_| 1.0));
        let rgb = crate::spectrum::xyz_to_linear_srgb(crate::spectrum::spectrum_xyz(value)) / white;
        Ok(rgb.as_vec3())
    }
}

/// Which of `material`'s parameters the pbrt parameter `name` became.
fn textured_parameter(material: &Material, name: &str) -> TexturedParameter {
    match (material, name) {
        (Material::Diffuse { .. }, _) => TexturedParameter::Albedo,
        (Material::Mirror { .. }, _) => TexturedParameter::Tint,
        (Material::Glass { .. }, "Kr") => TexturedParameter::ReflectTint,
        (Material::Glass { .. }, "Kt") => TexturedParameter::TransmitTint,
        (Material::Glass { .. }, _) => TexturedParameter::Ior,
    }
}

fn named_glass(name: &str) -> Option<f32> {
    NAMED_GLASSES.iter().find(|g| g.0 == name).map(|g| g.1)
}

pub(super) fn rgb_text(c: Vec3) -> String {
    format!("[{} {} {}]", c.x, c.y, c.z)
}
