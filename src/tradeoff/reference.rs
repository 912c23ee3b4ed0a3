//! `dpm reference`: the reference image a scene's sweep is scored against, a long progressive
//! run of a consistent estimate, cached on disk. Owns the command's flags, the reference
//! settings, the cache key and the cache file; it renders through [`SceneTarget`] and must not
//! shade, trace or score anything itself.
//!
//! Settings and why: the reference is the caustic contribution (see [`super::scene_target`])
//! estimated with the isotropic Epanechnikov kernel, which favours none of the estimates
//! compared, made progressive (Knaus and Zwicker; [`crate::render::schedule`]): `--passes`
//! passes (default 64) of `--photons` fresh caustic photons each (default 1,000,000), the
//! radius starting at the k-equivalent radius for `--k` = 1000 in pass 0's map and shrinking as
//! r²(i+1) = r²(i)·(i+α)/(i+1), α = 2/3. Its bias and noise both keep falling with passes, so
//! unlike a one-shot isotropic estimate at any radius it does not blur folded caustics into
//! the sharp estimates' error. After 64 passes the radius is half the starting one, a third of
//! the sweep's default radius at its largest count, over 64M photons in all. How far it got is
//! reported: the relative MSE between the mean of the first half of the passes and the mean of
//! all of them, which a converged reference drives to zero.
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
use crate::render::schedule::{DEFAULT_ALPHA, Schedule};
use glam::Vec3;
use indicatif::ProgressBar;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub const DEFAULT_PHOTONS: u64 = 1_000_000;
pub const DEFAULT_K: u64 = 1000;
pub const DEFAULT_PASSES: u64 = 64;
/// How many times the sweep's largest photon count `dpm tradeoff` asks each reference pass for.
pub const PHOTON_FACTOR: usize = 5;

#[derive(Clone, Debug, clap::Args)]
pub struct ReferenceArgs {
    /// Scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,
    /// Stored caustic photons of each pass (5× the default sweep's largest count).
    #[arg(long, default_value_t = DEFAULT_PHOTONS, value_parser = clap::value_parser!(u64).range(1..))]
    pub photons: u64,
    /// The starting radius is the k-equivalent radius for this k in pass 0's map.
    #[arg(long, default_value_t = DEFAULT_K, value_parser = clap::value_parser!(u64).range(2..))]
    pub k: u64,
    /// Progressive passes.
    #[arg(long, default_value_t = DEFAULT_PASSES, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub passes: u64,
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
    /// Stored photons per pass.
    pub photons: usize,
    pub k: usize,
    pub passes: u64,
    pub seed: u64,
}

/// A reference image, and whether it came from the cache.
pub struct Reference {
    pub path: PathBuf,
    pub image: Image,
    pub reused: bool,
    /// Rendering time (0 when reused).
    pub seconds: f64,
    /// The starting and final radii (`None` when reused).
    pub radius: Option<(f32, f32)>,
    /// Relative MSE between the mean of the first half of the passes and of all of them
    /// (`None` when reused or with one pass): how much the last half still moved it.
    pub half_change: Option<f64>,
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
    h.update(b"dpm reference v2 progressive");
    h.update(&(bytes.len() as u64).to_le_bytes());
    h.update(&bytes);
    h.update(&scene_fingerprint(&target.world.description).to_le_bytes());
    for v in [
        settings.photons as u64,
        settings.k as u64,
        settings.passes,
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
    if let Ok(image) = image_io::read_pfm(&path)
        && image.width == target.width()
        && image.height == target.height()
    {
        return Ok(Reference {
            path,
            image,
            reused: true,
            seconds: 0.0,
            radius: None,
            half_change: None,
        });
    }
    let start = Instant::now();
    let schedule = Schedule::new(DEFAULT_ALPHA, settings.seed);
    let bar = crate::timing::progress(settings.passes, "reference passes");
    let mut sums = vec![Vec3::ZERO.as_dvec3(); target.width() * target.height()];
    let mut half = None;
    let mut radii = None;
    for pass in 0..settings.passes {
        let map = target.trace(settings.photons, pass, &ProgressBar::hidden());
        if map.is_empty() {
            return Err(ReferenceError::NoPhotons(target.path.clone()));
        }
        let (r0, _) = *radii.get_or_insert_with(|| {
            let r = k_equivalent_radius(&map, settings.k).unwrap_or(1.0);
            (r, r)
        });
        let radius = r0 * schedule.radius_scale(pass);
        radii = Some((r0, radius));
        let estimate = FixedRadiusEstimate::new(RadialKernel::Epanechnikov, radius);
        let image = target.caustic_image(&map, &estimate);
        for (s, p) in sums.iter_mut().zip(&image.pixels) {
            *s += p.as_dvec3();
        }
        if pass + 1 == settings.passes / 2 {
            half = Some(mean_image(target, &sums, pass + 1));
        }
        bar.inc(1);
    }
    bar.finish_and_clear();
    let image = mean_image(target, &sums, settings.passes);
    let half_change = half.map(|h| crate::image_metrics::image_relative_mse(&h, &image));
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
        radius: radii,
        half_change,
    })
}

fn mean_image(target: &SceneTarget, sums: &[glam::DVec3], passes: u64) -> Image {
    Image::from_fn(target.width(), target.height(), |x, y| {
        (sums[y * target.width() + x] / passes as f64).as_vec3()
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
            passes: args.passes,
            seed: args.seed,
        };
        let reference = ensure(&target, settings, &args.cache_dir)?;
        Ok(describe(&reference, settings))
    })
}

/// One line saying where the reference is, whether it was reused, and how far it got.
pub fn describe(reference: &Reference, settings: ReferenceSettings) -> String {
    let what = format!(
        "{} passes of {} photons, k={}",
        settings.passes, settings.photons, settings.k
    );
    if reference.reused {
        return format!("reference: reused {} ({what})", reference.path.display());
    }
    let (r0, r1) = reference.radius.unwrap_or_default();
    format!(
        "reference: rendered {} ({what}; radius {r0:.5} -> {r1:.5}; the last half of the passes \
         moved it by a relative MSE of {}; {:.1} s)",
        reference.path.display(),
        reference
            .half_change
            .map_or("-".to_string(), |c| format!("{c:.2e}")),
        reference.seconds
    )
}
