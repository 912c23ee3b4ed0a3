//! The image output stage: a linear-RGB [`Image`] and the writers for PNG (tone-mapped sRGB),
//! OpenEXR (linear f32 or f16) and PFM (linear f32), chosen by the file extension, and the
//! readers (`read`: dpm's own PFM/EXR outputs, and the EXR, PFM, PNG and TGA images scenes name). Every write is atomic: the bytes go to a temporary file in the destination directory,
//! which is synced and then renamed over the destination, so an existing file is never left
//! half-overwritten. Owns pixel storage and file formats only; it must not know about photons,
//! estimates, cameras or scenes.

mod read;

pub use read::{
    MAX_SCENE_TEXELS, SceneImageFormat, decode_linear, decode_linear_within, read_image, read_pfm,
    srgb_to_linear,
};

use glam::Vec3;
use std::ffi::OsStr;
use std::fs::{self, File, OpenOptions};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

/// A linear-RGB image; row 0 is the top row, pixels are stored row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// A black image.
    pub fn new(width: usize, height: usize) -> Self {
        Self {
            width,
            height,
            pixels: vec![Vec3::ZERO; width * height],
        }
    }

    /// An image whose pixel at column `x`, row `y` (0 = top) is `f(x, y)`.
    pub fn from_fn(width: usize, height: usize, mut f: impl FnMut(usize, usize) -> Vec3) -> Self {
        let mut pixels = Vec::with_capacity(width * height);
        for y in 0..height {
            for x in 0..width {
                pixels.push(f(x, y));
            }
        }
        Self {
            width,
            height,
            pixels,
        }
    }

    /// A grey image from one value a pixel (row 0 = top).
    pub fn from_grey(width: usize, height: usize, values: &[f32]) -> Self {
        assert_eq!(values.len(), width * height, "one value a pixel");
        Self {
            width,
            height,
            pixels: values.iter().map(|&v| Vec3::splat(v)).collect(),
        }
    }

    pub fn get(&self, x: usize, y: usize) -> Vec3 {
        self.pixels[y * self.width + x]
    }

    pub fn set(&mut self, x: usize, y: usize, value: Vec3) {
        self.pixels[y * self.width + x] = value;
    }
}

/// The file formats, chosen from the output path's extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    Png,
    Exr,
    Pfm,
}

impl ImageFormat {
    /// The format for `path`'s extension (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Self, ImageError> {
        let ext = path
            .extension()
            .and_then(OsStr::to_str)
            .map(str::to_ascii_lowercase);
        match ext.as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            Some("pfm") => Ok(Self::Pfm),
            _ => Err(ImageError::UnknownExtension {
                path: path.to_path_buf(),
                extension: ext.unwrap_or_default(),
            }),
        }
    }
}

/// Sample precision of an EXR file.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ExrPrecision {
    #[default]
    F32,
    F16,
}

/// What to do with NaN or infinite pixels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NonFinitePolicy {
    /// Refuse to write: a non-finite pixel means a bug upstream, and the error names it.
    #[default]
    Reject,
    /// Write zero in their place.
    Zero,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WriteOptions {
    /// Exposure in stops, applied before the PNG tone map (linear formats ignore it).
    pub exposure: f32,
    pub exr_precision: ExrPrecision,
    pub non_finite: NonFinitePolicy,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self {
            exposure: 0.0,
            exr_precision: ExrPrecision::F32,
            non_finite: NonFinitePolicy::Reject,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: unknown image extension {extension:?} (expected .png, .exr or .pfm)")]
    UnknownExtension { path: PathBuf, extension: String },
    #[error("{path}: output directory {dir} does not exist")]
    MissingDirectory { path: PathBuf, dir: PathBuf },
    #[error("{path}: pixel ({x}, {y}) is not finite ({value}); {count} non-finite pixels in all")]
    NonFinite {
        path: PathBuf,
        x: usize,
        y: usize,
        value: Vec3,
        count: usize,
    },
    #[error("{path}: image is {width}x{height} but holds {pixels} pixels")]
    BadDimensions {
        path: PathBuf,
        width: usize,
        height: usize,
        pixels: usize,
    },
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: io::Error },
    #[error("{path}: {message}")]
    Encode { path: PathBuf, message: String },
    #[error("{path}: not a PFM file: {message}")]
    BadPfm { path: PathBuf, message: String },
}

/// Writes `image` to `path` in the format its extension names, atomically.
pub fn write_image(path: &Path, image: &Image, options: &WriteOptions) -> Result<(), ImageError> {
    let format = ImageFormat::from_path(path)?;
    if image.pixels.len() != image.width * image.height || image.width == 0 || image.height == 0 {
        return Err(ImageError::BadDimensions {
            path: path.to_path_buf(),
            width: image.width,
            height: image.height,
            pixels: image.pixels.len(),
        });
    }
    let pixels = finite_pixels(path, image, options.non_finite)?;
    let image = Image {
        width: image.width,
        height: image.height,
        pixels,
    };
    write_atomically(path, |out| match format {
        ImageFormat::Pfm => encode_pfm(&image, out),
        ImageFormat::Png => encode_png(&image, options.exposure, out),
        ImageFormat::Exr => encode_exr(&image, options.exr_precision, out),
    })
}

fn finite_pixels(
    path: &Path,
    image: &Image,
    policy: NonFinitePolicy,
) -> Result<Vec<Vec3>, ImageError> {
    let mut first = None;
    let mut count = 0;
    let pixels = image
        .pixels
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            if p.is_finite() {
                return p;
            }
            count += 1;
            first.get_or_insert((i, p));
            Vec3::ZERO
        })
        .collect();
    match (first, policy) {
        (Some((i, value)), NonFinitePolicy::Reject) => Err(ImageError::NonFinite {
            path: path.to_path_buf(),
            x: i % image.width,
            y: i / image.width,
            value,
            count,
        }),
        _ => Ok(pixels),
    }
}

/// The directory an output at `path` would be written into (`.` for a bare file name), when it
/// does not exist: every writer checks this before work starts, so a typo costs nothing.
pub fn missing_output_directory(path: &Path) -> Option<&Path> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    (!dir.is_dir()).then_some(dir)
}

/// Runs `encode` on a temporary file beside `path`, syncs it and renames it to `path`. On any
/// failure the temporary file is removed and `path` is left as it was.
pub fn write_atomically(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<File>) -> Result<(), String>,
) -> Result<(), ImageError> {
    let io_error = |source| ImageError::Io {
        path: path.to_path_buf(),
        source,
    };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    if !dir.is_dir() {
        return Err(ImageError::MissingDirectory {
            path: path.to_path_buf(),
            dir,
        });
    }
    let (temp_path, file) = create_temp_file(&dir, path).map_err(io_error)?;
    let result = (|| {
        let mut out = BufWriter::new(file);
        encode(&mut out).map_err(|message| ImageError::Encode {
            path: path.to_path_buf(),
            message,
        })?;
        let file = out.into_inner().map_err(|e| io_error(e.into_error()))?;
        file.sync_all().map_err(io_error)?;
        drop(file);
        fs::rename(&temp_path, path).map_err(io_error)
    })();
    if result.is_err() {
        let _ = fs::remove_file(&temp_path);
        return result;
    }
    // Make the rename itself durable; not every platform can sync a directory, so this is
    // best effort.
    if let Ok(d) = File::open(&dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

fn create_temp_file(dir: &Path, path: &Path) -> io::Result<(PathBuf, File)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let name = path.file_name().and_then(OsStr::to_str).unwrap_or("image");
    loop {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let temp = dir.join(format!(".{name}.{}.{n}.tmp", std::process::id()));
        match OpenOptions::new().write(true).create_new(true).open(&temp) {
            Ok(f) => return Ok((temp, f)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
}

/// PFM: "PF", width and height, a negative scale for little-endian, then float RGB rows from the
/// bottom row to the top.
fn encode_pfm(image: &Image, out: &mut impl Write) -> Result<(), String> {
    let mut bytes = format!("PF\n{} {}\n-1.0\n", image.width, image.height).into_bytes();
    bytes.reserve(image.pixels.len() * 12);
    for row in image.pixels.chunks(image.width).rev() {
        for p in row {
            for c in p.to_array() {
                bytes.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out.write_all(&bytes).map_err(|e| e.to_string())
}

/// Linear value to an 8-bit sRGB code after `exposure` stops, clamped to [0, 1].
pub fn tone_map(linear: f32, exposure: f32) -> u8 {
    let v = (linear * exposure.exp2()).clamp(0.0, 1.0);
    let srgb = if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    };
    (srgb * 255.0 + 0.5) as u8
}

fn encode_png(image: &Image, exposure: f32, out: &mut BufWriter<File>) -> Result<(), String> {
    use image::ImageEncoder;
    let bytes: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| p.to_array().map(|c| tone_map(c, exposure)))
        .collect();
    image::codecs::png::PngEncoder::new(out)
        .write_image(
            &bytes,
            image.width as u32,
            image.height as u32,
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| e.to_string())
}

fn encode_exr(
    image: &Image,
    precision: ExrPrecision,
    out: &mut BufWriter<File>,
) -> Result<(), String> {
    use exr::prelude::{Image as ExrImage, SpecificChannels, WritableImage};
    let size = (image.width, image.height);
    let at = |pos: exr::math::Vec2<usize>| image.pixels[pos.1 * image.width + pos.0];
    let result = match precision {
        ExrPrecision::F32 => {
            let channels = SpecificChannels::rgb(|pos| {
                let p = at(pos);
                (p.x, p.y, p.z)
            });
            ExrImage::from_channels(size, channels)
                .write()
                .to_buffered(out)
        }
        ExrPrecision::F16 => {
            let channels = SpecificChannels::rgb(|pos| {
                let p = at(pos);
                (
                    half::f16::from_f32(p.x),
                    half::f16::from_f32(p.y),
                    half::f16::from_f32(p.z),
                )
            });
            ExrImage::from_channels(size, channels)
                .write()
                .to_buffered(out)
        }
    };
    result.map_err(|e| e.to_string())
}

/// One named channel of a multi-channel EXR: full-resolution f32 samples, row 0 at the top.
pub struct ExrChannel {
    /// `R`, `G`, `B` for the main image; `layer.R` style names for the rest (OpenEXR's
    /// convention, which pbrt-v4, Mitsuba and OpenImageIO read as layers).
    pub name: String,
    pub samples: Vec<f32>,
}

/// Writes a linear-float EXR with the given channels (each `width × height`), atomically.
/// Non-finite samples are refused, as for every image.
pub fn write_exr_channels(
    path: &Path,
    width: usize,
    height: usize,
    channels: Vec<ExrChannel>,
) -> Result<(), ImageError> {
    use exr::prelude::{
        AnyChannel, AnyChannels, Encoding, FlatSamples, Image as ExrImage, Layer, LayerAttributes,
        SmallVec, WritableImage,
    };
    for c in &channels {
        assert_eq!(c.samples.len(), width * height, "channel {}", c.name);
        if let Some(i) = c.samples.iter().position(|v| !v.is_finite()) {
            return Err(ImageError::NonFinite {
                path: path.to_path_buf(),
                x: i % width.max(1),
                y: i / width.max(1),
                value: Vec3::splat(c.samples[i]),
                count: c.samples.iter().filter(|v| !v.is_finite()).count(),
            });
        }
    }
    let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = channels
        .into_iter()
        .map(|c| AnyChannel::new(c.name.as_str(), FlatSamples::F32(c.samples)))
        .collect();
    let layer = Layer::new(
        (width, height),
        LayerAttributes::default(),
        Encoding::FAST_LOSSLESS,
        AnyChannels::sort(list),
    );
    write_atomically(path, |out| {
        ExrImage::from_layer(layer)
            .write()
            .to_buffered(out)
            .map_err(|e| e.to_string())
    })
}
