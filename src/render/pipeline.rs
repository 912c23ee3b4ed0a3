//! `dpm render` from the command line to the files: the flags ([`super::args`]) checked
//! together, then the pass loop. Scene file → Embree world → for each pass ([`super::pass`]:
//! its maps, its estimates, its pixels) → the [`Film`] → `-o`, `--film` and the kernel field,
//! rewritten atomically as passes complete, with a progress bar over the passes and a
//! per-phase timing table at the end. Owns checking the flags, the pass budget (`--passes`, `--time`), resuming and writing; must not implement any stage.
//!
//! The loop: passes run from the first (`--first-pass`, or the end of a `--resume`d film) for
//! `--passes` passes, or while the time budget lasts: a pass whose predicted time (the mean of
//! this run's pass times) would overrun `--time` is not started, though the first pass always
//! runs. Ctrl-C ends the current pass unfinished and writes the film of the complete ones.

pub use super::args::{
    DEFAULT_CAUSTIC_PHOTONS, DEFAULT_EMISSION_SAMPLES, DEFAULT_GLASS_SPLIT_DEPTH,
    DEFAULT_GLOBAL_PHOTONS, DEFAULT_PASSES, DEFAULT_RADIUS_K, MAX_EDGE_SAMPLES,
    MAX_EMISSION_SAMPLES, MAX_IRRADIANCE_STRIDE, MAX_LIGHT_SAMPLES, RenderArgs, parse_resolution,
};
use super::camera::PinholeCamera;
use super::film::{Film, FilmHeader};
use super::film_file::{self, FilmFileError};
use super::memory_budget::check_memory;
use super::output::{write_film_image, write_kernel_field};
use super::pass::{BaseRadii, PassContext, PassMaps, RenderSettings, trace_pass_maps, wanted_maps};
use super::photon_files::{load_maps, save_maps, validate_photon_files};
use super::pilots::PixelPlan;
use super::schedule::{MAX_PASSES, Schedule};
use crate::embree::{self, EmbreeError};
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
        emission_samples: args.emission_samples,
        edge_samples: args.edge_samples,
        guide_paths: if args.caustic_photons > 0 {
            args.guide_paths
        } else {
            0
        },
        alpha: args.ppm_alpha,
        estimator: args.estimate.settings_with_radius_k(DEFAULT_RADIUS_K),
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
    let mut world = times.time("build Embree scene", || World::new(description))?;
    let settings = render_settings(args, &world);
    super::caustic_guide::learn(&mut world, &settings, args.seed, &mut times);
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
    let found = times.time("pilot rays", || {
        PixelPlan::survey(
            &pinhole,
            &world,
            settings.max_depth,
            settings.emission_samples,
            settings.edge_samples,
        )
    });
    let Some(plan) = found else {
        return Err(RenderError::Interrupted {
            output,
            saved_photons: None,
        });
    };
    times.add_counts(
        "pilot rays",
        &[
            ("emission pixels", plan.emission_pixels() as u64),
            ("edge pixels", plan.edge_pixels() as u64),
        ],
    );
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
            plan: &plan,
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
