//! `dpm render` from the command line to the files, in the order a render runs: the flags
//! ([`super::args`]) checked together ([`validate`]); the scene loaded and the passes' shared
//! settings wired ([`super::setup`]); the passes ([`super::pass_loop`], each one a
//! [`super::pass`]) into the [`Film`]; then `-o`, `--film`, the kernel field and `--stats`
//! written from the complete passes, with a per-phase timing table at the end. Owns the
//! errors and exit codes of a render, checking the flags and the final writes; must not
//! implement any stage.

pub use super::args::{
    DEFAULT_CAUSTIC_PHOTONS, DEFAULT_EMISSION_SAMPLES, DEFAULT_GLASS_SPLIT_DEPTH,
    DEFAULT_GLOBAL_PHOTONS, DEFAULT_PASSES, DEFAULT_RADIUS_K, MAX_EDGE_SAMPLES,
    MAX_EMISSION_SAMPLES, MAX_IRRADIANCE_STRIDE, MAX_LIGHT_SAMPLES, RenderArgs, parse_resolution,
};
use super::camera::RayCamera;
use super::film::Film;
use super::film_file::{self, FilmFileError};
use super::output::{write_film_image, write_kernel_field};
use super::pass_loop::{LoopOutcome, PassLoop};
use super::photon_files::validate_photon_files;
use super::schedule::MAX_PASSES;
use super::setup::{Wiring, load_world, survey_pixels};
use crate::embree::{self, EmbreeError};
use crate::estimate::settings::{EstimateError, EstimatorKind};
use crate::image_io::{self, Image, ImageError, ImageFormat};
use crate::photon::store::StoreError;
use crate::photon::tracer::TraceCounts;
use crate::scene::SceneError;
use crate::timing::PhaseTimes;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    /// The last pass's volume photon maps: photons and heap bytes (a scene with media).
    pub volume_maps: Option<(usize, usize)>,
    /// Heap bytes of the media's density and majorant grids (a scene with media).
    pub media_bytes: Option<usize>,
    pub passes: Vec<PassRecord>,
    /// Ctrl-C stopped the run; the film holds the passes completed before it.
    pub interrupted: bool,
    /// The budget could not hold even one pass (it ran anyway).
    pub budget_note: Option<String>,
}

/// Checks the options that need no scene, before any work is done.
pub fn validate(args: &RenderArgs) -> Result<PathBuf, RenderError> {
    args.estimate
        .settings_with_radius_k(DEFAULT_RADIUS_K)
        .validate()?;
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
    if args.volume_k < 1 {
        return invalid(format!("--volume-k {}: must be at least 1", args.volume_k));
    }
    if !(args.volume_contrast.is_finite() && args.volume_contrast >= 0.0) {
        return invalid(format!(
            "--volume-contrast {}: must be 0 (round kernels) or positive",
            args.volume_contrast
        ));
    }
    if args.global_k < 2 {
        return invalid(format!("--global-k {}: must be at least 2", args.global_k));
    }
    args.check_counts().map_err(RenderError::Invalid)?;
    if args.passes == Some(0) {
        return invalid("--passes 0: at least one pass".into());
    }
    if let Some(t) = args.time.filter(|t| !(t.is_finite() && *t > 0.0)) {
        return invalid(format!("--time {t}: must be a positive number of seconds"));
    }
    if let Some(s) = args.write_every.filter(|s| !(s.is_finite() && *s >= 0.0)) {
        return invalid(format!(
            "--write-every {s}: must be zero or a positive number of seconds"
        ));
    }
    if !(args.glossy_min_alpha >= 0.0 && args.glossy_min_alpha.is_finite()) {
        return invalid(format!(
            "--glossy-min-alpha {}: must be a finite roughness of at least 0",
            args.glossy_min_alpha
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
    run_observed(args, None)
}

/// Called after each pass lands in the film, with the pass's record and the film: how an
/// embedding program (the Python module) shows a render as it converges.
pub type PassObserver<'a> = &'a (dyn Fn(&PassRecord, &Film) + Sync);

/// [`run`], calling `observer` after every pass.
pub fn run_observed(
    args: &RenderArgs,
    observer: Option<PassObserver<'_>>,
) -> Result<RenderOutcome, RenderError> {
    let output = validate(args)?;
    let pool = embree::thread_pool(args.threads)
        .map_err(|e| RenderError::Invalid(format!("--threads {}: {e}", args.threads)))?;
    pool.install(|| run_in_pool(args, output, observer))
}

/// The passes asked for: --passes, else one for a photon-map file's single pass, else the
/// default (with --time and no --passes the budget decides instead).
pub(super) fn pass_count(args: &RenderArgs) -> u64 {
    args.passes.unwrap_or(
        if args.save_photons.is_some() || args.load_photons.is_some() {
            1
        } else {
            DEFAULT_PASSES
        },
    )
}

/// Passes this run may render: --passes, else the default, else (with --time alone) as many
/// as a render holds.
pub(super) fn pass_limit(args: &RenderArgs) -> u64 {
    match (args.passes, args.time) {
        (None, Some(_)) => MAX_PASSES,
        _ => pass_count(args),
    }
}

fn run_in_pool(
    args: &RenderArgs,
    output: PathBuf,
    observer: Option<PassObserver<'_>>,
) -> Result<RenderOutcome, RenderError> {
    embree::enable_flush_to_zero();
    let run_start = Instant::now();
    let mut times = PhaseTimes::new();
    let (mut world, scene_hash) = load_world(args, &mut times)?;
    if world.media.is_some() && (args.save_photons.is_some() || args.load_photons.is_some()) {
        return Err(RenderError::Invalid(
            "--save-photons and --load-photons hold surface photon maps, and this scene has \
             participating media (whose volume photons they would lose)"
                .into(),
        ));
    }
    let wiring = Wiring::new(args, &mut world, scene_hash, &output, &mut times)?;
    let camera = &world.description.camera;
    let reference = match &args.reference {
        Some(path) => {
            let (width, height) = camera.image_size();
            Some(read_reference(path, width, height)?)
        }
        None => None,
    };
    let start = wiring.start(args, &world, &mut times)?;
    let camera = RayCamera::new(camera);
    let Some(plan) = survey_pixels(&camera, &world, &wiring.settings, &mut times) else {
        return Err(RenderError::Interrupted {
            output,
            saved_photons: None,
        });
    };
    let passes = PassLoop {
        args,
        world: &world,
        wiring: &wiring,
        camera,
        plan: &plan,
        reference,
        output: &output,
        film_path: args.film.clone().or_else(|| args.resume.clone()),
        run_start,
        observer,
    };
    let ran = passes.run(start, &mut times)?;
    let film_path = passes.film_path;
    let media_bytes = world.media.as_ref().map(|m| m.bytes());
    finish(
        args,
        output,
        film_path.as_deref(),
        ran,
        (times, media_bytes),
    )
}

/// Writes what the complete passes hold (the image, the film, the kernel field, the stats)
/// and the outcome; with no complete pass, says nothing was written.
fn finish(
    args: &RenderArgs,
    output: PathBuf,
    film_path: Option<&Path>,
    ran: LoopOutcome,
    (mut times, media_bytes): (PhaseTimes, Option<usize>),
) -> Result<RenderOutcome, RenderError> {
    let Some(film) = ran.film.filter(|f| !f.passes().is_empty()) else {
        return Err(RenderError::Interrupted {
            output,
            saved_photons: ran.saved_photons,
        });
    };
    write_outputs(args, &output, film_path, &film, &mut times)?;
    times.add_counts("write image", &[("passes", film.passes().count())]);
    if let Some(path) = &args.kernel_field {
        times.time("write kernel field", || write_kernel_field(path, &film))?;
    }
    let last = ran.last_report.as_ref();
    let outcome = RenderOutcome {
        image: film.image(),
        output,
        times,
        caustic: last.and_then(|r| r.caustic),
        caustic_bytes_per_photon: last.and_then(|r| r.caustic_bytes_per_photon),
        global: last.and_then(|r| r.global),
        estimator: last.and_then(|r| r.estimator.clone()),
        volume_maps: last.and_then(|r| r.volume_maps),
        media_bytes,
        passes: ran.records,
        interrupted: ran.interrupted,
        budget_note: ran.budget_note,
        film,
    };
    if let Some(path) = &args.stats {
        write_stats(path, args, &outcome)?;
    }
    Ok(outcome)
}

/// Rewrites `-o` and the film with every pass the film holds.
pub(super) fn write_outputs(
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
        "volume_maps": outcome.volume_maps.map(|(photons, bytes)| serde_json::json!({"photons": photons, "bytes": bytes})),
        "media_bytes": outcome.media_bytes,
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
