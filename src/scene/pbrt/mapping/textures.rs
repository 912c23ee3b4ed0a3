//! pbrt's named textures as dpm's [`Texture`]s: `Texture "name" "spectrum"|"color"|"float"
//! "class" ...` with the classes `constant`, `imagemap`, `checkerboard` (2-D), `scale` and
//! `mix` on the `uv` mapping, and the `"texture X" "name"` parameters that use them. Owns the
//! table of named textures, their parameters and defaults (pbrt-v3's, with pbrt-v4's names
//! where they differ) and the errors for a missing name, a type mismatch or a bad image;
//! images are read through [`Mapper::read_image`]. Must not evaluate textures at a point.

use super::super::parser::{Item, TextureItem};
use super::{Mapper, param_error, value_error};
use crate::image_io::srgb_to_linear;
use crate::scene::texture::{TextureImage, UvMapping, Wrap};
use crate::scene::{SceneError, Texture};
use glam::{Vec2, Vec3};
use std::sync::Arc;

/// pbrt's luminance weights for linear RGB, which a float image texture reads.
const LUMINANCE: Vec3 = Vec3::new(0.212_671, 0.715_160, 0.072_169);

/// What a texture gives: a colour or one number.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum TextureType {
    Colour,
    Float,
}

impl TextureType {
    fn name(self) -> &'static str {
        match self {
            TextureType::Colour => "spectrum",
            TextureType::Float => "float",
        }
    }
}

impl Mapper<'_> {
    /// Maps every `Texture` directive in order, so each may use the ones before it. A texture
    /// that cannot be mapped (an unsupported class, a missing image) is an error only where a
    /// parameter dpm reads uses it: scenes define textures for bump maps dpm ignores.
    pub(super) fn define_textures(&mut self, textures: &[TextureItem]) -> Result<(), SceneError> {
        for t in textures {
            let ty = match t.ty.as_str() {
                "spectrum" | "color" | "rgb" => TextureType::Colour,
                "float" => TextureType::Float,
                other => {
                    return Err(t.item.at.error(
                        "Texture",
                        format!("\"{other}\" is not a texture type (spectrum or float)"),
                    ));
                }
            };
            let texture = self.texture(ty, &t.item);
            if texture.is_ok() {
                self.unused(&t.item, "Texture");
            }
            if self
                .textures
                .insert(t.name.clone(), (ty, texture))
                .is_some()
            {
                let at = t.item.at.clone();
                self.warn(
                    &at,
                    format!(
                        "Texture \"{}\" is defined again; the last definition is used",
                        t.name
                    ),
                );
            }
        }
        Ok(())
    }

    fn texture(&mut self, ty: TextureType, item: &Item) -> Result<Texture, SceneError> {
        let p = |e| param_error("Texture", e);
        let params = &item.params;
        let texture = match item.kind.as_str() {
            "constant" => self.parameter(params, "Texture", "value", ty, 1.0)?,
            "imagemap" => self.image_texture(ty, item)?,
            "checkerboard" => {
                let dimension = params.integer("dimension").map_err(p)?.unwrap_or(2);
                if dimension != 2 {
                    return Err(value_error(
                        item,
                        "Texture",
                        "dimension",
                        format!(
                            "checkerboard dimension {dimension}: dpm has the 2-D checkerboard only"
                        ),
                    ));
                }
                // Without ray differentials every checkerboard is point-sampled.
                params.mark_used("aamode");
                Texture::Checkerboard {
                    mapping: uv_mapping(item)?,
                    even: Box::new(self.parameter(params, "Texture", "tex1", ty, 1.0)?),
                    odd: Box::new(self.parameter(params, "Texture", "tex2", ty, 0.0)?),
                }
            }
            "scale" if params.at("tex").is_some() || params.at("scale").is_some() => {
                // pbrt-v4: `tex` times the float `scale`.
                Texture::Scale(
                    Box::new(self.parameter(params, "Texture", "tex", ty, 1.0)?),
                    Box::new(self.parameter(
                        params,
                        "Texture",
                        "scale",
                        TextureType::Float,
                        1.0,
                    )?),
                )
            }
            "scale" => Texture::Scale(
                Box::new(self.parameter(params, "Texture", "tex1", ty, 1.0)?),
                Box::new(self.parameter(params, "Texture", "tex2", ty, 1.0)?),
            ),
            "mix" => Texture::Mix {
                first: Box::new(self.parameter(params, "Texture", "tex1", ty, 0.0)?),
                second: Box::new(self.parameter(params, "Texture", "tex2", ty, 1.0)?),
                amount: Box::new(self.parameter(
                    params,
                    "Texture",
                    "amount",
                    TextureType::Float,
                    0.5,
                )?),
            },
            other => {
                return Err(item.at.error(
                    "Texture",
                    format!("texture class \"{other}\" is not supported (dpm has constant, imagemap, checkerboard, scale and mix)"),
                ));
            }
        };
        Ok(folded(texture))
    }

    /// The value of parameter `name` of type `ty` as a texture: a named texture, a constant
    /// as written, or `default` when absent.
    pub(super) fn parameter(
        &self,
        params: &super::super::params::ParamList,
        directive: &str,
        name: &str,
        ty: TextureType,
        default: f32,
    ) -> Result<Texture, SceneError> {
        Ok(self
            .parameter_if_given(params, directive, name, ty)?
            .unwrap_or(Texture::Constant(Vec3::splat(default))))
    }

    /// [`Self::parameter`], `None` when the parameter is absent.
    pub(super) fn parameter_if_given(
        &self,
        params: &super::super::params::ParamList,
        directive: &str,
        name: &str,
        ty: TextureType,
    ) -> Result<Option<Texture>, SceneError> {
        let p = |e| param_error(directive, e);
        if let Some(texture_name) = params.texture(name).map_err(p)? {
            let refuse = |message: String| {
                p(params
                    .error_at(name, message)
                    .expect("the parameter was just read"))
            };
            return match self.textures.get(&texture_name) {
                Some((found, Ok(texture))) if *found == ty => Ok(Some(texture.clone())),
                Some((found, Err(why))) if *found == ty => Err(why.clone()),
                Some((found, _)) => Err(refuse(format!(
                    "texture \"{texture_name}\" is a {} texture; this parameter needs a {} texture",
                    found.name(),
                    ty.name()
                ))),
                None => Err(refuse(format!(
                    "no texture is named \"{texture_name}\" (a Texture directive must define it first)"
                ))),
            };
        }
        Ok(match ty {
            TextureType::Colour => params.colour(name).map_err(p)?,
            TextureType::Float => params.float(name).map_err(p)?.map(Vec3::splat),
        }
        .map(Texture::Constant))
    }

    /// [`Self::parameter_if_given`] for a parameter that a colour or a float texture may give
    /// (a float one in every channel): a conductor's η and k, pbrt-v3's mix amount.
    pub(super) fn parameter_of_either_type(
        &self,
        params: &super::super::params::ParamList,
        directive: &str,
        name: &str,
    ) -> Result<Option<Texture>, SceneError> {
        let texture = params
            .texture(name)
            .map_err(|e| param_error(directive, e))?;
        let ty = match texture.and_then(|t| self.textures.get(&t)) {
            Some((TextureType::Float, _)) => TextureType::Float,
            _ => TextureType::Colour,
        };
        self.parameter_if_given(params, directive, name, ty)
    }

    fn image_texture(&mut self, ty: TextureType, item: &Item) -> Result<Texture, SceneError> {
        let p = |e| param_error("Texture", e);
        let params = &item.params;
        let Some(file) = params.string("filename").map_err(p)? else {
            return Err(item
                .at
                .error("Texture", "imagemap needs \"string filename\""));
        };
        let lower = file.to_ascii_lowercase();
        let eight_bit = lower.ends_with(".png") || lower.ends_with(".tga");
        // pbrt-v3's `gamma` (default: on for 8-bit files), pbrt-v4's `encoding`.
        let gamma = match params.string("encoding").map_err(p)? {
            Some(e) if e == "sRGB" => true,
            Some(e) if e == "linear" => false,
            Some(e) => {
                return Err(value_error(
                    item,
                    "Texture",
                    "encoding",
                    format!("encoding \"{e}\" is not supported (sRGB or linear)"),
                ));
            }
            None => params.bool("gamma").map_err(p)?.unwrap_or(eight_bit),
        };
        let wrap_name = params.string("wrap").map_err(p)?;
        let wrap = match wrap_name.as_deref() {
            None => Wrap::Repeat,
            Some(name) => Wrap::from_name(name).ok_or_else(|| {
                value_error(
                    item,
                    "Texture",
                    "wrap",
                    format!("wrap \"{name}\" is not one of repeat, black, clamp"),
                )
            })?,
        };
        let scale = params.float("scale").map_err(p)?.unwrap_or(1.0);
        let invert = params.bool("invert").map_err(p)?.unwrap_or(false);
        // Filtering beyond bilinear needs ray differentials dpm does not carry.
        for ignored in ["filter", "maxanisotropy", "trilinear"] {
            params.mark_used(ignored);
        }
        let mapping = uv_mapping(item)?;
        let raw = self.read_image(item, "Texture", "filename", &file, false)?;
        if let Some(i) = raw.pixels.iter().position(|t| !t.is_finite()) {
            return Err(value_error(
                item,
                "Texture",
                "filename",
                format!("`{file}`: texel {i} is not finite"),
            ));
        }
        let decode = |v: f32| if gamma { srgb_to_linear(v) } else { v };
        let texels = match ty {
            TextureType::Colour => raw.pixels.iter().map(|t| t.map(decode)).collect(),
            TextureType::Float => (raw.pixels.iter())
                .map(|t| Vec3::splat(decode(t.dot(LUMINANCE))))
                .collect(),
        };
        Ok(Texture::Image {
            image: Arc::new(TextureImage {
                width: raw.width,
                height: raw.height,
                texels,
            }),
            mapping,
            wrap,
            scale,
            invert,
        })
    }
}

/// The `uv` mapping's `uscale`, `vscale`, `udelta`, `vdelta`; other mappings are refused.
fn uv_mapping(item: &Item) -> Result<UvMapping, SceneError> {
    let p = |e| param_error("Texture", e);
    let params = &item.params;
    if let Some(kind) = params.string("mapping").map_err(p)?
        && kind != "uv"
    {
        return Err(value_error(
            item,
            "Texture",
            "mapping",
            format!("mapping \"{kind}\" is not supported: dpm maps textures by (u, v) only"),
        ));
    }
    let f = |name: &str, default: f32| -> Result<f32, SceneError> {
        Ok(params.float(name).map_err(p)?.unwrap_or(default))
    };
    Ok(UvMapping {
        scale: Vec2::new(f("uscale", 1.0)?, f("vscale", 1.0)?),
        delta: Vec2::new(f("udelta", 0.0)?, f("vdelta", 0.0)?),
    })
}

/// `texture` with its constant parts worked out: a material whose textures are all constant
/// keeps the untextured fast path.
fn folded(texture: Texture) -> Texture {
    let constant = |t: &Texture| t.as_constant();
    match &texture {
        Texture::Scale(a, b) => match (constant(a), constant(b)) {
            (Some(a), Some(b)) => Texture::Constant(a * b),
            _ => texture,
        },
        Texture::Mix {
            first,
            second,
            amount,
        } => match (constant(first), constant(second), constant(amount)) {
            (Some(a), Some(b), Some(t)) => Texture::Constant((Vec3::ONE - t) * a + t * b),
            _ => texture,
        },
        Texture::Checkerboard { even, odd, .. } => match (constant(even), constant(odd)) {
            (Some(a), Some(b)) if a == b => Texture::Constant(a),
            _ => texture,
        },
        _ => texture,
    }
}
