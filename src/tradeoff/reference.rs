//! `dpm reference`: the reference image a scene's sweep is scored against, rendered once with
//! many more photons and a smaller radius than any run of the sweep, and cached on disk. Owns
//! the command's flags, the reference settings, the cache key and the cache file; it renders
//! through [`SceneTarget`] and must not shade, trace or score anything itself.
//!
//! Settings and why: the reference is the caustic contribution (see [`super::scene_target`])
//! estimated with the isotropic Epanechnikov kernel, which favours none of the estimates
//! compared, from `--photons` stored caustic photons (default 4,000,000: 20× the default
//! sweep's largest count, 200,000) at the k-equivalent radius for `--k` = 2000 in that map.
//! Against the sweep's largest map at dpm's default radius (k = 400) that is half the radius
//! (√(2000/400 ÷ 20) = 0.5), so a quarter of the bias (bias grows as r²), with 5× the photons
//! in each disc, so 0.45× the noise. Half the radius and not a quarter: with 20× the photons a
//! quarter radius leaves 1.25× the photons per disc, and the reference's own noise would be as
//! large as the errors it is meant to measure.
//!
//! Cache: `<cache-dir>/<scene stem>-<key>.pfm` (linear RGB), where the key is an FNV-1a 64 hash
//! of the scene file's bytes, the loaded scene's fingerprint (lights, materials, geometry, so
//! an edited OBJ file changes it too) and every setting above plus the resolution and seed. An
//! unchanged scene and settings reuse the file; anything else renders a new one.

use super::scene_target::{SceneTarget, SceneTargetError};
use crate::estimate::classic::FixedRadiusEstimate;
use crate::estimate::kernel::RadialKernel;
use crate::estimate::settings::k_equivalent_radius;
use crate::image_io::{self, Image, ImageError, WriteOptions};
use crate::photon::store::{Fnv64, scene_fingerprint};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub const DEFAULT_PHOTONS: u64 = 4_000_000;
pub const DEFAULT_K: u64 = 2000;
/// How many times the sweep's largest photon count `dpm tradeoff` asks the reference for.
pub const PHOTON_FACTOR: usize = 20;

#[derive(Clone, Debug, clap::Args)]
pub struct ReferenceArgs {
    /// Scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Stored caustic photons of the reference (20× the default sweep's largest count).
    #[arg(long, default_value_t = DEFAULT_PHOTONS, value_parser = clap::value_parser!(u64).range(1..))]
    pub photons: u64,
    /// The reference radius is the k-equivalent radius for this k in the reference map
    /// (2000: half the default radius of a map with 20× fewer photons).
    #[arg(long, default_value_t = DEFAULT_K, value_parser = clap::value_parser!(u64).range(2..))]
    pub k: u64,
    /// Image width (overrides the scene's camera resolution).
    #[arg(long, default_value_t = 320, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub width: u32,
    /// Image height.
    #[arg(long, default_value_t = 240, value_parser = clap::value_parser!(u32).range(1..=16384))]
    pub height: u32,
    /// Seed of the photon paths and pixel samples.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Folder of the cached references (created when missing).
    #[arg(long, default_value = "out/reference")]
    pub cache_dir: PathBuf,
}

/// What a reference is made with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSettings {
    pub photons: usize,
    pub k: usize,
    pub seed: u64,
}

/// A reference image, and whether it came from the cache.
pub struct Reference {
    pub path: PathBuf,
    pub image: Image,
    pub reused: bool,
    /// Rendering time (0 when reused).
    pub seconds: f64,
    /// The radius it was rendered with (`None` when reused).
    pub radius: Option<f32>,
}

#[derive(Debug, thiserror::Error)]
pub enum ReferenceError {
    #[error("{0}")]
    Target(#[from] SceneTargetError),
    #[error("{}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("--cache-dir {}: {source}", path.display())]
    CacheDir {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{0}")]
    Image(#[from] ImageError),
    #[error(
        "{}: no caustic photons were stored; the lights do not reach a mirror or glass object \
         followed by a diffuse surface",
        .0.display()
    )]
    NoPhotons(PathBuf),
}

impl ReferenceError {
    /// 2 for bad input (the scene, a flag), 1 for failures inside.
    pub fn exit_code(&self) -> u8 {
        match self {
            ReferenceError::Target(SceneTargetError::Embree(_)) => 1,
            ReferenceError::Image(ImageError::Io { .. } | ImageError::Encode { .. }) => 1,
            _ => 2,
        }
    }
}

/// Where the reference for `target` made with `settings` is cached.
pub fn cache_path(
    target: &SceneTarget,
    settings: ReferenceSettings,
    cache_dir: &Path,
) -> Result<PathBuf, ReferenceError> {
    let bytes = std::fs::read(&target.path).map_err(|source| ReferenceError::Read {
        path: target.path.clone(),
        source,
    })?;
    let mut h = Fnv64::default();
    h.update(b"dpm reference v1");
    h.update(&(bytes.len() as u64).to_le_bytes());
    h.update(&bytes);
    h.update(&scene_fingerprint(&target.world.description).to_le_bytes());
    for v in [
        settings.photons as u64,
        settings.k as u64,
        settings.seed,
        target.width() as u64,
        target.height() as u64,
    ] {
        h.update(&v.to_le_bytes());
    }
    let stem = target
        .path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    Ok(cache_dir.join(format!("{stem}-{:016x}.pfm", h.finish())))
}

/// The cached reference when its file is there and readable at the right size, else a newly
/// rendered one (written to the cache atomically).
pub fn ensure(
    target: &SceneTarget,
    settings: ReferenceSettings,
    cache_dir: &Path,
) -> Result<Reference, ReferenceError> {
    let path = cache_path(target, settings, cache_dir)?;
    if let Ok(image) = image_io::read_pfm(&path) {
        if image.width == target.width() && image.height == target.height() {
            return Ok(Reference {
                path,
                image,
                reused: true,
                seconds: 0.0,
                radius: None,
            });
        }
    }
    let start = Instant::now();
    let bar = crate::timing::progress(settings.photons as u64, "reference photons");
    let map = target.trace(settings.photons, &bar);
    bar.finish_and_clear();
    if map.is_empty() {
        return Err(ReferenceError::NoPhotons(target.path.clone()));
    }
    let radius = k_equivalent_radius(&map, settings.k).unwrap_or(1.0);
    let estimate = FixedRadiusEstimate::new(RadialKernel::Epanechnikov, radius);
    let image = target.caustic_image(&map, &estimate);
    std::fs::create_dir_all(cache_dir).map_err(|source| ReferenceError::CacheDir {
        path: cache_dir.to_path_buf(),
        source,
    })?;
    image_io::write_image(&path, &image, &WriteOptions::default())?;
    Ok(Reference {
        path,
        image,
        reused: false,
        seconds: start.elapsed().as_secs_f64(),
        radius: Some(radius),
    })
}

/// `dpm reference`: loads the scene and makes sure its reference is cached; returns the report
/// line.
pub fn run(args: &ReferenceArgs) -> Result<String, ReferenceError> {
    let pool = crate::embree::thread_pool(0).expect("the default thread pool builds");
    pool.install(|| {
        crate::embree::enable_flush_to_zero();
        let target = SceneTarget::load(&args.scene, args.width, args.height, args.seed)?;
        let settings = ReferenceSettings {
            photons: args.photons as usize,
            k: args.k as usize,
            seed: args.seed,
        };
        let reference = ensure(&target, settings, &args.cache_dir)?;
        Ok(describe(&reference, settings))
    })
}

/// One line saying where the reference is and whether it was reused.
pub fn describe(reference: &Reference, settings: ReferenceSettings) -> String {
    if reference.reused {
        format!(
            "reference: reused {} ({} photons, k={})",
            reference.path.display(),
            settings.photons,
            settings.k
        )
    } else {
        format!(
            "reference: rendered {} ({} photons, radius {:.5} = k-equivalent for k={}, {:.1} s)",
            reference.path.display(),
            settings.photons,
            reference.radius.unwrap_or(0.0),
            settings.k,
            reference.seconds
        )
    }
}
