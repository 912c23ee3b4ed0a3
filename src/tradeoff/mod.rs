//! `dpm tradeoff`: how much accuracy each estimate buys for how much time. Owns the command's
//! flags, their defaults and presets, the orchestration (target → optional reference → sweep
//! → CSV, SVG plot and the Pareto table on stdout) and the command's errors; it must not
//! evaluate estimates, score images or draw the plot itself (the submodules do), and must not
//! touch the photon map's internals.
//!
//! - [`sweep`]: the runs, their timing split and the CSV rows.
//! - [`pareto`]: the Pareto front of (time, error) points.
//! - [`svg`]: the error-against-time plot.
//! - [`constructed`]: the constructed-distribution target (exact density).
//! - [`scene_target`]: the scene target (the caustic contribution of the eye pass).
//! - [`scene_metrics`]: a scene's errors and regions, defined from its reference image.
//! - [`reference`](mod@reference): `dpm reference`, the cached reference image of a scene.

pub mod constructed;
pub mod pareto;
pub mod progressive;
pub mod reference;
pub mod scene_metrics;
pub mod scene_target;
pub mod svg;
pub mod sweep;

use crate::density::{DistributionName, Extent, Grid};
use crate::estimate::settings::EstimatorKind;
use crate::image_io::{Image, ImageError, WriteOptions};
use crate::render::schedule::{DEFAULT_ALPHA, Schedule};
use constructed::ConstructedTarget;
use glam::Vec3;
use reference::{ReferenceError, ReferenceSettings};
use scene_target::{SceneTarget, SceneTargetError};
use std::path::{Path, PathBuf};
use std::time::Instant;
use sweep::{ErrorKind, RadiusSpec, Row, SweepError, SweepPlan, Target};

/// Which estimates a sweep runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum SweptEstimate {
    Cone,
    Epanechnikov,
    Diffusion,
}

#[derive(Clone, Debug, clap::Args)]
pub struct TradeoffArgs {
    /// Sweep a scene's caustics against its reference image (made by `dpm reference`'s rules,
    /// or loaded from its cache) instead of a built-in distribution.
    #[arg(long, value_name = "SCENE", conflicts_with = "distribution")]
    pub scene: Option<PathBuf>,
    /// Built-in distribution with an exact density (default: constructed).
    #[arg(long, value_enum)]
    pub distribution: Option<DistributionName>,
    /// Few points and a small image (seconds, for tests and a first look); flags given
    /// explicitly still win.
    #[arg(long)]
    pub quick: bool,
    /// Photon counts, comma-separated (stored photons). Default: 100000,300000,1000000,3000000 for a
    /// distribution, 50000,100000,200000 for a scene.
    #[arg(long, value_delimiter = ',', value_name = "N,N,...")]
    pub photons: Option<Vec<usize>>,
    /// The cone filter's k values. Default: 50,100,200,400,800.
    #[arg(long, value_delimiter = ',', value_name = "K,K,...")]
    pub cone_k: Option<Vec<usize>>,
    /// Radii of the Epanechnikov and diffusion estimates: a length in scene units, or `Nx`
    /// for N times the map's default radius (the k-equivalent radius for k = 400, which
    /// shrinks as photons are added). Default: 0.5x,1x,2x.
    #[arg(long, value_delimiter = ',', value_name = "R,R,...")]
    pub radii: Option<Vec<RadiusSpec>>,
    /// The diffusion estimate's K values (dimensionless). Default: 0.1,0.2,0.4.
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "K,K,...",
        allow_negative_numbers = true
    )]
    pub diffusivities: Option<Vec<f64>>,
    /// Estimates to sweep. Default: all three.
    #[arg(long, value_enum, value_delimiter = ',', value_name = "NAME,...")]
    pub estimates: Option<Vec<SweptEstimate>>,
    /// Image width: the grid of a distribution (default 256) or the scene's render
    /// (default 320, overriding its camera).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default 256 for a distribution, 240 for a scene).
    #[arg(long)]
    pub height: Option<u32>,
    /// Seed of every photon and pixel sample.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// The error plotted against time and used for the Pareto fronts.
    #[arg(long, value_enum, default_value_t = ErrorKind::Rmse)]
    pub error: ErrorKind,
    /// CSV of every run. Default: out/tradeoff/TARGET.csv.
    #[arg(long, value_name = "FILE.csv")]
    pub csv: Option<PathBuf>,
    /// The plot of error against time. Default: out/tradeoff/TARGET.svg.
    #[arg(long, value_name = "FILE.svg")]
    pub svg: Option<PathBuf>,
    /// Stored photons of each pass of a scene's reference. Default: 5× the largest of --photons.
    #[arg(long)]
    pub reference_photons: Option<usize>,
    /// Progressive passes of a scene's reference (see `dpm reference`).
    #[arg(long, default_value_t = reference::DEFAULT_PASSES)]
    pub reference_passes: u64,
    /// The reference's radius is the k-equivalent radius for this k (see `dpm reference`).
    #[arg(long, default_value_t = reference::DEFAULT_K as usize)]
    pub reference_k: usize,
    /// Folder of cached references (created when missing).
    #[arg(long, default_value = "out/reference")]
    pub cache_dir: PathBuf,
    /// Also write a scene's regions as a PNG: red = edge band, green = flat, black = neither.
    #[arg(long, value_name = "FILE.png")]
    pub regions: Option<PathBuf>,
    /// Worker threads (0: one per core).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Also run each swept estimate progressively for this many passes (at its default
    /// setting: cone k = 400, the others at 1× radius, K = 0.2), scored after 1, 2, 4, ...
    /// passes against cumulative time: one line per estimate on the plot.
    #[arg(long, value_name = "PASSES", default_value_t = 0)]
    pub progressive: u64,
    /// Stored photons per pass of the progressive series. Default: the largest of --photons.
    #[arg(long, value_name = "N")]
    pub progressive_photons: Option<usize>,
}

#[derive(Debug, thiserror::Error)]
pub enum TradeoffError {
    #[error("{0}")]
    Invalid(String),
    #[error("{0}")]
    Target(#[from] SceneTargetError),
    #[error("{0}")]
    Reference(#[from] ReferenceError),
    #[error("{0}")]
    Sweep(#[from] SweepError),
    #[error("{0}")]
    Image(#[from] ImageError),
}

impl TradeoffError {
    /// 2 for bad input (flags, scene, output paths), 1 for failures inside.
    pub fn exit_code(&self) -> u8 {
        match self {
            TradeoffError::Target(SceneTargetError::Embree(_)) => 1,
            TradeoffError::Reference(e) => e.exit_code(),
            TradeoffError::Image(ImageError::Io { .. } | ImageError::Encode { .. }) => 1,
            _ => 2,
        }
    }
}

/// What a sweep wrote and found.
pub struct TradeoffOutcome {
    pub rows: Vec<Row>,
    pub csv: PathBuf,
    pub svg: PathBuf,
    /// The Pareto table (markdown), for stdout.
    pub table: String,
    pub reference: Option<String>,
    pub seconds: f64,
}

fn invalid(message: String) -> TradeoffError {
    TradeoffError::Invalid(message)
}

/// The estimates `--estimates` names (default: all three).
fn estimates(args: &TradeoffArgs) -> Vec<SweptEstimate> {
    args.estimates.clone().unwrap_or(vec![
        SweptEstimate::Cone,
        SweptEstimate::Epanechnikov,
        SweptEstimate::Diffusion,
    ])
}

/// The plan the flags ask for, presets and defaults filled in.
pub fn plan(args: &TradeoffArgs) -> Result<SweepPlan, TradeoffError> {
    let scene = args.scene.is_some();
    let photons = match (args.quick, scene) {
        (true, false) => vec![5_000, 40_000],
        (true, true) => vec![5_000, 20_000],
        (false, false) => vec![100_000, 300_000, 1_000_000, 3_000_000],
        (false, true) => vec![50_000, 100_000, 200_000],
    };
    let (cone_k, radii, diffusivities) = if args.quick {
        (vec![20, 100], vec![RadiusSpec::Scale(1.0)], vec![0.2])
    } else {
        (
            vec![50, 100, 200, 400, 800],
            [0.5, 1.0, 2.0].map(RadiusSpec::Scale).to_vec(),
            vec![0.1, 0.2, 0.4],
        )
    };
    let estimates = estimates(args);
    fn or_none<T>(wanted: bool, v: Vec<T>) -> Vec<T> {
        if wanted { v } else { Vec::new() }
    }
    let wants = |e| estimates.contains(&e);
    let radii = args.radii.clone().unwrap_or(radii);
    let plan = SweepPlan {
        photon_counts: args.photons.clone().unwrap_or(photons),
        cone_k: or_none(
            wants(SweptEstimate::Cone),
            args.cone_k.clone().unwrap_or(cone_k),
        ),
        epanechnikov_radii: or_none(wants(SweptEstimate::Epanechnikov), radii.clone()),
        diffusion_radii: or_none(wants(SweptEstimate::Diffusion), radii),
        diffusivities: args.diffusivities.clone().unwrap_or(diffusivities),
        seed: args.seed,
    };
    if plan.photon_counts.is_empty() || plan.photon_counts.contains(&0) {
        return Err(invalid(format!(
            "--photons {:?}: every count must be at least 1",
            plan.photon_counts
        )));
    }
    if let Some(k) = plan.cone_k.iter().find(|k| **k < 2) {
        return Err(invalid(format!(
            "--cone-k {k}: must be at least 2 (the k-th photon is left out)"
        )));
    }
    if let Some(d) = plan.diffusivities.iter().find(|d| d.is_nan() || **d < 0.0) {
        return Err(invalid(format!(
            "--diffusivities {d}: K must be a number ≥ 0"
        )));
    }
    if estimates.is_empty() || plan.runs() == 0 {
        return Err(invalid(
            "--estimates: nothing to run (no estimate, or an empty parameter list)".into(),
        ));
    }
    if args.reference_k < 2 {
        return Err(invalid(format!(
            "--reference-k {}: must be at least 2",
            args.reference_k
        )));
    }
    if args.reference_photons == Some(0) {
        return Err(invalid("--reference-photons 0: must be at least 1".into()));
    }
    Ok(plan)
}

/// Checks an output path: its extension and that its folder exists (a default path's folder
/// is created).
fn output_path(
    flag: &str,
    given: &Option<PathBuf>,
    default: PathBuf,
    extension: &str,
) -> Result<PathBuf, TradeoffError> {
    let path = match given {
        Some(p) => p.clone(),
        None => {
            if let Some(dir) = default.parent() {
                std::fs::create_dir_all(dir).map_err(|e| {
                    invalid(format!("--{flag}: cannot create {}: {e}", dir.display()))
                })?;
            }
            default
        }
    };
    if path.extension().and_then(|e| e.to_str()) != Some(extension) {
        return Err(invalid(format!(
            "--{flag} {}: must end in .{extension}",
            path.display()
        )));
    }
    if let Some(dir) = crate::image_io::missing_output_directory(&path) {
        return Err(invalid(format!(
            "--{flag} {}: directory {} does not exist",
            path.display(),
            dir.display()
        )));
    }
    Ok(path)
}

fn dimension(flag: &str, value: Option<u32>, default: u32) -> Result<u32, TradeoffError> {
    match value.unwrap_or(default) {
        0 => Err(invalid(format!("--{flag} 0: must be at least 1"))),
        v if v > 16384 => Err(invalid(format!("--{flag} {v}: at most 16384"))),
        v => Ok(v),
    }
}

/// Runs `dpm tradeoff`.
pub fn run(args: &TradeoffArgs) -> Result<TradeoffOutcome, TradeoffError> {
    let plan = plan(args)?;
    if args.regions.is_some() && args.scene.is_none() {
        return Err(invalid("--regions needs --scene".into()));
    }
    let scene = args.scene.is_some();
    let (w, h) = match (args.quick, scene) {
        (true, false) => (48, 48),
        (true, true) => (64, 48),
        (false, false) => (256, 256),
        (false, true) => (320, 240),
    };
    let (width, height) = (
        dimension("width", args.width, w)?,
        dimension("height", args.height, h)?,
    );
    let stem = match &args.scene {
        Some(p) => p
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_else(|| "scene".into()),
        None => format!(
            "{:?}",
            args.distribution.unwrap_or(DistributionName::Constructed)
        )
        .to_lowercase(),
    };
    let out = Path::new("out/tradeoff");
    let csv = output_path("csv", &args.csv, out.join(format!("{stem}.csv")), "csv")?;
    let svg = output_path("svg", &args.svg, out.join(format!("{stem}.svg")), "svg")?;
    if let Some(p) = &args.regions {
        output_path("regions", &Some(p.clone()), PathBuf::new(), "png")?;
    }
    let pool = crate::embree::thread_pool(args.threads)
        .map_err(|e| invalid(format!("--threads {}: {e}", args.threads)))?;
    pool.install(|| {
        crate::embree::enable_flush_to_zero();
        let start = Instant::now();
        let mut reference_line = None;
        let mut target: Box<dyn Target> = match &args.scene {
            None => Box::new(ConstructedTarget::new(
                args.distribution.unwrap_or(DistributionName::Constructed),
                Grid {
                    width: width as usize,
                    height: height as usize,
                    extent: Extent::UNIT,
                },
                args.seed,
            )),
            Some(path) => {
                let mut target = SceneTarget::load(path, width, height, args.seed)?;
                let largest = plan.photon_counts.iter().copied().max().unwrap_or(1);
                let settings = ReferenceSettings {
                    photons: args
                        .reference_photons
                        .unwrap_or(largest * reference::PHOTON_FACTOR),
                    k: args.reference_k,
                    passes: args.reference_passes,
                    seed: args.seed,
                };
                let made = reference::ensure(&target, settings, &args.cache_dir)?;
                let line = reference::describe(&made, settings);
                eprintln!("{line}");
                reference_line = Some(line);
                target.set_reference(&made.image);
                if let (Some(p), Some(regions)) = (&args.regions, target.regions()) {
                    let image = Image::from_fn(regions.width, regions.height, |x, y| {
                        let i = y * regions.width + x;
                        match (regions.edge_band[i], regions.flat[i]) {
                            (true, _) => Vec3::new(1.0, 0.0, 0.0),
                            (_, true) => Vec3::new(0.0, 1.0, 0.0),
                            _ => Vec3::ZERO,
                        }
                    });
                    crate::image_io::write_image(p, &image, &WriteOptions::default())?;
                }
                // Rendered before any run is timed; every run reuses it.
                target.direct_light();
                Box::new(target)
            }
        };
        let bar = crate::timing::progress(plan.runs() as u64, "tradeoff");
        let rows = sweep::run_sweep(&plan, target.as_mut(), &bar);
        bar.finish_and_clear();
        let mut rows = rows?;
        if args.progressive > 0 {
            let kinds: Vec<EstimatorKind> = estimates(args)
                .iter()
                .map(|e| match e {
                    SweptEstimate::Cone => EstimatorKind::Cone,
                    SweptEstimate::Epanechnikov => EstimatorKind::Epanechnikov,
                    SweptEstimate::Diffusion => EstimatorKind::Diffusion,
                })
                .collect();
            let count = args
                .progressive_photons
                .unwrap_or_else(|| plan.photon_counts.iter().copied().max().unwrap_or(1));
            let bar = crate::timing::progress(args.progressive, "progressive");
            let schedule = Schedule::new(DEFAULT_ALPHA, args.seed);
            let series = progressive::run_progressive(
                &kinds,
                count,
                args.progressive,
                schedule,
                target.as_mut(),
                &bar,
            );
            bar.finish_and_clear();
            rows.extend(series?);
        }
        crate::density::write_text(&csv, &sweep::format_csv(&rows))?;
        let title = format!(
            "{} ({}x{}): {} against time",
            target.name(),
            width,
            height,
            args.error.label()
        );
        let plot = svg::plot(
            &title,
            "seconds (log scale)",
            args.error.label(),
            &series(&rows, args.error),
        );
        crate::density::write_text(&svg, &plot)?;
        Ok(TradeoffOutcome {
            table: front_table(&rows, args.error),
            rows,
            csv: csv.clone(),
            svg: svg.clone(),
            reference: reference_line,
            seconds: start.elapsed().as_secs_f64(),
        })
    })
}

/// A row's series: its estimate, or "progressive ESTIMATE" for a progressive series.
fn series_name(r: &Row) -> String {
    match r.passes {
        Some(_) => format!("progressive {}", r.estimate),
        None => r.estimate.to_string(),
    }
}

/// Series names in the order they appear in the rows.
fn estimate_names(rows: &[Row]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for r in rows {
        let name = series_name(r);
        if !names.contains(&name) {
            names.push(name);
        }
    }
    names
}

/// One plot series per estimate, with its front.
pub fn series(rows: &[Row], error: ErrorKind) -> Vec<svg::Series> {
    estimate_names(rows)
        .into_iter()
        .map(|name| {
            let members: Vec<&Row> = rows.iter().filter(|r| series_name(r) == name).collect();
            let points: Vec<(f64, f64)> = members
                .iter()
                .map(|r| (r.total_seconds(), error.of(&r.errors)))
                .collect();
            // A progressive series is drawn as its line through every checkpoint.
            let front = if members.iter().any(|r| r.passes.is_some()) {
                (0..points.len()).collect()
            } else {
                pareto::pareto_front(&points)
            };
            svg::Series {
                name,
                points,
                front,
            }
        })
        .collect()
}

/// Each estimate's Pareto front as a markdown table; the last column marks the runs that are
/// also on the front of all estimates together.
pub fn front_table(rows: &[Row], error: ErrorKind) -> String {
    let point = |r: &Row| (r.total_seconds(), error.of(&r.errors));
    let all: Vec<(f64, f64)> = rows.iter().map(point).collect();
    let overall = pareto::pareto_front(&all);
    let mut out = format!(
        "Pareto fronts by {} ({} runs)\n\n| estimate | photons | parameters | trace s | prepare s \
         | estimate s | total s | RMSE | rel. MSE | edge-band RMSE | flat noise | best overall |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
        error.label(),
        rows.len()
    );
    for name in estimate_names(rows) {
        let indices: Vec<usize> = (0..rows.len())
            .filter(|&i| series_name(&rows[i]) == name)
            .collect();
        let points: Vec<(f64, f64)> = indices.iter().map(|&i| all[i]).collect();
        for j in pareto::pareto_front(&points) {
            let i = indices[j];
            let r = &rows[i];
            out.push_str(&format!(
                "| {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4} | {:.4} | {:.4} | {:.4} | {} |\n",
                name,
                r.photons,
                match r.passes {
                    Some(p) => format!("{} ×{p} passes", r.parameters()),
                    None => r.parameters(),
                },
                r.trace_seconds,
                r.prepare_seconds,
                r.estimate_seconds,
                r.total_seconds(),
                r.errors.rmse,
                r.errors.relative_mse,
                r.errors.edge_band_rmse,
                r.errors.flat_noise,
                if overall.contains(&i) { "yes" } else { "" }
            ));
        }
    }
    out
}
