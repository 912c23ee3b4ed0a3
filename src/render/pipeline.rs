//! `dpm render` from the command line to the files: the flags, then the pass loop. Scene file →
//! Embree world → for each pass ([`super::pass`]: its maps, its estimates, its pixels) → the
//! [`Film`] → `-o`, `--film` and the kernel field, rewritten atomically as passes complete,
//! with a progress bar over the passes and a per-phase timing table at the end. Owns the flags,
//! the pass budget (`--passes`, `--time`), resuming and writing; must not implement any stage.
//!
//! The loop: passes run from the first (`--first-pass`, or the end of a `--resume`d film) for
//! `--passes` passes, or while the time budget lasts: a pass whose predicted time (the mean of
//! this run's pass times) would overrun `--time` is not started, though the first pass always
//! runs. Ctrl-C ends the current pass unfinished and writes the film of the complete ones.

use super::camera::PinholeCamera;
use super::film::{Film, FilmHeader};
use super::film_file::{self, FilmFileError};
use super::memory_budget::check_memory;
use super::output::{write_film_image, write_kernel_field};
use super::pass::{BaseRadii, PassContext, PassMaps, RenderSettings, trace_pass_maps, wanted_maps};
use super::photon_files::{load_maps, save_maps, validate_photon_files};
use super::schedule::{DEFAULT_ALPHA, MAX_PASSES, Schedule};
use crate::embree::{self, EmbreeError};
use crate::estimate::EstimatorFlags;
use crate::estimate::precomputed::DEFAULT_STRIDE;
use crate::estimate::settings::{EstimateError, EstimatorKind};
use crate::image_io::{self, Image, ImageError, ImageFormat};
use crate::photon::store::{self, StoreError};
use crate::photon::tracer::{MapKind, TraceCounts};
use crate::scene::{self, Material, SceneError};
use crate::timing::{PhaseTimes, progress};
use crate::world::World;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

#[derive(Clone, Debug, clap::Args)]
pub struct RenderArgs {
    /// Scene file: dpm's TOML, or a pbrt-v3/v4 scene by the `.pbrt` extension (see
    /// docs/scene-format.md).
    pub scene: PathBuf,

    /// Refuse a pbrt material dpm can only approximate (uber, plastic, rough metals, ...)
    /// instead of rendering its diffuse part with a warning.
    #[arg(long)]
    pub strict: bool,

    /// Output image; the format follows the extension: .png (tone-mapped sRGB), .exr (linear
    /// float RGB, with direct, caustic and indirect layers and, with the diffusion estimate,
    /// the kernel field), .pfm (linear float RGB). Rewritten atomically as passes complete.
    /// Default: the scene's name with .png.
    #[arg(short, long)]
    pub output: Option<PathBuf>,

    /// Worker threads (0: one per core). The image does not depend on it.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub threads: usize,

    /// Seed of every random number (photon paths and pixel samples of every pass).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub seed: u64,

    /// Progressive passes to render. Each traces fresh photons, shrinks every radius by
    /// r²(i+1) = r²(i)·(i+α)/(i+1) and renders fresh pixel samples; the image is their mean,
    /// and converges as passes accumulate. Default: 8 (1 with --save-photons or
    /// --load-photons; with --time, as many as the budget holds).
    #[arg(long, allow_negative_numbers = true)]
    pub passes: Option<u64>,

    /// Wall-clock budget in seconds: passes run until the next one (predicted from the mean
    /// pass time so far) would overrun it. The first pass always runs.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub time: Option<f64>,

    /// Index of the first pass (passes are the same whichever run renders them, so ranges
    /// rendered apart can be merged with `dpm merge`).
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub first_pass: u64,

    /// α of the progressive radius reduction, in (0, 1) (Knaus and Zwicker: 2/3).
    #[arg(long, default_value_t = DEFAULT_ALPHA, allow_negative_numbers = true)]
    pub ppm_alpha: f64,

    /// Save the film (per-pixel sums of every pass, with the scene's hash, seed and settings)
    /// to FILE after every pass, atomically: `--resume FILE` continues it, `dpm merge` combines it.
    #[arg(long, value_name = "FILE")]
    pub film: Option<PathBuf>,

    /// Continue the film in FILE (same scene, seed and settings): passes start where it ends.
    /// It is rewritten there unless --film names another file.
    #[arg(long, value_name = "FILE")]
    pub resume: Option<PathBuf>,

    /// Rewrite -o (and --film) at most every this many seconds (0: after every pass); the
    /// last pass is always written.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 0.0,
        allow_negative_numbers = true
    )]
    pub write_every: f64,

    /// A reference image (.pfm or .exr, same resolution) to report the error against after
    /// every pass (relative MSE, in the progress bar and --stats).
    #[arg(long, value_name = "IMAGE")]
    pub reference: Option<PathBuf>,

    /// Render at WIDTHxHEIGHT pixels instead of the scene's `resolution` (e.g. 1280x720). The
    /// vertical field of view stays the scene's `fov_y`, so a wider image sees more at the
    /// sides. A film remembers its resolution: --resume and `dpm merge` refuse another.
    #[arg(long, value_name = "WxH", value_parser = parse_resolution, allow_hyphen_values = true)]
    pub resolution: Option<(u32, u32)>,

    /// Camera samples per pixel in each pass, stratified within the pixel across samples and
    /// passes (one Owen-scrambled Sobol sequence per pixel).
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub spp: u32,

    /// Exposure in stops for PNG output (linear formats are written unscaled).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub exposure: f32,

    /// Mirror and glass bounces followed from the eye.
    #[arg(long, default_value_t = 10, allow_negative_numbers = true)]
    pub max_depth: u32,

    /// Photons STORED in each pass's caustic map (light → specular+ → diffuse); paths are
    /// emitted until this many are stored. Only built when the scene has a mirror or glass
    /// object; 0 turns caustics off.
    #[arg(long, default_value_t = DEFAULT_CAUSTIC_PHOTONS, allow_negative_numbers = true)]
    pub caustic_photons: usize,

    /// Photons STORED in each pass's global map (indirect diffuse light). Default: 200000 when
    /// the scene has two or more diffuse objects (so diffuse light can bounce between them),
    /// else 0 (no global map: a lone plane cannot light itself).
    #[arg(long, allow_negative_numbers = true)]
    pub global_photons: Option<usize>,

    /// Final-gather rays per diffuse eye hit for indirect light; 0 (the default) shows the
    /// global map's estimate directly: over progressive passes its blotches average out and
    /// its corner darkening shrinks with the radius, and it reached every error sooner than
    /// 1 or 4 gather rays did (README, "Choosing the defaults").
    #[arg(long, default_value_t = 0, allow_negative_numbers = true)]
    pub final_gather: u32,

    /// Photons per global-map estimate (constant kernel, k-th photon left out).
    #[arg(long, default_value_t = 100, allow_negative_numbers = true)]
    pub global_k: usize,

    /// With final gathering, the global estimate is computed once per pass at one photon in N
    /// of the global map and a gather ray reads the nearest such point whose normal
    /// agrees (Christensen's precomputed irradiance) instead of running its own estimate;
    /// 0 turns it off (a k-NN estimate per gather ray).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_STRIDE, allow_negative_numbers = true)]
    pub irradiance_stride: usize,

    /// Shadow rays per area light (sphere, quad or mesh) and per environment at each diffuse
    /// eye hit, stratified and averaged; a point, spot or distant light takes one.
    #[arg(
        long,
        value_name = "N",
        default_value_t = 1,
        allow_negative_numbers = true
    )]
    pub light_samples: u32,

    /// Glass hits along an eye path that follow both the reflected and the refracted ray
    /// (weighted by the Fresnel reflectance); past them a path follows one, chosen with that
    /// probability. Splitting every hit costs up to 2^depth rays a pixel through thick glass
    /// for detail a few more passes average in anyway; 0 is pure sampling, 1000 splits every
    /// hit (the Whitted tracer).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_GLASS_SPLIT_DEPTH)]
    pub glass_split_depth: u32,

    /// Caustic radiance estimate.
    #[command(flatten)]
    pub estimate: EstimatorFlags,

    /// Also write the diffusion kernel's shape at each pixel's first diffuse hit (hue = edge
    /// direction, brightness = 1 − λ2, averaged over passes), like the paper's Figure 2b.
    /// Needs --estimator diffusion.
    #[arg(long)]
    pub kernel_field: Option<PathBuf>,

    /// Write the per-phase times, counts and per-pass errors as JSON.
    #[arg(long)]
    pub stats: Option<PathBuf>,

    /// Save pass 0's photon maps to FILE (versioned binary with a checksum, written
    /// atomically) right after tracing, so a later one-pass render can skip tracing with
    /// --load-photons.
    #[arg(long, value_name = "FILE")]
    pub save_photons: Option<PathBuf>,

    /// Load the photon maps from FILE (made by --save-photons) instead of tracing them, for a
    /// one-pass render. The file must come from the same scene (lights, materials,
    /// geometry), --seed and photon counts; the image is then identical to one from freshly
    /// traced maps.
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
    #[error("{0}")]
    Film(#[from] FilmFileError),
    #[error(
        "interrupted; {} was not written (no pass was complete){}",
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
            RenderError::Film(e) => e.exit_code(),
            RenderError::Interrupted { .. } => 130,
            _ => 2,
        }
    }
}

/// One pass's line in the report: its time and, with --reference, the film's error after it.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PassRecord {
    pub pass: u64,
    pub seconds: f64,
    /// Seconds since the run started, when this pass was complete.
    pub elapsed: f64,
    pub relative_mse: Option<f64>,
}

/// What a render produced.
pub struct RenderOutcome {
    pub image: Image,
    pub film: Film,
    pub output: PathBuf,
    pub times: PhaseTimes,
    /// The last pass's maps.
    pub caustic: Option<TraceCounts>,
    /// Heap bytes per stored photon of the caustic map, its gradients included when made.
    pub caustic_bytes_per_photon: Option<f64>,
    pub global: Option<TraceCounts>,
    /// The last pass's caustic estimate, every number resolved.
    pub estimator: Option<String>,
    pub passes: Vec<PassRecord>,
    /// Ctrl-C stopped the run; the film holds the passes completed before it.
    pub interrupted: bool,
    /// The budget could not hold even one pass (it ran anyway).
    pub budget_note: Option<String>,
}

/// Checks the options that need no scene, before any work is done.
pub fn validate(args: &RenderArgs) -> Result<PathBuf, RenderError> {
    args.estimate.settings().validate()?;
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
    let invalid = |m: String| Err(RenderError::Invalid(m));
    if args.spp == 0 {
        return invalid("--spp 0: at least one sample per pixel".into());
    }
    if let Some(path) = &args.kernel_field {
        if args.estimate.estimator != EstimatorKind::Diffusion {
            return invalid("--kernel-field needs --estimator diffusion".into());
        }
        ImageFormat::from_path(path)?;
    }
    if args.global_k < 2 {
        return invalid(format!("--global-k {}: must be at least 2", args.global_k));
    }
    if !(1..=MAX_LIGHT_SAMPLES).contains(&args.light_samples) {
        return invalid(format!(
            "--light-samples {}: must be from 1 to {MAX_LIGHT_SAMPLES}",
            args.light_samples
        ));
    }
    if args.irradiance_stride > MAX_IRRADIANCE_STRIDE {
        return invalid(format!(
            "--irradiance-stride {}: must be from 0 (off) to {MAX_IRRADIANCE_STRIDE}",
            args.irradiance_stride
        ));
    }
    if args.passes == Some(0) {
        return invalid("--passes 0: at least one pass".into());
    }
    if let Some(t) = args.time.filter(|t| !(t.is_finite() && *t > 0.0)) {
        return invalid(format!("--time {t}: must be a positive number of seconds"));
    }
    if !(args.write_every.is_finite() && args.write_every >= 0.0) {
        return invalid(format!(
            "--write-every {}: must be zero or a positive number of seconds",
            args.write_every
        ));
    }
    if !(args.ppm_alpha > 0.0 && args.ppm_alpha < 1.0) {
        return invalid(format!("--ppm-alpha {}: must be in (0, 1)", args.ppm_alpha));
    }
    let last = args
        .first_pass
        .checked_add(pass_count(args))
        .filter(|l| *l <= MAX_PASSES);
    if last.is_none() {
        return invalid(format!(
            "--first-pass {} with --passes {}: a render holds at most {MAX_PASSES} passes",
            args.first_pass,
            pass_count(args)
        ));
    }
    if args.resume.is_some() && args.first_pass != 0 {
        return invalid("--resume continues where its film ends; drop --first-pass".into());
    }
    let one_pass = pass_count(args) == 1 && args.time.is_none() && args.first_pass == 0;
    if (args.load_photons.is_some() || args.save_photons.is_some()) && !one_pass {
        return invalid(
            "--save-photons and --load-photons hold one pass's maps: use them with one pass \
             (no --passes, --time or --first-pass)"
                .into(),
        );
    }
    for (flag, path) in [("--film", &args.film), ("--resume", &args.resume)] {
        if let Some(p) = path
            && p == &output
        {
            return invalid(format!("{flag} {}: is also the output image", p.display()));
        }
    }
    for (flag, path) in [("--resume", &args.resume), ("--reference", &args.reference)] {
        if let Some(p) = path.as_ref().filter(|p| !p.is_file()) {
            return invalid(format!("{flag} {}: does not exist", p.display()));
        }
    }
    if let Some(p) = &args.reference
        && !matches!(
            ImageFormat::from_path(p)?,
            ImageFormat::Pfm | ImageFormat::Exr
        )
    {
        return invalid(format!(
            "--reference {}: must be a .pfm or .exr image",
            p.display()
        ));
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

/// `--resolution`'s value: two whole numbers >= 1 joined by `x` (`1280x720`).
pub fn parse_resolution(text: &str) -> Result<(u32, u32), String> {
    let wanted = "expected WIDTHxHEIGHT in pixels, e.g. 1280x720";
    let (width, height) = text
        .trim()
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("no `x` between width and height: {wanted}"))?;
    let side = |what: &str, value: &str| match value.trim().parse::<u32>() {
        Ok(0) => Err(format!("the {what} is 0: it must be at least 1 pixel")),
        Ok(pixels) => Ok(pixels),
        Err(_) => Err(format!(
            "the {what} `{value}` is not a whole number of pixels: {wanted}"
        )),
    };
    Ok((side("width", width)?, side("height", height)?))
}

/// Most shadow rays per area light a diffuse hit may take (more is a typo, not a setting).
pub const MAX_LIGHT_SAMPLES: u32 = 4096;
/// Largest `--irradiance-stride`: beyond it the table is too sparse to stand for the map.
pub const MAX_IRRADIANCE_STRIDE: usize = 1 << 16;

/// Passes per render by default: chosen by measurement (README, "Choosing the defaults").
pub const DEFAULT_PASSES: u64 = 8;
/// Stored caustic photons per pass by default.
pub const DEFAULT_CAUSTIC_PHOTONS: usize = 100_000;
/// Stored global photons per pass by default (scenes with two or more diffuse objects).
pub const DEFAULT_GLOBAL_PHOTONS: usize = 200_000;
/// Glass hits that split an eye path by default (README, "Whole scenes").
pub const DEFAULT_GLASS_SPLIT_DEPTH: u32 = 1000;

/// The passes asked for: --passes, else one for a photon-map file's single pass, else the
/// default (with --time and no --passes the budget decides instead).
fn pass_count(args: &RenderArgs) -> u64 {
    args.passes.unwrap_or(
        if args.save_photons.is_some() || args.load_photons.is_some() {
            1
        } else {
            DEFAULT_PASSES
        },
    )
}

/// The settings every pass of this render uses.
fn render_settings(args: &RenderArgs, world: &World) -> RenderSettings {
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
    RenderSettings {
        caustic_photons: args.caustic_photons,
        global_photons: args.global_photons.unwrap_or(if diffuse_objects >= 2 {
            DEFAULT_GLOBAL_PHOTONS
        } else {
            0
        }),
        spp: args.spp,
        max_depth: args.max_depth,
        final_gather: args.final_gather,
        global_k: args.global_k,
        irradiance_stride: args.irradiance_stride,
        light_samples: args.light_samples,
        glass_split_depth: args.glass_split_depth,
        alpha: args.ppm_alpha,
        estimator: args.estimate.settings(),
    }
}

fn run_in_pool(args: &RenderArgs, output: PathBuf) -> Result<RenderOutcome, RenderError> {
    embree::enable_flush_to_zero();
    let run_start = Instant::now();
    let mut times = PhaseTimes::new();
    let (mut description, report) = times.time("load scene", || {
        let options = scene::LoadOptions {
            strict: args.strict,
        };
        scene::load_with_options(&args.scene, &options)
    })?;
    if let Some((width, height)) = args.resolution {
        // The field of view stays the scene's vertical one.
        description.camera.width = width;
        description.camera.height = height;
    }
    report_load(args, &report, &mut times);
    let scene_hash = store::scene_fingerprint(&description);
    let world = times.time("build Embree scene", || World::new(description))?;
    let settings = render_settings(args, &world);
    let wanted = wanted_maps(&settings, &world);
    check_memory(settings.estimator.estimator, &world, &wanted)?;
    let schedule = Schedule::new(settings.alpha, args.seed);
    let camera = &world.description.camera;
    // The kernel field needs the diffusion estimate and a caustic map to steer it.
    let kernel_field = settings.estimator.estimator == EstimatorKind::Diffusion
        && wanted.iter().any(|w| w.kind == MapKind::Caustic)
        && (args.kernel_field.is_some()
            || ImageFormat::from_path(&output).ok() == Some(ImageFormat::Exr));
    let header = |radii: BaseRadii| FilmHeader {
        scene_file: args.scene.display().to_string(),
        scene_hash,
        seed: args.seed,
        width: camera.width as usize,
        height: camera.height as usize,
        settings: settings.clone(),
        radii,
        kernel_field,
    };
    let reference = match &args.reference {
        Some(path) => Some(read_reference(path, camera.width, camera.height)?),
        None => None,
    };

    // The film to continue, or none yet (its header needs pass 0's radii).
    let mut film: Option<Film> = None;
    let mut first = args.first_pass;
    if let Some(path) = &args.resume {
        let resumed = times.time("read film", || film_file::read(path))?;
        let probe = header(resumed.header.radii);
        if let Some(field) = resumed.header.first_difference(&probe) {
            return Err(RenderError::Invalid(format!(
                "--resume {}: the film's {field} differs from this render's; it cannot be continued",
                path.display()
            )));
        }
        first = resumed.passes().end();
        film = Some(resumed);
    }
    let film_path = args.film.clone().or_else(|| args.resume.clone());
    let mut saved_photons = None;
    let mut radii = film.as_ref().map(|f| f.header.radii);
    if radii.is_none() && first > 0 {
        // A run that does not start at pass 0 needs pass 0's radii: given ones need no maps,
        // derived ones need pass 0's, traced once.
        let given = settings.estimator.radius.is_some()
            || !wanted.iter().any(|w| w.kind == MapKind::Caustic);
        let global = wanted
            .iter()
            .any(|w| matches!(w.kind, MapKind::Global { .. }));
        let maps = if given && !global {
            PassMaps::default()
        } else {
            trace_pass_maps(&world, &settings, &schedule, 0, &mut times)
        };
        radii = Some(BaseRadii::resolve(&settings, &maps)?);
    }

    let limit = match (args.passes, args.time) {
        (None, Some(_)) => MAX_PASSES,
        _ => pass_count(args),
    };
    let last = (first + limit).min(MAX_PASSES);
    // Passes done of N; with a budget and no pass count, seconds elapsed of the budget.
    let budget_bar = args.time.filter(|_| args.passes.is_none());
    let bar = match budget_bar {
        Some(t) => progress(t.ceil() as u64, "seconds of budget"),
        None => progress(last - first, "passes"),
    };
    let pinhole = PinholeCamera::new(camera);
    let mut records: Vec<PassRecord> = Vec::new();
    let mut last_report = None;
    let mut last_write: Option<Instant> = None;
    let mut budget_note = None;
    let mut interrupted = false;
    for pass in first..last {
        if let (Some(budget), false) = (args.time, records.is_empty()) {
            let mean = records.iter().map(|r| r.seconds).sum::<f64>() / records.len() as f64;
            if run_start.elapsed().as_secs_f64() + mean > budget {
                break;
            }
        }
        let pass_start = Instant::now();
        let maps = if pass == 0 && args.load_photons.is_some() {
            load_maps(args, scene_hash, &wanted, &mut times)?
        } else {
            trace_pass_maps(&world, &settings, &schedule, pass, &mut times)
        };
        if crate::interrupt::requested() {
            interrupted = true;
            break;
        }
        if pass == 0
            && let Some(path) = &args.save_photons
        {
            save_maps(path, scene_hash, args.seed, &wanted, &maps, &mut times)?;
            saved_photons = Some(path.clone());
        }
        // Pass 0's maps resolve the base radii; later passes only scale them.
        let radii = match radii {
            Some(r) => r,
            None => *radii.insert(BaseRadii::resolve(&settings, &maps)?),
        };
        let film = film.get_or_insert_with(|| Film::new(header(radii)));
        let context = PassContext {
            world: &world,
            camera: pinhole,
            settings: &settings,
            radii,
            schedule,
            kernel_field,
        };
        let Some(report) = context.run(pass, maps, &mut times)? else {
            interrupted = true;
            break;
        };
        film.add_pass(pass, &report.image)
            .expect("a pass's image fits its film and is new to it");
        let seconds = pass_start.elapsed().as_secs_f64();
        let relative_mse = reference.as_ref().map(|r| relative_mse(&film.image(), r));
        records.push(PassRecord {
            pass,
            seconds,
            elapsed: run_start.elapsed().as_secs_f64(),
            relative_mse,
        });
        last_report = Some(report);
        if pass == first
            && args
                .time
                .is_some_and(|t| run_start.elapsed().as_secs_f64() > t)
        {
            budget_note = Some(format!(
                "the --time budget ({:.1} s) is shorter than one pass ({seconds:.1} s); one pass ran",
                args.time.unwrap_or_default()
            ));
        }
        match budget_bar {
            Some(_) => bar.set_position(run_start.elapsed().as_secs()),
            None => bar.inc(1),
        }
        bar.set_message(pass_message(film, &records, &last_report));
        let due =
            last_write.is_none_or(|t| t.elapsed() >= Duration::from_secs_f64(args.write_every));
        if due && pass + 1 < last {
            write_outputs(args, &output, film_path.as_deref(), film, &mut times)?;
            last_write = Some(Instant::now());
        }
    }
    bar.finish_and_clear();
    let Some(film) = film.filter(|f| !f.passes().is_empty()) else {
        return Err(RenderError::Interrupted {
            output,
            saved_photons,
        });
    };
    write_outputs(args, &output, film_path.as_deref(), &film, &mut times)?;
    times.add_counts("write image", &[("passes", film.passes().count())]);
    if let Some(path) = &args.kernel_field {
        times.time("write kernel field", || write_kernel_field(path, &film))?;
    }
    let outcome = RenderOutcome {
        image: film.image(),
        output,
        times,
        caustic: last_report.as_ref().and_then(|r| r.caustic),
        caustic_bytes_per_photon: last_report
            .as_ref()
            .and_then(|r| r.caustic_bytes_per_photon),
        global: last_report.as_ref().and_then(|r| r.global),
        estimator: last_report.as_ref().and_then(|r| r.estimator.clone()),
        passes: records,
        interrupted,
        budget_note,
        film,
    };
    if let Some(path) = &args.stats {
        write_stats(path, args, &outcome)?;
    }
    Ok(outcome)
}

/// The pass bar's message: passes held, photons so far, the error so far.
fn pass_message(
    film: &Film,
    records: &[PassRecord],
    last: &Option<super::pass::PassReport>,
) -> String {
    let per_pass = last.as_ref().map_or(0, |r| {
        r.caustic.map_or(0, |c| c.stored) + r.global.map_or(0, |c| c.stored)
    });
    let photons = per_pass * records.len() as u64;
    let mut m = format!("{} passes, {photons} photons", film.passes().count());
    if let Some(e) = records.last().and_then(|r| r.relative_mse) {
        m += &format!(", rel. MSE {e:.3e}");
    }
    m
}

fn write_outputs(
    args: &RenderArgs,
    output: &Path,
    film_path: Option<&Path>,
    film: &Film,
    times: &mut PhaseTimes,
) -> Result<(), RenderError> {
    let start = Instant::now();
    write_film_image(output, film, args.exposure)?;
    times.accumulate("write image", start.elapsed(), &[]);
    if let Some(path) = film_path {
        let start = Instant::now();
        film_file::write(path, film)?;
        times.accumulate("write film", start.elapsed(), &[]);
    }
    Ok(())
}

fn write_stats(path: &Path, args: &RenderArgs, outcome: &RenderOutcome) -> Result<(), RenderError> {
    let json = serde_json::json!({
        "scene": args.scene,
        "embree": embree::version_string(),
        "output": outcome.output,
        "estimator": outcome.estimator,
        "passes": outcome.film.passes().count(),
        "pass_ranges": outcome.film.passes().ranges(),
        "per_pass": outcome.passes,
        "interrupted": outcome.interrupted,
        "caustic": outcome.caustic.map(|c| serde_json::json!({"emitted": c.emitted, "stored": c.stored, "bytes_per_photon": outcome.caustic_bytes_per_photon})),
        "global": outcome.global.map(|c| serde_json::json!({"emitted": c.emitted, "stored": c.stored})),
        "phases": outcome.times.phases,
        "total_seconds": outcome.times.total_seconds(),
        "peak_resident_bytes": crate::resident_memory::peak_resident_bytes(),
    });
    let text = serde_json::to_string_pretty(&json).expect("JSON of plain values");
    image_io::write_atomically(path, |w| {
        w.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })?;
    Ok(())
}

/// A reference image for the per-pass error: PFM or EXR, at the render's resolution.
pub fn read_reference(path: &Path, width: u32, height: u32) -> Result<Image, RenderError> {
    let image = image_io::read_image(path)?;
    if (image.width, image.height) != (width as usize, height as usize) {
        return Err(RenderError::Invalid(format!(
            "--reference {}: is {}x{}, the render is {width}x{height}",
            path.display(),
            image.width,
            image.height
        )));
    }
    Ok(image)
}

/// Relative MSE of `image` against `reference` over the RGB channel means (see
/// [`crate::tradeoff::scene_metrics::relative_mse`]).
pub fn relative_mse(image: &Image, reference: &Image) -> f64 {
    let mean = |i: &Image| -> Vec<f64> {
        i.pixels
            .iter()
            .map(|p| crate::density::channel_mean(*p))
            .collect()
    };
    crate::tradeoff::scene_metrics::relative_mse(&mean(image), &mean(reference))
}

/// What loading repaired or suspects: warnings on stderr, dropped triangles in the table.
fn report_load(args: &RenderArgs, report: &scene::LoadReport, times: &mut PhaseTimes) {
    let scene = args.scene.display().to_string();
    for warning in &report.warnings {
        // pbrt warnings already begin with their file:line:column.
        if warning.starts_with(&scene) {
            eprintln!("warning: {warning}");
        } else {
            eprintln!("warning: {scene}: {warning}");
        }
    }
    for note in &report.notes {
        eprintln!("note: {note}");
    }
    if report.degenerate_triangles_dropped > 0 {
        let dropped = report.degenerate_triangles_dropped as u64;
        times.add_counts("load scene", &[("zero-area triangles dropped", dropped)]);
    }
}
