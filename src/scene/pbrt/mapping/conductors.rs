//! A conductor's complex index of refraction, however a pbrt scene gives it: constant RGB `eta`
//! and `k`, the named metals (`metal-Cu-eta` …, pbrt-v4's default copper), sampled `.spd`
//! spectra turned into RGB through the CIE 1931 functions, or a `reflectance` (pbrt-v4's η = 1,
//! k = 2√r/√(1 − r), whose normal-incidence Fresnel reflectance is r). Owns those tables and
//! the `.spd` reader; must not choose a material.

use super::super::Place;
use super::super::params::ParamList;
use super::glossy::Readers;
use super::{Mapper, param_error};
use crate::scene::SceneError;
use glam::Vec3;

/// Normal-incidence reflectance (linear sRGB) of the metals pbrt names, for a smooth
/// conductor given by a named η/k spectrum.
const NAMED_METALS: &[(&str, [f32; 3])] = &[
    ("Cu", [0.955, 0.638, 0.538]),
    ("Au", [1.000, 0.766, 0.336]),
    ("Ag", [0.972, 0.960, 0.915]),
    ("Al", [0.913, 0.922, 0.924]),
];

/// Normal-incidence Fresnel reflectance of a conductor of index η + ik.
pub(super) fn normal_reflectance(eta: Vec3, k: Vec3) -> Vec3 {
    let one = Vec3::ONE;
    ((eta - one) * (eta - one) + k * k) / ((eta + one) * (eta + one) + k * k)
}

/// The metal a pbrt spectrum name (`metal-Cu-eta`, `metal-Au-k`, …) names.
fn metal_of(name: &str) -> &str {
    name.strip_prefix("metal-")
        .and_then(|rest| rest.split('-').next())
        .unwrap_or("")
}

impl Mapper<'_> {
    /// A rough conductor's (η, k), its parameters named `prefix` + `eta`, `k`, `reflectance`
    /// (`prefix` is `conductor.` in pbrt-v4's coatedconductor). Textures are read through
    /// `read`, which records them; the model holds their typical values.
    pub(super) fn conductor_eta_k(
        &self,
        params: &ParamList,
        at: &Place,
        read: &Readers,
        prefix: &str,
    ) -> Result<(Vec3, Vec3), SceneError> {
        let p = |e| param_error("Material", e);
        let name = |n: &str| format!("{prefix}{n}");
        let textured = |n: &str| -> Result<bool, SceneError> {
            Ok(params.texture(&name(n)).map_err(p)?.is_some())
        };
        let reflectance = if textured("reflectance")? {
            Some((read.colour)(&name("reflectance"), 1.0)?)
        } else {
            params.colour(&name("reflectance")).map_err(p)?
        };
        if let Some(r) = reflectance {
            let r = r.clamp(Vec3::ZERO, Vec3::splat(0.9999));
            return Ok((Vec3::ONE, 2.0 * r.powf(0.5) / (Vec3::ONE - r).powf(0.5)));
        }
        if textured("eta")? || textured("k")? {
            let value = |n: &str, default: f32| -> Result<Vec3, SceneError> {
                match textured(n)? {
                    true => (read.unbounded)(&name(n), default),
                    false => Ok(params
                        .colour(&name(n))
                        .map_err(p)?
                        .unwrap_or(Vec3::splat(default))),
                }
            };
            return Ok((
                value("eta", 1.0)?.max(Vec3::splat(1e-3)),
                value("k", 0.0)?.max(Vec3::ZERO),
            ));
        }
        let named = |n: &str| params.spectrum_name(&name(n));
        let (eta_name, k_name) = (named("eta"), named("k"));
        let is_file = |n: &Option<String>| n.as_ref().is_some_and(|n| n.ends_with(".spd"));
        if is_file(&eta_name) || is_file(&k_name) {
            let rgb = |n: &Option<String>, default: f32| -> Result<Vec3, SceneError> {
                match n {
                    Some(file) => self.spectrum_file_rgb(file, at),
                    None => Ok(Vec3::splat(default)),
                }
            };
            return Ok((
                rgb(&eta_name, 1.0)?.max(Vec3::splat(1e-3)),
                rgb(&k_name, 0.0)?.max(Vec3::ZERO),
            ));
        }
        if eta_name.is_some() || k_name.is_some() {
            let spectrum = eta_name.or(k_name).unwrap_or_default();
            return crate::scene::metals::NAMED_METAL_INDICES
                .iter()
                .find(|(m, _, _)| *m == metal_of(&spectrum))
                .map(|(_, eta, k)| (Vec3::from_array(*eta), Vec3::from_array(*k)))
                .ok_or_else(|| unknown_metal(at, &spectrum));
        }
        let eta = params.colour(&name("eta")).map_err(p)?;
        let k = params.colour(&name("k")).map_err(p)?;
        let copper = crate::scene::metals::NAMED_METAL_INDICES[0];
        Ok(match (eta, k) {
            (None, None) => (Vec3::from_array(copper.1), Vec3::from_array(copper.2)),
            (eta, k) => (
                eta.unwrap_or(Vec3::ONE).max(Vec3::splat(1e-3)),
                k.unwrap_or(Vec3::ZERO).max(Vec3::ZERO),
            ),
        })
    }

    /// A smooth conductor's colour: `reflectance`, else F0 from constant η and k (pbrt-v4's
    /// default conductor is copper).
    pub(super) fn conductor_reflectance(
        &self,
        params: &ParamList,
        at: &Place,
    ) -> Result<Vec3, SceneError> {
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
            return Ok(normal_reflectance(rgb(&eta_name, 1.0)?, rgb(&k_name, 0.0)?));
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
                .ok_or_else(|| unknown_metal(at, &name));
        }
        let eta = params.colour("eta").map_err(p)?;
        let k = params.colour("k").map_err(p)?;
        Ok(match (eta, k) {
            (None, None) => Vec3::from_array(NAMED_METALS[0].1),
            (eta, k) => normal_reflectance(eta.unwrap_or(Vec3::ONE), k.unwrap_or(Vec3::ZERO)),
        })
    }

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

fn unknown_metal(at: &Place, name: &str) -> SceneError {
    at.error(
        "Material \"spectrum eta\"",
        format!("\"{name}\" is not a metal dpm knows (metal-Cu, -Au, -Ag, -Al); give rgb eta and k or a reflectance"),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_named_metals_indices_give_their_normal_incidence_reflectance() {
        for (metal, f0) in NAMED_METALS {
            let (_, eta, k) = crate::scene::metals::NAMED_METAL_INDICES
                .iter()
                .find(|m| m.0 == *metal)
                .unwrap();
            let r = normal_reflectance(Vec3::from_array(*eta), Vec3::from_array(*k));
            // The two tables reduce the spectra to RGB separately: within 0.04 of each other.
            assert!(
                (r - Vec3::from_array(*f0)).abs().max_element() < 0.04,
                "{metal}: {r}"
            );
        }
    }
}
