//! One whole render, as the data flows: scene file → Embree world → photon maps (only those
//! the scene and the chosen render need) → estimate preparation (the diffusion estimate's
//! gradient pass, timed as its own phase) → eye pass → image file, with progress bars and a
//! per-phase timing table. Owns the `dpm render` options; must not implement any stage itself.

use super::integrator::{EstimatedMap, Indirect, Integrator};
use super::{PinholeCamera, render_image};
use crate::embree::{self, EmbreeError};
use crate::estimate::RadianceEstimate;
use crate::estimate::classic::KnnEstimate;
use crate::estimate::diffusion::gradient_pass;
use crate::estimate::kernel::RadialKernel;
use crate::estimate::settings::{
    EstimateError, EstimatorKind, EstimatorSettings, ResolvedEstimator,
};
use crate::image_io::{self, Image, ImageError, ImageFormat, WriteOptions};
use crate::photon::PhotonMap;
use crate::photon::tracer::{MapKind, TraceCounts, trace_map};
use crate::scene::{self, Material, SceneError};
use crate::timing::{PhaseTimes, progress};
use crate::world::World;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene file (TOML; see docs/scene-format.md).
    pub scene: PathBuf,

    /// Output image; the format follows the extension: .png (tone-mapped sRGB), .exr (linear
    /// float RGB), .pfm (linear float RGB). Written atomically. Default: the scene's name with .png.
    #[arg(short, long)]
    pub output: Option<PathBuf>,

    /// Worker threads (0: one per core). The image does not depend on it.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,

    /// Seed of every random number (photon paths and pixel samples).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,

    /// Samples per pixel: the first goes through the pixel centre, the rest are jittered.
    #[arg(long, default_value_t = 1)]
    pub spp: u32,

    /// Exposure in stops for PNG output (linear formats are written unscaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,

    /// Mirror and glass bounces followed from the eye.
    #[arg(long, default_value_t = 10)]
    pub max_depth: u32,

    /// Photons STORED in the caustic map (light → specular+ → diffuse); paths are emitted until
    /// this many are stored. Only built when the scene has a mirror or glass object; 0 turns
    /// caustics off.
    #[arg(long, default_value_t = 1_000_000)]
    pub caustic_photons: usize,

    /// Photons STORED in the global map (indirect diffuse light). Default: 200000 when the scene
    /// has two or more diffuse objects (so diffuse light can bounce between them), else 0 (no
    /// global map: a lone plane cannot light itself).
    #[arg(long)]
    pub global_photons: Option<usize>,

    /// Final-gather rays per diffuse eye hit for indirect light; 0 shows the global map's
    /// estimate directly instead (faster, blotchier).
    #[arg(long, default_value_t = 16)]
    pub final_gather: u32,

    /// Photons per global-map estimate (constant kernel, k-th photon left out).
    #[arg(long, default_value_t = 100)]
    pub global_k: usize,

    /// Caustic radiance estimate.
    #[command(flatten)]
    pub estimate: EstimatorSettings,

    /// Also write the diffusion kernel's shape at each pixel's first diffuse hit (hue = edge
    /// direction, brightness = 1 − λ2), like the paper's Figure 2b. Needs --estimator diffusion.
    #[arg(long)]
    pub kernel_field: Option<PathBuf>,

    /// Write the per-phase times and counts as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,
}

#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    #[error("{0}")]
    Scene(#[from] SceneError),
    #[error("{0}")]
    Estimate(#[from] EstimateError),
    #[error("{0}")]
    Image(#[from] ImageError),
    #[error("{0}")]
    Embree(#[from] EmbreeError),
    #[error("{0}")]
    Invalid(String),
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
}

impl RenderError {
    /// Exit code: 2 for bad input (scene, parameters, output path), 1 for failures inside.
    pub fn exit_code(&self) -> i32 {
        match self {
            RenderError::Embree(_) | RenderError::Io { .. } => 1,
            RenderError::Image(ImageError::Io { .. } | ImageError::Encode { .. }) => 1,
            _ => 2,
        }
    }
}

/// What a render produced.
pub struct RenderOutcome {
    pub image: Image,
    pub output: PathBuf,
    pub times: PhaseTimes,
    pub caustic: Option<TraceCounts>,
    pub global: Option<TraceCounts>,
    pub estimator: Option<String>,
}

/// Checks the options that need no scene, before any work is done.
pub fn validate(args: &RenderArgs) -> Result<PathBuf, RenderError> {
    args.estimate.validate()?;
    let output = args.output.clone().unwrap_or_else(|| {
        let stem = args.scene.file_stem().unwrap_or_default();
        PathBuf::from(stem).with_extension("png")
    });
    ImageFormat::from_path(&output)?;
    let dir = output
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(ImageError::MissingDirectory {
            path: output.clone(),
            dir: dir.to_path_buf(),
        }
        .into());
    }
    if args.spp == 0 {
        return Err(RenderError::Invalid(
            "--spp 0: at least one sample per pixel".into(),
        ));
    }
    if let Some(path) = &args.kernel_field {
        if args.estimate.estimator != EstimatorKind::Diffusion {
            return Err(RenderError::Invalid(
                "--kernel-field needs --estimator diffusion".into(),
            ));
        }
        ImageFormat::from_path(path)?;
    }
    if args.global_k < 2 {
        return Err(RenderError::Invalid(format!(
            "--global-k {}: must be at least 2",
            args.global_k
        )));
    }
    Ok(output)
}

pub fn run(args: &RenderArgs) -> Result<RenderOutcome, RenderError> {
    let output = validate(args)?;
    let pool = embree::thread_pool(args.threads)
        .map_err(|e| RenderError::Invalid(format!("--threads {}: {e}", args.threads)))?;
    pool.install(|| run_in_pool(args, output))
}

fn run_in_pool(args: &RenderArgs, output: PathBuf) -> Result<RenderOutcome, RenderError> {
    embree::enable_flush_to_zero();
    let mut times = PhaseTimes::new();
    let description = times.time("load scene", || scene::load(&args.scene))?;
    let world = times.time("build Embree scene", || World::new(description))?;

    let diffuse_objects = world
        .description
        .shapes
        .iter()
        .filter(|s| {
            let m = match s {
                scene::Shape::Sphere { material, .. } => *material,
                scene::Shape::Triangles(t) => t.material,
            };
            matches!(world.material(m), Material::Diffuse { .. })
        })
        .count();
    let global_target =
        args.global_photons
            .unwrap_or(if diffuse_objects >= 2 { 200_000 } else { 0 });

    let caustic = if world.has_specular() && args.caustic_photons > 0 {
        Some(trace(
            &world,
            MapKind::Caustic,
            args.caustic_photons,
            args.seed,
            "caustic photons",
            &mut times,
        ))
    } else {
        None
    };
    let global = (global_target > 0).then(|| {
        let kind = MapKind::Global {
            with_direct: args.final_gather > 0,
        };
        trace(
            &world,
            kind,
            global_target,
            args.seed,
            "global photons",
            &mut times,
        )
    });

    // The caustic estimate; the diffusion estimate's gradient pass is its own phase.
    let mut caustic_map = caustic;
    let mut estimator = None;
    let mut diffusion = None;
    let caustic_estimate: Option<Box<dyn RadianceEstimate>> = match caustic_map.as_mut() {
        Some((map, _)) if !map.is_empty() => {
            let resolved = args.estimate.resolve(map)?;
            estimator = Some(resolved.to_string());
            if let (EstimatorKind::Diffusion, ResolvedEstimator::Diffusion(d)) =
                (args.estimate.estimator, &resolved)
            {
                let start = Instant::now();
                gradient_pass(map, d.gradient_radius());
                diffusion = Some(*d);
                times.record(
                    "gradient pass",
                    start.elapsed(),
                    &[("photons", map.len() as u64)],
                );
            }
            let estimate = resolved.into_boxed();
            estimate.prepare(map);
            Some(estimate)
        }
        _ => None,
    };
    let global_estimate = KnnEstimate::new(RadialKernel::Constant, args.global_k, None);

    let integrator = Integrator {
        world: &world,
        caustics: match (&caustic_map, &caustic_estimate) {
            (Some((map, _)), Some(e)) => Some(EstimatedMap {
                map,
                estimate: e.as_ref(),
            }),
            _ => None,
        },
        indirect: match &global {
            Some((map, _)) if !map.is_empty() => {
                let m = EstimatedMap {
                    map,
                    estimate: &global_estimate,
                };
                if args.final_gather > 0 {
                    Indirect::FinalGather {
                        map: m,
                        rays: args.final_gather,
                    }
                } else {
                    Indirect::Visualize(m)
                }
            }
            _ => Indirect::None,
        },
        max_depth: args.max_depth,
    };
    let camera = PinholeCamera::new(&world.description.camera);
    let bar = progress(world.description.camera.height as u64, "render");
    let start = Instant::now();
    let image = render_image(&camera, &integrator, args.spp, args.seed, &bar);
    bar.finish_and_clear();
    let pixels = (image.width * image.height) as u64;
    times.record(
        "render",
        start.elapsed(),
        &[("pixels", pixels), ("spp", args.spp as u64)],
    );

    let options = WriteOptions {
        exposure: args.exposure,
        ..WriteOptions::default()
    };
    times.time("write image", || {
        image_io::write_image(&output, &image, &options)
    })?;
    if let (Some(path), Some(d), Some((map, _))) = (&args.kernel_field, &diffusion, &caustic_map) {
        let field = times.time("kernel field", || {
            super::render_kernel_field(&camera, &world, map, d)
        });
        times.time("write kernel field", || {
            image_io::write_image(path, &field, &WriteOptions::default())
        })?;
    }
    if let Some(path) = &args.stats {
        let json = serde_json::json!({
            "scene": args.scene,
            "output": output,
            "estimator": estimator,
            "caustic": caustic_map.as_ref().map(|(_, c)| serde_json::json!({"emitted": c.emitted, "stored": c.stored})),
            "global": global.as_ref().map(|(_, c)| serde_json::json!({"emitted": c.emitted, "stored": c.stored})),
            "phases": times.phases,
            "total_seconds": times.total_seconds(),
        });
        let text = serde_json::to_string_pretty(&json).expect("JSON of plain values");
        image_io::write_atomically(path, |w| {
            w.write_all(text.as_bytes()).map_err(|e| e.to_string())
        })?;
    }
    Ok(RenderOutcome {
        image,
        output,
        times,
        caustic: caustic_map.as_ref().map(|(_, c)| *c),
        global: global.as_ref().map(|(_, c)| *c),
        estimator,
    })
}

fn trace(
    world: &World,
    kind: MapKind,
    target: usize,
    seed: u64,
    what: &str,
    times: &mut PhaseTimes,
) -> (PhotonMap, TraceCounts) {
    let bar = progress(target as u64, what);
    let start = Instant::now();
    let (map, counts) = trace_map(world, kind, target, seed, &bar);
    bar.finish_and_clear();
    times.record(
        &format!("trace {what}"),
        start.elapsed(),
        &[("emitted", counts.emitted), ("stored", counts.stored)],
    );
    (map, counts)
}
