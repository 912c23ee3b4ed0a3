//! `dpm density`: estimate the density of photons lying in a plane on a pixel grid, as in the
//! paper's constructed-distribution experiment (Section 4, Figures 4-6), and score it against
//! the known density. Owns the command's flags, the photon sources (a CSV file or a built-in
//! distribution), the orchestration and the outputs; it uses the estimates through
//! [`RadianceEstimate`](crate::estimate::RadianceEstimate) and must not implement kernels, trace rays or touch scenes.
//!
//! A pixel's value is the estimate at its centre of photon power per unit area (irradiance: no
//! BRDF, no 1/π). Row 0 of every output is the top of the extent (`Y1`). The truth written with
//! `--truth` and used by the metrics is the exact density at each pixel's centre (not averaged
//! over the pixel), because every estimate is a point estimate at the centre.

pub mod csv;
pub mod distribution;
pub mod grid;
pub mod kernel_field;
pub mod metrics;
pub mod rng;
pub mod shapes;

pub use distribution::{Distribution, DistributionName, Truth};
pub use grid::{Extent, Grid};
pub use metrics::{Metrics, RegionWidths, Regions};

use crate::estimate::{EstimateError, EstimatorFlags, ResolvedEstimator};
use crate::image_io::{Image, ImageError, WriteOptions, write_atomically, write_image};
use crate::photon::{Photon, PhotonMap};
use crate::render::schedule::{Schedule, pass_estimator};
use glam::{DVec2, Vec3};
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Clone, Debug, clap::Args)]
pub struct DensityArgs {
    /// Photons: CSV, one photon a line, `x,y` or `x,y,power` (power 1 when absent).
    #[arg(long, value_name = "FILE", required_unless_present = "distribution")]
    pub photons: Option<PathBuf>,
    /// A built-in distribution with a known density, instead of --photons.
    #[arg(long, value_enum, conflicts_with = "photons")]
    pub distribution: Option<DistributionName>,
    /// Photons drawn from the built-in distribution.
    #[arg(long, default_value_t = 1_000_000, value_parser = clap::value_parser!(u64).range(1..))]
    pub count: u64,
    /// Seed of the built-in distribution's photons.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub width: u32,
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(1..=65536))]
    pub height: u32,
    /// The rectangle of the plane the image covers.
    #[arg(
        long,
        value_name = "X0,Y0,X1,Y1",
        default_value = "0,0,1,1",
        allow_hyphen_values = true
    )]
    pub extent: Extent,
    #[command(flatten)]
    pub estimator: EstimatorFlags,
    /// Output image (.png, .exr or .pfm).
    #[arg(short = 'o', long, value_name = "OUT")]
    pub output: PathBuf,
    /// Also write the grid values (and the truth, when known) as CSV.
    #[arg(long, value_name = "FILE")]
    pub csv: Option<PathBuf>,
    /// Write the exact density at each pixel centre as an image (built-in distributions only).
    // `conflicts_with`, not `requires = "distribution"`: clap skips a `requires` whose target
    // conflicts with a given argument (clap issue 4520).
    #[arg(long, value_name = "OUT", conflicts_with = "photons")]
    pub truth: Option<PathBuf>,
    /// Write an image of the diffusion estimate's kernel at each pixel (like the paper's
    /// Figure 2b): hue = the edge direction's angle (0° to 180° round the colour wheel),
    /// brightness = 1 − λ2 (black: round kernel; bright: squeezed across an edge).
    #[arg(long, value_name = "OUT")]
    pub kernel_field: Option<PathBuf>,
    /// Write the report, metrics included, as JSON.
    #[arg(long, value_name = "FILE.json")]
    pub stats: Option<PathBuf>,
    /// PNG exposure in stops; by default the true peak (or the estimate's 99.5th percentile)
    /// maps to white.
    #[arg(long, allow_hyphen_values = true)]
    pub exposure: Option<f32>,
    /// Width of the edge band around discontinuities (world units).
    #[arg(long, default_value_t = 0.04)]
    pub band: f64,
    /// Distance from the border inside which metrics are not taken (world units).
    #[arg(long, default_value_t = 0.05)]
    pub margin: f64,
    /// Progressive passes (built-in distributions only): each draws --count fresh photons from
    /// its own stream and shrinks every radius by r²(i+1) = r²(i)·(i+α)/(i+1); the image is the
    /// mean of the passes, and the report gives the error after 1, 2, 4, ... passes.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    pub passes: u64,
    /// α of the progressive radius reduction, in (0, 1).
    #[arg(long, default_value_t = crate::render::schedule::DEFAULT_ALPHA)]
    pub ppm_alpha: f64,
}

#[derive(Debug, thiserror::Error)]
pub enum DensityError {
    #[error(transparent)]
    Csv(#[from] csv::CsvError),
    #[error("{}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{}: no photons", .0.display())]
    NoPhotons(PathBuf),
    #[error(transparent)]
    Estimator(#[from] EstimateError),
    #[error("--kernel-field needs --estimator diffusion (the estimator is {0})")]
    KernelFieldNeedsDiffusion(String),
    #[error(transparent)]
    Image(#[from] ImageError),
    #[error("{0}")]
    Invalid(String),
}

#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Seconds {
    pub photons: f64,
    pub prepare: f64,
    pub estimate: f64,
}

/// What a run did and, for a built-in distribution, how well.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct DensityReport {
    /// The photon file or the distribution's name.
    pub source: String,
    pub photons: usize,
    pub estimator: String,
    pub width: usize,
    pub height: usize,
    pub extent: Extent,
    pub regions: RegionWidths,
    pub seconds: Seconds,
    pub metrics: Option<Metrics>,
    /// Passes averaged (1 for a one-shot estimate).
    pub passes: u64,
    /// With a known density: the metrics of the mean after 1, 2, 4, ... passes (and the last).
    pub progression: Vec<(u64, Metrics)>,
}

impl std::fmt::Display for DensityReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut rows = vec![
            ("source", self.source.clone()),
            ("photons", self.photons.to_string()),
            ("estimator", self.estimator.clone()),
            ("image", format!("{}x{}", self.width, self.height)),
            (
                "seconds: photons/prepare/estimate",
                format!(
                    "{:.2}/{:.2}/{:.2}",
                    self.seconds.photons, self.seconds.prepare, self.seconds.estimate
                ),
            ),
        ];
        if self.passes > 1 {
            rows.push(("passes", self.passes.to_string()));
        }
        for (n, m) in self.progression.iter().filter(|_| self.passes > 1) {
            rows.push((
                "after passes: RMSE / edge / flat / line",
                format!(
                    "{n:>5}: {:.4} / {:.4} / {:.4} / {}",
                    m.rmse,
                    m.edge_band_rmse,
                    m.flat_noise,
                    m.line_peak.map_or("-".into(), |l| format!("{l:.3}"))
                ),
            ));
        }
        if let Some(m) = &self.metrics {
            rows.push((
                "edge band / margin",
                format!("{} / {}", self.regions.band, self.regions.margin),
            ));
            rows.extend(m.rows());
        }
        f.write_str(&metrics::format_table("dpm density", &rows))
    }
}

/// The photons of a run and, for a built-in distribution, the distribution.
pub struct PhotonSource {
    pub name: String,
    pub photons: Vec<Photon>,
    pub distribution: Option<Distribution>,
}

/// Reads the photon file or draws the built-in distribution's photons.
pub fn load_photons(args: &DensityArgs) -> Result<PhotonSource, DensityError> {
    load_photons_with_seed(args, args.seed)
}

/// [`load_photons`], the built-in distribution drawn with `seed` (a pass's own seed).
fn load_photons_with_seed(args: &DensityArgs, seed: u64) -> Result<PhotonSource, DensityError> {
    if let Some(name) = args.distribution {
        let distribution = Distribution::new(name, args.count);
        let photons = distribution.photons(seed);
        let name = format!("{name:?} distribution, seed {}", args.seed).to_lowercase();
        return Ok(PhotonSource {
            name,
            photons,
            distribution: Some(distribution),
        });
    }
    let path = args
        .photons
        .clone()
        .expect("clap requires --photons or --distribution");
    let text = std::fs::read_to_string(&path).map_err(|source| DensityError::Read {
        path: path.clone(),
        source,
    })?;
    let photons: Vec<Photon> = csv::parse_photons(&path, &text)?
        .into_iter()
        .map(|p| {
            Photon::new(
                Vec3::new(p.x, p.y, 0.0),
                Vec3::splat(p.power),
                Vec3::NEG_Z,
                Vec3::Z,
            )
        })
        .collect();
    if photons.is_empty() {
        return Err(DensityError::NoPhotons(path));
    }
    Ok(PhotonSource {
        name: path.display().to_string(),
        photons,
        distribution: None,
    })
}

/// The regions of the metrics for a distribution on a grid.
pub fn regions(distribution: &Distribution, grid: &Grid, widths: RegionWidths) -> Regions {
    let (edges, kinks) = (
        distribution.layout.discontinuities(),
        distribution.layout.kinks(),
    );
    let nearest = |curves: &[shapes::Curve], p: DVec2| {
        curves
            .iter()
            .map(|c| c.distance(p))
            .fold(f64::INFINITY, f64::min)
    };
    let line = distribution.layout.thin_line;
    let probe = metrics::LineProbe {
        a: line.a,
        b: line.b,
        true_peak: distribution.thin_line_peak(),
    };
    Regions::new(
        grid,
        widths,
        |p| nearest(&edges, p),
        |p| nearest(&kinks, p),
        Some(probe),
    )
}

/// Runs the density command: photons → map → estimate on the grid → outputs and report.
pub fn run(args: &DensityArgs) -> Result<DensityReport, DensityError> {
    let grid = Grid {
        width: args.width as usize,
        height: args.height as usize,
        extent: args.extent,
    };
    let widths = RegionWidths {
        band: args.band,
        margin: args.margin,
    };

    if args.passes > 1 && args.distribution.is_none() {
        return Err(DensityError::Invalid(
            "--passes needs --distribution: a photon file cannot give fresh photons per pass"
                .into(),
        ));
    }
    if !(args.ppm_alpha > 0.0 && args.ppm_alpha < 1.0) {
        return Err(DensityError::Invalid(format!(
            "--ppm-alpha {}: must be in (0, 1)",
            args.ppm_alpha
        )));
    }
    let settings = args.estimator.settings();
    settings.validate()?;
    let schedule = Schedule::new(args.ppm_alpha, args.seed);
    let mut seconds = Seconds::default();
    let mut sums = vec![glam::DVec3::ZERO; grid.width * grid.height];
    let mut base_radius = settings.radius;
    let mut resolved_first = None;
    let mut last_map = None;
    let mut progression = Vec::new();
    let mut source_name = String::new();
    let mut photon_count = 0;
    let mut distribution = None;
    let mut truth = None;
    // The photons of the passes before, newest last, that shape a pass's kernels.
    let mut history: std::collections::VecDeque<(u64, Vec<crate::photon::Photon>)> =
        Default::default();
    let depth = u64::from(settings.tensor_history);
    for pass in 0..args.passes {
        // Only the last pass's map is kept (for the kernel field): free the previous one first.
        drop(last_map.take());
        let start = Instant::now();
        let source = load_photons_with_seed(args, schedule.seed(pass))?;
        if depth > 0 {
            let kept = (settings.history_photons).kept(pass, depth, source.photons.iter().copied());
            history.push_back((pass, kept));
        }
        photon_count = source.photons.len();
        source_name = source.name;
        if distribution.is_none() {
            truth = source.distribution.as_ref().map(|d| d.truth_on(&grid));
            distribution = source.distribution;
        }
        let emitted = photon_count as u64;
        let mut map = PhotonMap::build(source.photons, emitted);
        seconds.photons += start.elapsed().as_secs_f64();

        let start = Instant::now();
        if pass == 0 && base_radius.is_none() {
            base_radius = crate::estimate::settings::k_equivalent_radius(&map, settings.k);
        }
        let resolved = pass_estimator(&settings, base_radius, &schedule, pass).resolve(&map)?;
        if args.kernel_field.is_some() && !matches!(resolved, ResolvedEstimator::Diffusion(_)) {
            return Err(DensityError::KernelFieldNeedsDiffusion(
                resolved.to_string(),
            ));
        }
        resolved_first.get_or_insert(resolved);
        // The passes before this one, when it has any, shape its kernels.
        let analysis = match resolved {
            ResolvedEstimator::Diffusion(d) if history.len() > 1 => {
                let earlier: Vec<(u64, &[crate::photon::Photon])> = (history.iter())
                    .take(history.len() - 1)
                    .map(|(pass, photons)| (*pass, photons.as_slice()))
                    .collect();
                let mut analysis = crate::estimate::diffusion::shaped::history_map(
                    &earlier,
                    depth,
                    settings.history_photons,
                )
                .expect("an earlier pass");
                d.gradient_pass(&mut analysis);
                Some((d, analysis))
            }
            _ => None,
        };
        let estimate: Box<dyn crate::estimate::RadianceEstimate + '_> = match &analysis {
            Some((d, analysis)) => Box::new(crate::estimate::diffusion::shaped::ShapedBy {
                estimate: *d,
                analysis,
            }),
            None => resolved.into_boxed(),
        };
        estimate.prepare(&mut map);
        seconds.prepare += start.elapsed().as_secs_f64();

        let start = Instant::now();
        let what = if args.passes > 1 {
            format!("{} pass {}/{}", estimate.name(), pass + 1, args.passes)
        } else {
            estimate.name().to_string()
        };
        let bar = grid::progress_bar(grid.height, &what);
        let pass_pixels = grid::evaluate(&grid, &map, estimate.as_ref(), &bar);
        for (s, p) in sums.iter_mut().zip(&pass_pixels) {
            *s += p.as_dvec3();
        }
        seconds.estimate += start.elapsed().as_secs_f64();
        let done = pass + 1;
        if let (Some(d), Some(t)) = (&distribution, &truth)
            && (done.is_power_of_two() || done == args.passes)
        {
            let mean = mean_values(&sums, done);
            progression.push((done, Metrics::new(&mean, t, &regions(d, &grid, widths))));
        }
        last_map = Some((map, resolved));
        if history.len() > settings.tensor_history as usize {
            history.pop_front();
        }
    }
    let passes = args.passes;
    let resolved = resolved_first.expect("at least one pass");
    let pixels: Vec<Vec3> = sums
        .iter()
        .map(|s| (*s / passes as f64).as_vec3())
        .collect();
    let (map, last_resolved) = last_map.expect("at least one pass");
    let source = PhotonSource {
        name: source_name,
        photons: Vec::new(),
        distribution,
    };
    let (photons_seconds, prepare_seconds, estimate_seconds) =
        (seconds.photons, seconds.prepare, seconds.estimate);

    let values = mean_values(&sums, passes);
    let metrics = source
        .distribution
        .as_ref()
        .zip(truth.as_ref())
        .map(|(d, t)| {
            let regions = regions(d, &grid, widths);
            Metrics::new(&values, t, &regions)
        });

    let truth_centre = truth.as_ref().map(|t| t.centre.as_slice());
    let exposure = args
        .exposure
        .unwrap_or_else(|| auto_exposure(&values, truth_centre));
    let options = WriteOptions {
        exposure,
        ..Default::default()
    };
    write_image(
        &args.output,
        &Image {
            width: grid.width,
            height: grid.height,
            pixels,
        },
        &options,
    )?;
    if let (Some(path), Some(t)) = (&args.truth, &truth) {
        let grey: Vec<f32> = t.centre.iter().map(|&v| v as f32).collect();
        let image = Image::from_grey(grid.width, grid.height, &grey);
        write_image(path, &image, &options)?;
    }
    // The kernel field of the last pass (at its radii).
    if let (Some(path), ResolvedEstimator::Diffusion(diffusion)) =
        (&args.kernel_field, last_resolved)
    {
        let bar = grid::progress_bar(grid.height, "kernel field");
        let image = kernel_field::render(&grid, &map, &diffusion, &bar);
        write_image(path, &image, &WriteOptions::default())?;
    }
    if let Some(path) = &args.csv {
        let text = csv::format_grid(grid.width, &values, truth_centre, |row, col| {
            let c = grid.centre(row, col);
            (c.x, c.y)
        });
        write_text(path, &text)?;
    }

    let report = DensityReport {
        source: source.name,
        photons: photon_count,
        estimator: if passes > 1 {
            format!("progressive {resolved} (pass 0), alpha={}", args.ppm_alpha)
        } else {
            resolved.to_string()
        },
        width: grid.width,
        height: grid.height,
        extent: grid.extent,
        regions: widths,
        seconds: Seconds {
            photons: photons_seconds,
            prepare: prepare_seconds,
            estimate: estimate_seconds,
        },
        metrics,
        passes,
        progression,
    };
    if let Some(path) = &args.stats {
        let json = serde_json::to_string_pretty(&report).expect("the report serialises");
        write_text(path, &(json + "\n"))?;
    }
    Ok(report)
}

/// The channel means of `passes` passes' summed pixels.
fn mean_values(sums: &[glam::DVec3], passes: u64) -> Vec<f64> {
    sums.iter()
        .map(|s| (s.x + s.y + s.z) / (3.0 * passes as f64))
        .collect()
}

/// Stops that map the true peak, or without a truth the estimate's 99.5th percentile, to white.
fn auto_exposure(values: &[f64], truth: Option<&[f64]>) -> f32 {
    let white = match truth {
        Some(t) => t.iter().copied().fold(0.0, f64::max),
        None => {
            let mut sorted: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
            sorted.sort_by(f64::total_cmp);
            sorted
                .get(sorted.len() * 995 / 1000)
                .copied()
                .unwrap_or(1.0)
        }
    };
    if white > 0.0 {
        -(white.log2() as f32)
    } else {
        0.0
    }
}

/// Writes text atomically, like the images.
pub fn write_text(path: &Path, text: &str) -> Result<(), ImageError> {
    write_atomically(path, |out| {
        out.write_all(text.as_bytes()).map_err(|e| e.to_string())
    })
}
