//! One whole render, as the data flows: scene file → Embree world → photon maps (only those
//! the scene and the chosen render need) → estimate preparation (the diffusion estimate's
//! gradient pass, timed as its own phase) → eye pass → image file, with progress bars and a
//! per-phase timing table. Owns the `dpm render` options; must not implement any stage itself.

use super::integrator::{EstimatedMap, Indirect, Integrator};
use super::memory_budget::check_memory;
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
use crate::photon::store::{self, MapInfo, StoreError};
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
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub threads: usize,

    /// Seed of every random number (photon paths and pixel samples).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,

    /// Samples per pixel: the first goes through the pixel centre, the rest are jittered.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub spp: u32,

    /// Exposure in stops for PNG output (linear formats are written unscaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,

    /// Mirror and glass bounces followed from the eye.
    #[arg(long, default_value_t = 10, allow_negative_numbers = true)]
    pub max_depth: u32,

    /// Photons STORED in the caustic map (light → specular+ → diffuse); paths are emitted until
    /// this many are stored. Only built when the scene has a mirror or glass object; 0 turns
    /// caustics off.
    #[arg(long, default_value_t = 1_000_000, allow_negative_numbers = true)]
    pub caustic_photons: usize,

    /// Photons STORED in the global map (indirect diffuse light). Default: 200000 when the scene
    /// has two or more diffuse objects (so diffuse light can bounce between them), else 0 (no
    /// global map: a lone plane cannot light itself).
    #[arg(long, allow_negative_numbers = true)]
    pub global_photons: Option<usize>,

    /// Final-gather rays per diffuse eye hit for indirect light; 0 shows the global map's
    /// estimate directly instead (faster, blotchier).
    #[arg(long, default_value_t = 16, allow_negative_numbers = true)]
    pub final_gather: u32,

    /// Photons per global-map estimate (constant kernel, k-th photon left out).
    #[arg(long, default_value_t = 100, allow_negative_numbers = true)]
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

    /// Save the photon maps to FILE (versioned binary with a checksum, written atomically)
    /// right after tracing, so a later render can skip tracing with --load-photons.
    #[arg(long, value_name = "FILE")]
    pub save_photons: Option<PathBuf>,

    /// Load the photon maps from FILE (made by --save-photons) instead of tracing them. The
    /// file must come from the same scene (lights, materials, geometry), --seed and photon
    /// counts; the image is then identical to one from freshly traced maps.
    #[arg(long, value_name = "FILE")]
    pub load_photons: Option<PathBuf>,
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
    #[error("{0}")]
    Photons(#[from] StoreError),
    #[error(
        "interrupted; {} was not written{}",
        output.display(),
        saved_photons.as_ref().map(|p| format!(
            " (the photon maps were saved to {}; reuse them with --load-photons)",
            p.display()
        )).unwrap_or_default()
    )]
    Interrupted {
        output: PathBuf,
        saved_photons: Option<PathBuf>,
    },
}

impl RenderError {
    /// Exit code: 2 for bad input (scene, parameters, output path), 1 for failures inside.
    pub fn exit_code(&self) -> i32 {
        match self {
            RenderError::Embree(_) | RenderError::Io { .. } => 1,
            RenderError::Image(ImageError::Io { .. } | ImageError::Encode { .. }) => 1,
            RenderError::Photons(e) => e.exit_code(),
            RenderError::Interrupted { .. } => 130,
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
    /// Heap bytes per stored photon of the caustic map, its gradients included when made.
    pub caustic_bytes_per_photon: Option<f64>,
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
    if let Some(dir) = image_io::missing_output_directory(&output) {
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
    validate_photon_files(args, &output)?;
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
    let (description, report) =
        times.time("load scene", || scene::load_with_report(&args.scene))?;
    report_load(args, &report, &mut times);
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

    let (caustic, global, saved_photons) =
        photon_maps(args, &world, global_target, &output, &mut times)?;
    let stop_if_interrupted = || -> Result<(), RenderError> {
        if crate::interrupt::requested() {
            return Err(RenderError::Interrupted {
                output: output.clone(),
                saved_photons: saved_photons.clone(),
            });
        }
        Ok(())
    };

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
    stop_if_interrupted()?;
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

    stop_if_interrupted()?;

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
            "embree": embree::version_string(),
            "output": output,
            "estimator": estimator,
            "caustic": caustic_map.as_ref().map(|(m, c)| serde_json::json!({"emitted": c.emitted, "stored": c.stored, "bytes_per_photon": m.bytes_per_photon()})),
            "global": global.as_ref().map(|(_, c)| serde_json::json!({"emitted": c.emitted, "stored": c.stored})),
            "phases": times.phases,
            "total_seconds": times.total_seconds(),
            "peak_resident_bytes": crate::resident_memory::peak_resident_bytes(),
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
        caustic_bytes_per_photon: caustic_map.as_ref().map(|(m, _)| m.bytes_per_photon()),
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

// ---- Photon map files, memory check and interruption (the reliability additions) ----

/// What loading repaired or suspects: warnings on stderr, dropped triangles in the table.
fn report_load(args: &RenderArgs, report: &scene::LoadReport, times: &mut PhaseTimes) {
    for warning in &report.warnings {
        eprintln!("warning: {}: {warning}", args.scene.display());
    }
    if report.degenerate_triangles_dropped > 0 {
        let dropped = report.degenerate_triangles_dropped as u64;
        times.add_counts("load scene", &[("zero-area triangles dropped", dropped)]);
    }
}

/// Checks `--save-photons` / `--load-photons` before any work: a file to load exists, a file
/// to save goes to an existing directory and is not the output image.
fn validate_photon_files(args: &RenderArgs, output: &Path) -> Result<(), RenderError> {
    if let Some(path) = &args.load_photons {
        if !path.is_file() {
            let why = if path.exists() {
                "is not a file"
            } else {
                "does not exist"
            };
            return Err(RenderError::Invalid(format!(
                "--load-photons {}: {why}",
                path.display()
            )));
        }
    }
    if let Some(path) = &args.save_photons {
        if path == output {
            return Err(RenderError::Invalid(format!(
                "--save-photons {}: is also the output image",
                path.display()
            )));
        }
        if path.is_dir() {
            return Err(RenderError::Invalid(format!(
                "--save-photons {}: is a directory",
                path.display()
            )));
        }
        if let Some(dir) = image_io::missing_output_directory(path) {
            return Err(RenderError::Invalid(format!(
                "--save-photons {}: directory {} does not exist",
                path.display(),
                dir.display()
            )));
        }
    }
    Ok(())
}

/// The maps this render uses: the caustic map when the scene has a mirror or glass object
/// (and --caustic-photons > 0), the global map when `global_target` > 0.
fn wanted_maps(args: &RenderArgs, world: &World, global_target: usize) -> Vec<MapInfo> {
    let mut wanted = Vec::new();
    if world.has_specular() && args.caustic_photons > 0 {
        wanted.push(MapInfo {
            kind: MapKind::Caustic,
            target: args.caustic_photons as u64,
        });
    }
    if global_target > 0 {
        wanted.push(MapInfo {
            kind: MapKind::Global {
                with_direct: args.final_gather > 0,
            },
            target: global_target as u64,
        });
    }
    wanted
}

type MapAndCounts = Option<(PhotonMap, TraceCounts)>;

/// The caustic and global maps, loaded from --load-photons or traced (after the memory
/// check), then saved to --save-photons when asked; also where they were saved.
fn photon_maps(
    args: &RenderArgs,
    world: &World,
    global_target: usize,
    output: &Path,
    times: &mut PhaseTimes,
) -> Result<(MapAndCounts, MapAndCounts, Option<PathBuf>), RenderError> {
    let wanted = wanted_maps(args, world, global_target);
    let scene = store::scene_fingerprint(&world.description);
    let with_counts = |map: PhotonMap| {
        let counts = TraceCounts {
            emitted: map.emitted,
            stored: map.len() as u64,
        };
        (map, counts)
    };
    check_memory(args, world, &wanted)?;
    let (caustic, global) = if let Some(path) = &args.load_photons {
        let start = Instant::now();
        let mut file = store::read(path)?;
        file.check_fits(scene, args.seed, &wanted)?;
        let caustic = file.take(MapKind::Caustic).map(with_counts);
        let global = file
            .take(MapKind::Global { with_direct: false })
            .map(with_counts);
        let stored = |m: &MapAndCounts| m.as_ref().map_or(0, |(_, c)| c.stored);
        times.record(
            "load photons",
            start.elapsed(),
            &[("caustic", stored(&caustic)), ("global", stored(&global))],
        );
        (caustic, global)
    } else {
        let mut caustic = None;
        let mut global = None;
        for info in &wanted {
            let (slot, what) = match info.kind {
                MapKind::Caustic => (&mut caustic, "caustic photons"),
                MapKind::Global { .. } => (&mut global, "global photons"),
            };
            *slot = Some(trace(
                world,
                info.kind,
                info.target as usize,
                args.seed,
                what,
                times,
            ));
            if crate::interrupt::requested() {
                return Err(RenderError::Interrupted {
                    output: output.to_path_buf(),
                    saved_photons: None,
                });
            }
        }
        (caustic, global)
    };
    let mut saved = None;
    if let Some(path) = &args.save_photons {
        let start = Instant::now();
        let maps: Vec<(MapInfo, &PhotonMap)> = wanted
            .iter()
            .zip(caustic.iter().chain(global.iter()))
            .map(|(info, (map, _))| (*info, map))
            .collect();
        let bytes = store::write(path, scene, args.seed, &maps)?;
        times.record("save photons", start.elapsed(), &[("bytes", bytes)]);
        saved = Some(path.clone());
    }
    Ok((caustic, global, saved))
}
