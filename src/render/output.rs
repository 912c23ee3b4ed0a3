//! What a render writes from its film: the `-o` image (PNG tone-mapped, PFM linear RGB; EXR
//! linear with named layers beside the image: `direct.*`, `caustic.*`, `indirect.*` and, with
//! the diffusion estimate, `kernel.lambda2` and the edge direction), and the kernel-field
//! picture. Every file is written atomically. Owns the mapping from film layers to files; must
//! not accumulate or shade.

use super::film::{Film, KERNEL_CHANNELS, RGB_LAYERS};
use crate::image_io::{
    self, ExrChannel, Image, ImageError, ImageFormat, WriteOptions, write_exr_channels,
};
use std::path::Path;

/// Writes the film's image to `path` (EXR: with every layer).
pub fn write_film_image(path: &Path, film: &Film, exposure: f32) -> Result<(), ImageError> {
    if ImageFormat::from_path(path)? != ImageFormat::Exr {
        let options = WriteOptions {
            exposure,
            ..WriteOptions::default()
        };
        return image_io::write_image(path, &film.image(), &options);
    }
    let (w, h) = (film.header.width, film.header.height);
    let mut channels = Vec::new();
    let mut push_rgb = |prefix: &str, image: &Image| {
        for (c, name) in ["R", "G", "B"].iter().enumerate() {
            channels.push(ExrChannel {
                name: format!("{prefix}{name}"),
                samples: image.pixels.iter().map(|p| p.to_array()[c]).collect(),
            });
        }
    };
    for layer in RGB_LAYERS {
        let image = film.layer(layer).expect("every RGB layer is in every film");
        let prefix = if layer == "image" {
            String::new()
        } else {
            format!("{layer}.")
        };
        push_rgb(&prefix, &image);
    }
    for name in KERNEL_CHANNELS {
        if let Some(samples) = film.kernel_channel(name) {
            channels.push(ExrChannel {
                name: format!("kernel.{name}"),
                samples,
            });
        }
    }
    write_exr_channels(path, w, h, channels)
}

/// Writes the kernel-field picture (hue: edge direction, brightness: 1 − λ2), if the film has it.
pub fn write_kernel_field(path: &Path, film: &Film) -> Result<bool, ImageError> {
    let Some(picture) = film.kernel_field_picture() else {
        return Ok(false);
    };
    image_io::write_image(path, &picture, &WriteOptions::default())?;
    Ok(true)
}
