//! The TOML format's textures: a material colour given as a table, `{ image = "wood.png", ...
//! }` or `{ checkerboard = [[r, g, b], [r, g, b]], ... }` (docs/scene-format.md#textures).
//! Owns checking such a table and reading its image (EXR, PFM, PNG, TGA) through
//! [`SceneFiles`]; errors name the scene file, the line and the field. Must not evaluate
//! textures.

use super::document::{Document, child_path};
use super::files::SceneFiles;
use super::format::{ColourSpec, TextureSpec};
use super::texture::{TextureImage, UvMapping, Wrap};
use super::{SceneError, Texture};
use crate::image_io::{SceneImageFormat, decode_linear};
use glam::{Vec2, Vec3};
use std::path::Path;
use std::sync::Arc;

/// Texels past this are taken for a corrupt header, not a texture.
const MAX_TEXELS: usize = 1 << 28;

/// Where a TOML scene's images come from.
pub(crate) struct ImageSource<'a> {
    pub folder: &'a Path,
    pub files: &'a dyn SceneFiles,
}

/// The colour at `path`: its value, or a texture's typical value (clamped to [0, 1], what the
/// material's untextured copy holds) and the texture.
pub(crate) fn colour(
    doc: &Document,
    path: &str,
    spec: &ColourSpec,
    images: &ImageSource,
) -> Result<(Vec3, Option<Texture>), SceneError> {
    let spec = match spec {
        ColourSpec::Rgb(rgb) => return Ok((Vec3::from_array(*rgb), None)),
        ColourSpec::Texture(spec) => spec,
    };
    let texture = texture(doc, path, spec, images)?;
    Ok((
        texture.typical().clamp(Vec3::ZERO, Vec3::ONE),
        Some(texture),
    ))
}

/// The texture a texture table at `path` describes.
pub(crate) fn texture(
    doc: &Document,
    path: &str,
    spec: &TextureSpec,
    images: &ImageSource,
) -> Result<Texture, SceneError> {
    let field = |name: &str| child_path(path, name);
    let finite = |name: &str, xs: &[f32]| {
        if xs.iter().all(|x| x.is_finite()) {
            Ok(())
        } else {
            Err(doc.error(&field(name), "must be finite"))
        }
    };
    finite("uv_scale", &spec.uv_scale)?;
    finite("uv_offset", &spec.uv_offset)?;
    finite("scale", &[spec.scale])?;
    let mapping = UvMapping {
        scale: Vec2::from_array(spec.uv_scale),
        delta: Vec2::from_array(spec.uv_offset),
    };
    match (&spec.image, &spec.checkerboard) {
        (Some(file), None) => {
            let wrap = match &spec.wrap {
                None => Wrap::Repeat,
                Some(name) => Wrap::from_name(name).ok_or_else(|| {
                    doc.error(
                        &field("wrap"),
                        format!("`{name}` is not one of \"repeat\", \"black\", \"clamp\""),
                    )
                })?,
            };
            let image = read(doc, &field("image"), file, spec.srgb, images)?;
            Ok(Texture::Image {
                image: Arc::new(image),
                mapping,
                wrap,
                scale: spec.scale,
                invert: spec.invert,
            })
        }
        (None, Some([even, odd])) => {
            finite("checkerboard", &[*even, *odd].concat())?;
            for (name, given) in [
                ("image", spec.wrap.is_some() || spec.srgb.is_some()),
                ("scale", spec.scale != 1.0 || spec.invert),
            ] {
                if given {
                    return Err(doc.error(
                        path,
                        format!("a checkerboard has no {name} settings (wrap, srgb, scale, invert are for images)"),
                    ));
                }
            }
            Ok(Texture::Checkerboard {
                mapping,
                even: Box::new(Texture::Constant(Vec3::from_array(*even))),
                odd: Box::new(Texture::Constant(Vec3::from_array(*odd))),
            })
        }
        _ => Err(doc.error(
            path,
            "a texture table needs exactly one of `image` (a file) and `checkerboard` (two colours)",
        )),
    }
}

/// Reads the image `file` (relative to the scene's folder), linear RGB.
fn read(
    doc: &Document,
    path: &str,
    file: &str,
    srgb: Option<bool>,
    images: &ImageSource,
) -> Result<TextureImage, SceneError> {
    let at = images.folder.join(file);
    let refuse = |message: String| doc.error(path, format!("`{}`: {message}", at.display()));
    let format = SceneImageFormat::of(&at).ok_or_else(|| {
        refuse("dpm reads EXR, PFM, PNG and TGA images (by the name's extension)".into())
    })?;
    let bytes = (images.files.read(&at)).map_err(|e| refuse(format!("cannot read it: {e}")))?;
    let srgb = srgb.unwrap_or(format.is_srgb());
    let image = decode_linear(&bytes, format, srgb).map_err(refuse)?;
    if image.pixels.len() > MAX_TEXELS {
        return Err(refuse(format!(
            "{}x{} is too large",
            image.width, image.height
        )));
    }
    let image = TextureImage {
        width: image.width,
        height: image.height,
        texels: image.pixels,
    };
    image.check_finite().map_err(refuse)?;
    Ok(image)
}
