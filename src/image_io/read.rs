//! Reading images back as linear RGB: dpm's own outputs (PFM, EXR) for references and merges,
//! and the images scenes name (environment maps, textures), which also come as 8-bit PNG and
//! TGA, decoded from sRGB. Decoding works on bytes, so a scene's images can come from any
//! [`crate::scene::files::SceneFiles`]; every malformed file is an error, never a panic.

use super::{Image, ImageError, ImageFormat};
use glam::Vec3;
use std::ffi::OsStr;
use std::fs::File;
use std::io::{Cursor, Read};
use std::path::Path;

/// Reads a linear image: PFM, or the RGB channels of an EXR's first layer.
pub fn read_image(path: &Path) -> Result<Image, ImageError> {
    match ImageFormat::from_path(path)? {
        ImageFormat::Exr => read_exr_rgb(path),
        _ => read_pfm(path),
    }
}

/// Reads a PFM file (colour "PF" or grey "Pf", either byte order) into an image with row 0 at
/// the top.
pub fn read_pfm(path: &Path) -> Result<Image, ImageError> {
    let mut bytes = Vec::new();
    File::open(path)
        .and_then(|mut f| f.read_to_end(&mut bytes))
        .map_err(|source| ImageError::Io {
            path: path.to_path_buf(),
            source,
        })?;
    decode_pfm(&bytes).map_err(|message| ImageError::BadPfm {
        path: path.to_path_buf(),
        message,
    })
}

fn read_exr_rgb(path: &Path) -> Result<Image, ImageError> {
    let bytes = std::fs::read(path).map_err(|source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    decode_exr(&bytes).map_err(|message| ImageError::Encode {
        path: path.to_path_buf(),
        message,
    })
}

/// The formats a scene's images come in, by the name's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneImageFormat {
    Exr,
    Pfm,
    /// 8-bit, sRGB-encoded.
    Png,
    /// 8-bit, sRGB-encoded.
    Tga,
}

impl SceneImageFormat {
    /// The format `name`'s extension says, if dpm reads it.
    pub fn of(name: &Path) -> Option<Self> {
        let ext = name
            .extension()
            .and_then(OsStr::to_str)?
            .to_ascii_lowercase();
        Some(match ext.as_str() {
            "exr" => Self::Exr,
            "pfm" => Self::Pfm,
            "png" => Self::Png,
            "tga" => Self::Tga,
            _ => return None,
        })
    }

    /// Whether its values are stored sRGB-encoded (8-bit) rather than linear.
    pub fn is_srgb(self) -> bool {
        matches!(self, Self::Png | Self::Tga)
    }
}

/// Decodes `bytes` in `format` to linear RGB, row 0 at the top. With `srgb_decode` false an
/// 8-bit image's values are taken as linear (pbrt's `"bool gamma" false`). Grey images give
/// grey RGB; alpha is dropped.
pub fn decode_linear(
    bytes: &[u8],
    format: SceneImageFormat,
    srgb_decode: bool,
) -> Result<Image, String> {
    decode_linear_within(bytes, format, srgb_decode, MAX_SCENE_TEXELS)
}

/// Texels past this are taken for a corrupt header, not an image (2^28: a 16k × 16k image).
pub const MAX_SCENE_TEXELS: usize = 1 << 28;

/// [`decode_linear`], refusing any image of more than `max_texels` texels before its pixels
/// are allocated (a few compressed bytes can claim a huge image).
pub fn decode_linear_within(
    bytes: &[u8],
    format: SceneImageFormat,
    srgb_decode: bool,
    max_texels: usize,
) -> Result<Image, String> {
    let too_large = |w: usize, h: usize| {
        format!("the image claims {w}x{h} texels, more than the {max_texels} dpm reads")
    };
    match format {
        SceneImageFormat::Exr => {
            let meta = exr::meta::MetaData::read_from_buffered(Cursor::new(bytes), false)
                .map_err(|e| format!("cannot read the EXR: {e}"))?;
            for header in &meta.headers {
                let size = header.layer_size;
                if size.width().saturating_mul(size.height()) > max_texels {
                    return Err(too_large(size.width(), size.height()));
                }
            }
            decode_exr(bytes)
        }
        SceneImageFormat::Pfm => decode_pfm(bytes),
        SceneImageFormat::Png | SceneImageFormat::Tga => {
            let kind = match format {
                SceneImageFormat::Png => image::ImageFormat::Png,
                _ => image::ImageFormat::Tga,
            };
            let (w, h) = image::ImageReader::with_format(Cursor::new(bytes), kind)
                .into_dimensions()
                .map_err(|e| e.to_string())?;
            if (w as usize).saturating_mul(h as usize) > max_texels {
                return Err(too_large(w as usize, h as usize));
            }
            let mut reader = image::ImageReader::with_format(Cursor::new(bytes), kind);
            let mut limits = image::Limits::default();
            // The decoder's own buffers: at most 16 bytes a texel (16-bit RGBA).
            limits.max_alloc = Some((max_texels as u64).saturating_mul(16));
            reader.limits(limits);
            let decoded = reader.decode().map_err(|e| e.to_string())?;
            let rgb = decoded.to_rgb8();
            let (width, height) = (rgb.width() as usize, rgb.height() as usize);
            if width == 0 || height == 0 {
                return Err("the image has no pixels".into());
            }
            let table: Vec<f32> = (0..=255u8)
                .map(|v| {
                    let v = f32::from(v) / 255.0;
                    if srgb_decode { srgb_to_linear(v) } else { v }
                })
                .collect();
            let pixels = rgb
                .pixels()
                .map(|p| {
                    Vec3::new(
                        table[p[0] as usize],
                        table[p[1] as usize],
                        table[p[2] as usize],
                    )
                })
                .collect();
            Ok(Image {
                width,
                height,
                pixels,
            })
        }
    }
}

/// The sRGB transfer function's inverse (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.040_45 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}

fn decode_exr(bytes: &[u8]) -> Result<Image, String> {
    use exr::prelude::{ReadChannels, ReadLayers};
    let image = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _| Image::new(resolution.width(), resolution.height()),
            |image: &mut Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                image.set(pos.x(), pos.y(), Vec3::new(r, g, b))
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| format!("cannot read the EXR: {e}"))?;
    let pixels = image.layer_data.channel_data.pixels;
    if pixels.width == 0 || pixels.height == 0 {
        return Err("the image has no pixels".into());
    }
    Ok(pixels)
}

fn decode_pfm(bytes: &[u8]) -> Result<Image, String> {
    // The header is three whitespace-separated tokens after the magic; exactly one whitespace
    // byte follows the scale, then the raster begins.
    let mut pos = 0;
    let mut token = || -> Result<String, String> {
        while pos < bytes.len() && bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        let start = pos;
        while pos < bytes.len() && !bytes[pos].is_ascii_whitespace() {
            pos += 1;
        }
        if start == pos {
            return Err("header ends early".into());
        }
        let t = String::from_utf8_lossy(&bytes[start..pos]).into_owned();
        pos += 1;
        Ok(t)
    };
    let channels = match token()?.as_str() {
        "PF" => 3,
        "Pf" => 1,
        other => return Err(format!("magic is {other:?}, expected \"PF\" or \"Pf\"")),
    };
    let width: usize = token()?.parse().map_err(|_| "bad width".to_string())?;
    let height: usize = token()?.parse().map_err(|_| "bad height".to_string())?;
    let scale: f32 = token()?.parse().map_err(|_| "bad scale".to_string())?;
    if width == 0 || height == 0 || scale == 0.0 || !scale.is_finite() {
        return Err(format!("bad header: {width}x{height}, scale {scale}"));
    }
    let little_endian = scale < 0.0;
    let raster = &bytes[pos.min(bytes.len())..];
    let expected = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(channels * 4))
        .ok_or("image too large")?;
    if raster.len() < expected {
        return Err(format!(
            "raster has {} bytes, expected {expected}",
            raster.len()
        ));
    }
    let floats: Vec<f32> = raster[..expected]
        .chunks_exact(4)
        .map(|b| {
            let b = [b[0], b[1], b[2], b[3]];
            if little_endian {
                f32::from_le_bytes(b)
            } else {
                f32::from_be_bytes(b)
            }
        })
        .collect();
    // The file's first row is the bottom of the image.
    Ok(Image::from_fn(width, height, |x, y| {
        let i = ((height - 1 - y) * width + x) * channels;
        if channels == 3 {
            Vec3::new(floats[i], floats[i + 1], floats[i + 2])
        } else {
            Vec3::splat(floats[i])
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 77-byte PNG whose header claims 2 × 11,403,255 texels (found by the `image` fuzz target; its header's CRC made right, as the fuzz build does not check it).
    const HUGE_PNG: &[u8] = &[
        137, 80, 78, 71, 13, 10, 26, 10, 0, 0, 0, 13, 73, 72, 68, 82, 0, 0, 0, 2, 0, 173, 255, 247,
        8, 2, 0, 0, 0, 27, 245, 170, 180, 0, 0, 42, 19, 73, 68, 65, 84, 120, 156, 99, 8, 2, 0, 0,
        0, 253, 212, 154, 115, 0, 0, 0, 19, 73, 99, 248, 207, 192, 192, 0, 194, 253, 212, 154, 115,
        0, 0, 0, 19, 66, 96, 130,
    ];

    #[test]
    fn an_image_claiming_more_texels_than_allowed_is_refused_before_it_is_allocated() {
        let e = decode_linear_within(HUGE_PNG, SceneImageFormat::Png, true, 1 << 18).unwrap_err();
        assert!(e.contains("claims 2x11403255"), "{e}");
        // Within the scene limit it is read as far as its data goes, and fails there.
        assert!(decode_linear(HUGE_PNG, SceneImageFormat::Png, true).is_err());
    }
}
