//! Textures: what a material parameter that varies over a surface is, and its value at a
//! surface point's texture coordinates (u, v). Owns the texture kinds (constant, image,
//! checkerboard, scale, mix), the (u, v) → (s, t) mapping, bilinear image lookup with its wrap
//! modes, and [`TexturedMaterial`], a material some of whose parameters are textures. Must not
//! read files (the scene readers decode images and hand over texels) nor know about rays and
//! hits (the world resolves a hit's (u, v)).
//!
//! Definitions follow pbrt-v3's: an image's t = 0 is its bottom row, a texel's centre lies at
//! half-integer (s·width, t·height), a checkerboard is `tex1` where ⌊s⌋ + ⌊t⌋ is even. Lookups
//! are bilinear on the full-resolution image: dpm's rays carry no differentials, so there is
//! no MIP-map filtering.

use glam::{Vec2, Vec3};
use std::sync::Arc;

/// What a lookup outside [0, 1)² reads (pbrt's `wrap`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Wrap {
    /// The image tiles the plane.
    #[default]
    Repeat,
    /// Black outside the image.
    Black,
    /// The nearest edge texel.
    Clamp,
}

impl Wrap {
    /// By pbrt's name.
    pub fn from_name(name: &str) -> Option<Wrap> {
        match name {
            "repeat" => Some(Wrap::Repeat),
            "black" => Some(Wrap::Black),
            "clamp" => Some(Wrap::Clamp),
            _ => None,
        }
    }
}

/// pbrt's `uv` mapping: (s, t) = (uscale·u + udelta, vscale·v + vdelta).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvMapping {
    pub scale: Vec2,
    pub delta: Vec2,
}

impl Default for UvMapping {
    fn default() -> Self {
        UvMapping {
            scale: Vec2::ONE,
            delta: Vec2::ZERO,
        }
    }
}

impl UvMapping {
    #[inline]
    pub fn map(&self, uv: Vec2) -> Vec2 {
        self.scale * uv + self.delta
    }
}

/// Linear texels, row 0 at the image's top (as files store them), `width × height` of them.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<Vec3>,
}

impl TextureImage {
    /// Texel (x, y) counted from the bottom-left, as (s, t) runs; black outside under
    /// [`Wrap::Black`].
    #[inline]
    fn texel(&self, x: i64, y: i64, wrap: Wrap) -> Vec3 {
        let (w, h) = (self.width as i64, self.height as i64);
        let (x, y) = match wrap {
            Wrap::Repeat => (x.rem_euclid(w), y.rem_euclid(h)),
            Wrap::Clamp => (x.clamp(0, w - 1), y.clamp(0, h - 1)),
            Wrap::Black => {
                if x < 0 || y < 0 || x >= w || y >= h {
                    return Vec3::ZERO;
                }
                (x, y)
            }
        };
        self.texels[((h - 1 - y) * w + x) as usize]
    }

    /// The bilinear interpolation of the four texels around (s, t).
    pub fn bilinear(&self, st: Vec2, wrap: Wrap) -> Vec3 {
        let x = st.x * self.width as f32 - 0.5;
        let y = st.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        // Far outside i64's range a coordinate means nothing; keep the arithmetic defined.
        let (x0, y0) = (x0.clamp(-1e15, 1e15) as i64, y0.clamp(-1e15, 1e15) as i64);
        let t = |dx, dy| self.texel(x0 + dx, y0 + dy, wrap);
        (1.0 - fx) * (1.0 - fy) * t(0, 0)
            + fx * (1.0 - fy) * t(1, 0)
            + (1.0 - fx) * fy * t(0, 1)
            + fx * fy * t(1, 1)
    }

    /// Refuses texels that are not finite numbers (a float file may hold them).
    pub fn check_finite(&self) -> Result<(), String> {
        match self.texels.iter().position(|t| !t.is_finite()) {
            None => Ok(()),
            Some(i) => Err(format!(
                "texel ({}, {}) is not finite",
                i % self.width.max(1),
                i / self.width.max(1)
            )),
        }
    }

    /// The texels' mean.
    pub fn mean(&self) -> Vec3 {
        let sum: glam::DVec3 = self.texels.iter().map(|t| t.as_dvec3()).sum();
        (sum / self.texels.len().max(1) as f64).as_vec3()
    }
}

/// A texture's value at a surface point: RGB for colour textures, the same number in all
/// three channels for float textures.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Constant(Vec3),
    /// `scale × image(s, t)`, then `1 − that` (at least 0) when `invert`.
    Image {
        image: Arc<TextureImage>,
        mapping: UvMapping,
        wrap: Wrap,
        scale: f32,
        invert: bool,
    },
    /// `even` where ⌊s⌋ + ⌊t⌋ is even, else `odd` (pbrt's `tex1`, `tex2`).
    Checkerboard {
        mapping: UvMapping,
        even: Box<Texture>,
        odd: Box<Texture>,
    },
    /// The product of the two.
    Scale(Box<Texture>, Box<Texture>),
    /// `(1 − amount)·first + amount·second`.
    Mix {
        first: Box<Texture>,
        second: Box<Texture>,
        amount: Box<Texture>,
    },
}

impl Texture {
    /// The value at texture coordinates `uv`.
    pub fn evaluate(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image {
                image,
                mapping,
                wrap,
                scale,
                invert,
            } => {
                let v = *scale * image.bilinear(mapping.map(uv), *wrap);
                if *invert {
                    (Vec3::ONE - v).max(Vec3::ZERO)
                } else {
                    v
                }
            }
            Texture::Checkerboard { mapping, even, odd } => {
                let st = mapping.map(uv);
                let cell = st.x.floor() as i64 + st.y.floor() as i64;
                if cell.rem_euclid(2) == 0 {
                    even.evaluate(uv)
                } else {
                    odd.evaluate(uv)
                }
            }
            Texture::Scale(a, b) => a.evaluate(uv) * b.evaluate(uv),
            Texture::Mix {
                first,
                second,
                amount,
            } => {
                let t = amount.evaluate(uv);
                (Vec3::ONE - t) * first.evaluate(uv) + t * second.evaluate(uv)
            }
        }
    }

    /// Whether every value it can take is grey (its three channels equal), as a float
    /// texture's are: a colour texture given where one number is read loses nothing.
    pub fn is_grey(&self) -> bool {
        let grey = |c: &Vec3| c.x == c.y && c.y == c.z;
        match self {
            Texture::Constant(c) => grey(c),
            Texture::Image { image, .. } => image.texels.iter().all(grey),
            Texture::Checkerboard { even, odd, .. } => even.is_grey() && odd.is_grey(),
            Texture::Scale(a, b) => a.is_grey() && b.is_grey(),
            Texture::Mix {
                first,
                second,
                amount,
            } => first.is_grey() && second.is_grey() && amount.is_grey(),
        }
    }

    /// The constant this texture is, if it is one.
    pub fn as_constant(&self) -> Option<Vec3> {
        match self {
            Texture::Constant(c) => Some(*c),
            _ => None,
        }
    }

    /// A value standing for the whole texture where one number must do (the fingerprint,
    /// warnings): an image's mean, a checkerboard's two squares' mean, and so on.
    pub fn typical(&self) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::Image {
                image,
                scale,
                invert,
                ..
            } => {
                let v = *scale * image.mean();
                if *invert {
                    (Vec3::ONE - v).max(Vec3::ZERO)
                } else {
                    v
                }
            }
            Texture::Checkerboard { even, odd, .. } => 0.5 * (even.typical() + odd.typical()),
            Texture::Scale(a, b) => a.typical() * b.typical(),
            Texture::Mix {
                first,
                second,
                amount,
            } => {
                let t = amount.typical();
                (Vec3::ONE - t) * first.typical() + t * second.typical()
            }
        }
    }

    /// Every image this texture reads, for hashing.
    pub fn images(&self) -> Vec<&TextureImage> {
        match self {
            Texture::Constant(_) => Vec::new(),
            Texture::Image { image, .. } => vec![image],
            Texture::Checkerboard { even, odd, .. } => [even.images(), odd.images()].concat(),
            Texture::Scale(a, b) => [a.images(), b.images()].concat(),
            Texture::Mix {
                first,
                second,
                amount,
            } => [first.images(), second.images(), amount.images()].concat(),
        }
    }
}

/// One number for a colour: a grey colour's channel exactly, else the channels' mean.
#[inline]
pub fn channel_mean(c: Vec3) -> f32 {
    if c.x == c.y && c.y == c.z {
        c.x
    } else {
        (c.x + c.y + c.z) / 3.0
    }
}

/// A shape's alpha cut-out (pbrt's float `alpha` and `shadowalpha`): where alpha is 0 the
/// shape is not there, where it is 1 (or more) it is, and in between it is there for that
/// fraction of rays (pbrt-v4's stochastic alpha; pbrt-v3 cuts at exactly 0 only, the same on
/// the binary masks its scenes use). Shadow rays see the product of the two.
#[derive(Clone, Debug, PartialEq)]
pub struct Cutout {
    pub alpha: Texture,
    /// For shadow rays only, as in pbrt-v3.
    pub shadow_alpha: Option<Texture>,
}

impl Cutout {
    /// The fraction of rays that meet the shape at `uv`: closest-hit rays, or shadow rays.
    pub fn coverage(&self, uv: Vec2, shadow: bool) -> f32 {
        let alpha = self.alpha.evaluate(uv).x;
        match (&self.shadow_alpha, shadow) {
            (Some(s), true) => alpha * s.evaluate(uv).x,
            _ => alpha,
        }
    }
}

/// Which of a material's parameters a texture gives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TexturedParameter {
    /// A diffuse material's albedo.
    Albedo,
    /// A mirror's tint.
    Tint,
    ReflectTint,
    TransmitTint,
    /// A glass's index of refraction (a float texture).
    Ior,
    /// A parameter of a BSDF material's model ([`crate::bsdf::Model::set`] keeps it in range).
    Model(crate::bsdf::ModelParameter),
    /// A mix's `amount`: the mean of the texture's channels (a float texture's value), clamped
    /// to [0, 1].
    MixAmount,
}

/// A material (by its index in [`super::SceneDescription::materials`], which holds its
/// untextured values) and the textures that replace some of its parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct TexturedMaterial {
    pub material: u32,
    pub textures: Vec<(TexturedParameter, Texture)>,
}

impl TexturedMaterial {
    /// `base` (the material's untextured values) with its textured parameters evaluated at
    /// `uv`. Colours are clamped to [0, 1] and an index of refraction to at least 1, the
    /// range dpm's materials keep (pbrt clamps reflectances at 0 only); a model's parameters
    /// as [`crate::bsdf::Model::set`] keeps them.
    pub fn evaluate(&self, base: &super::Material, uv: Vec2) -> super::Material {
        use super::Material;
        let mut material = *base;
        for (parameter, texture) in &self.textures {
            let v = texture.evaluate(uv);
            let colour = v.clamp(Vec3::ZERO, Vec3::ONE);
            match (&mut material, parameter) {
                (Material::Diffuse { albedo }, TexturedParameter::Albedo) => *albedo = colour,
                (Material::Mirror { tint }, TexturedParameter::Tint) => *tint = colour,
                (Material::Glass { reflect_tint, .. }, TexturedParameter::ReflectTint) => {
                    *reflect_tint = colour
                }
                (Material::Glass { transmit_tint, .. }, TexturedParameter::TransmitTint) => {
                    *transmit_tint = colour
                }
                (Material::Glass { ior, .. }, TexturedParameter::Ior) => *ior = v.x.max(1.0),
                (Material::Bsdf(model), TexturedParameter::Albedo) => {
                    model.set(crate::bsdf::ModelParameter::Diffuse, v)
                }
                (Material::Bsdf(model), TexturedParameter::Model(p)) => model.set(*p, v),
                (Material::Mix { amount, .. }, TexturedParameter::MixAmount) => {
                    *amount = channel_mean(v).clamp(0.0, 1.0)
                }
                // A parameter the material does not have: the readers never pair them.
                _ => {}
            }
        }
        material
    }
}

#[cfg(test)]
#[path = "texture_tests.rs"]
mod tests;
