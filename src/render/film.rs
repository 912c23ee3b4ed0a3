//! The film: the running mean of a progressive render. Per pixel and channel it holds the sum,
//! in f64, of every pass's value, and the set of passes summed; its header names the scene (by
//! content hash), the seed, the settings and the resolved base radii, so that films of one
//! render made in different runs or on different machines can be merged, and films of
//! different renders cannot. Layers: the image and its direct, caustic and indirect parts
//! (RGB each) and, with the diffusion estimate, the kernel field; the RGB layers resolve through
//! the scene's image response (pbrt's film scale and white balance). Owns accumulation, merging
//! and resolving to images; must not shade, trace or touch files (that is [`super::film_file`]).

use super::pass::{BaseRadii, RenderSettings};
use crate::image_io::Image;
use crate::scene::ImageResponse;
use glam::Vec3;
use std::fmt;

/// The RGB layers every film holds, in channel order.
pub const RGB_LAYERS: [&str; 4] = ["image", "direct", "caustic", "indirect"];
/// The kernel-field channels (diffusion estimate only): mean λ2, the mean of the edge
/// direction's doubled angle as a vector weighted by 1 − λ2 (an edge direction is modulo 180°),
/// and mean λ1: below 1 where the kernel shrank along the edge too (a crossing or a fold, with
/// `--crossings shrink`), 1 where it kept its length.
pub const KERNEL_CHANNELS: [&str; 4] = ["lambda2", "edge_cos2", "edge_sin2", "lambda1"];

/// Everything that must agree for two films to be parts of one render.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FilmHeader {
    /// The scene file as given (for messages; not compared).
    pub scene_file: String,
    /// Hash of the loaded scene (lights, materials, geometry, camera).
    #[serde(with = "hex_u64")]
    pub scene_hash: u64,
    #[serde(with = "hex_u64")]
    pub seed: u64,
    pub width: usize,
    pub height: usize,
    pub settings: RenderSettings,
    /// The base radii every pass scales (resolved from pass 0's maps when not given).
    pub radii: BaseRadii,
    /// Whether the film carries the kernel-field channels.
    pub kernel_field: bool,
    /// What the written image's pixels are multiplied by (the scene's film settings); left
    /// out of the file when it is the identity, so such films keep their bytes.
    #[serde(default, skip_serializing_if = "ImageResponse::is_identity")]
    pub response: ImageResponse,
}

/// The first field (as the film file names it, `estimator.k` for a nested one) in which two
/// renders' settings differ, so that a refusal says which flag to give: a film written before
/// a default changed differs in that default.
fn settings_difference(a: &RenderSettings, b: &RenderSettings) -> Option<String> {
    let (a, b) = (serde_json::to_value(a).ok()?, serde_json::to_value(b).ok()?);
    fn first(a: &serde_json::Value, b: &serde_json::Value, prefix: &str) -> Option<String> {
        let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
            return (a != b).then(|| prefix.to_string());
        };
        let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
        keys.sort();
        keys.dedup();
        keys.into_iter().find_map(|key| {
            let null = serde_json::Value::Null;
            let (x, y) = (a.get(key).unwrap_or(&null), b.get(key).unwrap_or(&null));
            let name = if prefix.is_empty() {
                key.clone()
            } else {
                format!("{prefix}.{key}")
            };
            (x != y).then(|| first(x, y, &name)).flatten()
        })
    }
    first(&a, &b, "")
}

impl FilmHeader {
    /// The first field in which `other` differs, for a merge's error message.
    pub fn first_difference(&self, other: &FilmHeader) -> Option<String> {
        let what = if self.scene_hash != other.scene_hash {
            "scene"
        } else if self.seed != other.seed {
            "seed"
        } else if (self.width, self.height) != (other.width, other.height) {
            "resolution"
        } else if self.settings != other.settings {
            return Some(match settings_difference(&self.settings, &other.settings) {
                Some(field) => format!("settings ({field})"),
                None => "settings".into(),
            });
        } else if self.radii != other.radii {
            "radii"
        } else if self.kernel_field != other.kernel_field {
            "kernel field"
        } else if self.response != other.response {
            "image response (film scale, exposure or white balance)"
        } else {
            return None;
        };
        Some(what.into())
    }

    pub fn channels(&self) -> usize {
        3 * RGB_LAYERS.len()
            + if self.kernel_field {
                KERNEL_CHANNELS.len()
            } else {
                0
            }
    }
}

/// Hex strings for u64 fields: TOML integers stop at 2⁶³ − 1.
mod hex_u64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{v:016x}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let text = String::deserialize(d)?;
        u64::from_str_radix(&text, 16).map_err(serde::de::Error::custom)
    }
}

/// A set of pass indices as sorted, disjoint, non-adjacent half-open ranges.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct PassSet {
    ranges: Vec<(u64, u64)>,
}

impl PassSet {
    pub fn from_ranges(ranges: &[(u64, u64)]) -> Result<Self, String> {
        let mut set = PassSet::default();
        for &(a, b) in ranges {
            if a >= b {
                return Err(format!("empty pass range [{a}, {b})"));
            }
            set.insert(a..b)
                .map_err(|p| format!("pass {p} is listed twice"))?;
        }
        Ok(set)
    }

    /// Adds `passes`; on overlap adds nothing and returns the first pass already held.
    pub fn insert(&mut self, passes: std::ops::Range<u64>) -> Result<(), u64> {
        if let Some(p) = self.first_common(&[(passes.start, passes.end)]) {
            return Err(p);
        }
        self.ranges.push((passes.start, passes.end));
        self.ranges.sort_unstable();
        let mut merged: Vec<(u64, u64)> = Vec::with_capacity(self.ranges.len());
        for &(a, b) in &self.ranges {
            match merged.last_mut() {
                Some(last) if last.1 == a => last.1 = b,
                _ => merged.push((a, b)),
            }
        }
        self.ranges = merged;
        Ok(())
    }

    fn first_common(&self, other: &[(u64, u64)]) -> Option<u64> {
        let mut first = None;
        for &(a, b) in &self.ranges {
            for &(c, d) in other {
                let (lo, hi) = (a.max(c), b.min(d));
                if lo < hi {
                    first = Some(first.map_or(lo, |f: u64| f.min(lo)));
                }
            }
        }
        first
    }

    pub fn contains(&self, pass: u64) -> bool {
        self.ranges.iter().any(|&(a, b)| a <= pass && pass < b)
    }

    pub fn count(&self) -> u64 {
        self.ranges.iter().map(|(a, b)| b - a).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.ranges.is_empty()
    }

    pub fn ranges(&self) -> &[(u64, u64)] {
        &self.ranges
    }

    /// One past the highest pass held (0 when empty).
    pub fn end(&self) -> u64 {
        self.ranges.last().map_or(0, |r| r.1)
    }

    /// The gaps below the highest pass held: the passes a merge still lacks.
    pub fn missing(&self) -> Vec<(u64, u64)> {
        let mut gaps = Vec::new();
        let mut at = 0;
        for &(a, b) in &self.ranges {
            if a > at {
                gaps.push((at, a));
            }
            at = b;
        }
        gaps
    }
}

impl fmt::Display for PassSet {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let parts: Vec<String> = self.ranges.iter().map(|r| range_text(*r)).collect();
        write!(f, "{}", parts.join(", "))
    }
}

/// `[a, b)` as "a" or "a-(b−1)".
pub fn range_text((a, b): (u64, u64)) -> String {
    if b == a + 1 {
        format!("{a}")
    } else {
        format!("{a}-{}", b - 1)
    }
}

/// One pass's values: every channel of every pixel (pixel-major), the mean of its samples.
#[derive(Clone, Debug, PartialEq)]
pub struct PassImage {
    pub width: usize,
    pub height: usize,
    pub channels: usize,
    pub values: Vec<f32>,
}

impl PassImage {
    pub fn new(width: usize, height: usize, channels: usize) -> Self {
        Self {
            width,
            height,
            channels,
            values: vec![0.0; width * height * channels],
        }
    }

    pub fn pixel_mut(&mut self, index: usize) -> &mut [f32] {
        &mut self.values[index * self.channels..(index + 1) * self.channels]
    }

    /// RGB layer `layer` (index into [`RGB_LAYERS`]) as an image.
    pub fn layer(&self, layer: usize) -> Image {
        Image::from_fn(self.width, self.height, |x, y| {
            let v = &self.values[(y * self.width + x) * self.channels + 3 * layer..];
            Vec3::new(v[0], v[1], v[2])
        })
    }
}

/// Why two films cannot be combined, or a pass cannot be added.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum FilmError {
    #[error("both hold pass {0}")]
    Overlap(u64),
    #[error("they differ in {0}")]
    Mismatch(String),
    #[error(
        "the pass image is {got_w}x{got_h} with {got_c} channels; the film is {w}x{h} with {c}"
    )]
    Shape {
        got_w: usize,
        got_h: usize,
        got_c: usize,
        w: usize,
        h: usize,
        c: usize,
    },
}

/// The running mean of a render's passes.
#[derive(Clone, Debug, PartialEq)]
pub struct Film {
    pub header: FilmHeader,
    passes: PassSet,
    sums: Vec<f64>,
}

impl Film {
    pub fn new(header: FilmHeader) -> Self {
        let n = header.width * header.height * header.channels();
        Self {
            header,
            passes: PassSet::default(),
            sums: vec![0.0; n],
        }
    }

    /// A film from stored parts (the film file reader); `sums` must have the header's size.
    pub fn from_parts(header: FilmHeader, passes: PassSet, sums: Vec<f64>) -> Self {
        assert_eq!(sums.len(), header.width * header.height * header.channels());
        Self {
            header,
            passes,
            sums,
        }
    }

    pub fn passes(&self) -> &PassSet {
        &self.passes
    }

    pub fn sums(&self) -> &[f64] {
        &self.sums
    }

    /// Adds pass `pass`'s image.
    pub fn add_pass(&mut self, pass: u64, image: &PassImage) -> Result<(), FilmError> {
        let (w, h, c) = (
            self.header.width,
            self.header.height,
            self.header.channels(),
        );
        if (image.width, image.height, image.channels) != (w, h, c) {
            return Err(FilmError::Shape {
                got_w: image.width,
                got_h: image.height,
                got_c: image.channels,
                w,
                h,
                c,
            });
        }
        self.passes
            .insert(pass..pass + 1)
            .map_err(FilmError::Overlap)?;
        for (s, v) in self.sums.iter_mut().zip(&image.values) {
            *s += *v as f64;
        }
        Ok(())
    }

    /// Adds another film of the same render with disjoint passes.
    pub fn merge(&mut self, other: &Film) -> Result<(), FilmError> {
        if let Some(field) = self.header.first_difference(&other.header) {
            return Err(FilmError::Mismatch(field));
        }
        if let Some(p) = self.passes.first_common(other.passes.ranges()) {
            return Err(FilmError::Overlap(p));
        }
        for &(a, b) in other.passes.ranges() {
            self.passes.insert(a..b).expect("checked disjoint");
        }
        for (s, v) in self.sums.iter_mut().zip(&other.sums) {
            *s += *v;
        }
        Ok(())
    }

    /// The mean of channels `first..first + 3` over the passes held, through `response`.
    fn mean_rgb(&self, first: usize, response: &ImageResponse) -> Image {
        let (w, c) = (self.header.width, self.header.channels());
        let inv = 1.0 / self.passes.count().max(1) as f64;
        let identity = response.is_identity();
        Image::from_fn(w, self.header.height, |x, y| {
            let s = &self.sums[(y * w + x) * c + first..];
            let mean = [s[0] * inv, s[1] * inv, s[2] * inv];
            let [r, g, b] = if identity { mean } else { response.apply(mean) };
            Vec3::new(r as f32, g as f32, b as f32)
        })
    }

    /// The image: the mean of the passes, through the scene's image response.
    pub fn image(&self) -> Image {
        self.mean_rgb(0, &self.header.response)
    }

    /// RGB layer `name` of [`RGB_LAYERS`], through the scene's image response.
    pub fn layer(&self, name: &str) -> Option<Image> {
        let i = RGB_LAYERS.iter().position(|l| *l == name)?;
        Some(self.mean_rgb(3 * i, &self.header.response))
    }

    /// The kernel field's mean channels (λ2, edge cos 2θ, edge sin 2θ), when the film has them.
    pub fn kernel_channels(&self) -> Option<Image> {
        self.header
            .kernel_field
            .then(|| self.mean_rgb(3 * RGB_LAYERS.len(), &ImageResponse::default()))
    }

    /// Kernel-field channel `name` of [`KERNEL_CHANNELS`] (the mean over passes, row-major),
    /// when the film has the kernel field.
    pub fn kernel_channel(&self, name: &str) -> Option<Vec<f32>> {
        let i = KERNEL_CHANNELS.iter().position(|k| *k == name)?;
        if !self.header.kernel_field {
            return None;
        }
        let (first, c) = (3 * RGB_LAYERS.len() + i, self.header.channels());
        let inv = 1.0 / self.passes.count().max(1) as f64;
        Some(
            self.sums
                .chunks_exact(c)
                .map(|px| (px[first] * inv) as f32)
                .collect(),
        )
    }

    /// The kernel field as a picture (hue: edge direction, brightness: 1 − λ2), when present.
    pub fn kernel_field_picture(&self) -> Option<Image> {
        let k = self.kernel_channels()?;
        Some(Image::from_fn(k.width, k.height, |x, y| {
            let v = k.get(x, y);
            crate::estimate::diffusion::field_colour::colour(v.z.atan2(v.y) * 0.5, v.x)
        }))
    }
}
