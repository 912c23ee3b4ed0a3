//! pbrt's `mix` material as a [`Material::Mix`]: pbrt-v3's `namedmaterial1` and
//! `namedmaterial2` blended by `amount` (the first's weight: a spectrum or float, constant or
//! texture), pbrt-v4's `materials` `[a b]` (b chosen with probability `amount`, a float).
//! Both become pbrt-v4's choice of one material per point, pbrt-v3's pair swapped so that
//! `amount` is the probability of the second; a pbrt-v3 amount whose channels differ is
//! approximated by their mean, with a warning (refused under `--strict`). Owns finding the
//! two materials (each defined before the mix, as pbrt requires) and reading the amount; must
//! not evaluate textures or choose at a point.

use super::super::parser::Parsed;
use super::materials::Mapped;
use super::{Mapper, param_error, value_error};
use crate::scene::texture::channel_mean;
use crate::scene::{MAX_MIX_DEPTH, Material, SceneError, Texture, TexturedParameter};
use glam::Vec3;

impl Mapper<'_> {
    /// Maps `parsed.materials[index]`, a `mix` under `depth` other mixes, its two materials
    /// mapped (on first use) as a shape's are.
    pub(super) fn mix(
        &mut self,
        index: usize,
        parsed: &Parsed,
        depth: usize,
    ) -> Result<Mapped, SceneError> {
        let item = &parsed.materials[index].1;
        let params = &item.params;
        let p = |e| param_error("Material", e);
        if depth >= MAX_MIX_DEPTH {
            return Err(item.at.error(
                "Material",
                format!("mixes of mixes nest more than {MAX_MIX_DEPTH} deep"),
            ));
        }
        // The pair in pbrt-v4's order (the second chosen with probability `amount`), and the
        // parameter that names each.
        let (names, parameters) = match params.strings("materials").map_err(p)? {
            Some(names) if names.len() == 2 => (names, ["materials"; 2]),
            Some(names) => {
                return Err(value_error(
                    item,
                    "Material",
                    "materials",
                    format!("a mix takes two materials, not {}", names.len()),
                ));
            }
            None => {
                let name = |parameter: &str| -> Result<String, SceneError> {
                    params.string(parameter).map_err(p)?.ok_or_else(|| {
                        item.at.error(
                            "Material",
                            format!("a mix needs \"string {parameter}\" (pbrt-v3) or \"string materials\" (pbrt-v4)"),
                        )
                    })
                };
                // pbrt-v3 weighs the first by `amount`: it goes second.
                let (first, second) = (name("namedmaterial1")?, name("namedmaterial2")?);
                (vec![second, first], ["namedmaterial2", "namedmaterial1"])
            }
        };
        let mut ids = [0u32; 2];
        for (k, name) in names.iter().enumerate() {
            // The last definition of the name before the mix, as pbrt looks it up then.
            let defined = (parsed.materials[..index].iter())
                .rposition(|(n, _)| n.as_deref() == Some(name.as_str()))
                .ok_or_else(|| {
                    value_error(
                        item,
                        "Material",
                        parameters[k],
                        format!("no material is named \"{name}\" (MakeNamedMaterial must define it before the mix)"),
                    )
                })?;
            ids[k] = self.material_within_mixes(Some(defined), parsed, depth + 1)?;
        }
        let amount = (self.parameter_of_either_type(params, "Material", "amount")?)
            .unwrap_or(Texture::Constant(Vec3::splat(0.5)));
        let approximation = (!amount.is_grey()).then(|| {
            "mix \"amount\" differs between colour channels: dpm shows one material per point, chosen by the channels' mean (pbrt-v3 weighs each channel apart)".to_string()
        });
        let (amount, textures) = match amount {
            Texture::Constant(c) => {
                if !(c.is_finite() && c.min_element() >= 0.0 && c.max_element() <= 1.0) {
                    let shown = match c.x == c.y && c.y == c.z {
                        true => c.x.to_string(),
                        false => c.to_string(),
                    };
                    return Err(value_error(
                        item,
                        "Material",
                        "amount",
                        format!("a mix's amount {shown} is not in [0, 1]"),
                    ));
                }
                (channel_mean(c), Vec::new())
            }
            texture => (
                channel_mean(texture.typical()).clamp(0.0, 1.0),
                vec![(TexturedParameter::MixAmount, texture)],
            ),
        };
        Ok(Mapped {
            material: Material::Mix {
                materials: ids,
                amount,
            },
            approximation,
            textures,
        })
    }
}
