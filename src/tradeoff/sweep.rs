//! The sweep itself: which runs a sweep makes (photon counts × each estimate's parameters),
//! running them against a [`Target`] with the photon map traced once per count and the gradient
//! pass run once per (count, gradient radius), and the rows that record each run (CSV). Owns
//! the run order, the timing split and the CSV columns; it must not know how a target makes
//! photons, evaluates an image or scores it (that is [`Target`]'s job), and must not plot.

use crate::estimate::settings::{EstimatorKind, EstimatorSettings, k_equivalent_radius};
use crate::estimate::{EstimateError, RadianceEstimate, ResolvedEstimator};
use crate::photon::PhotonMap;
use indicatif::ProgressBar;
use std::fmt::Write as _;
use std::time::Instant;

/// k of the k-equivalent radius that `1x` means: dpm's default (the paper's cone setting).
pub const UNIT_RADIUS_K: usize = 400;

/// A fixed radius: in scene units, or a multiple of the map's k-equivalent radius for
/// k = [`UNIT_RADIUS_K`] (written `2x`), which shrinks as the photon count grows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RadiusSpec {
    Absolute(f32),
    Scale(f32),
}

impl std::str::FromStr for RadiusSpec {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let s = s.trim();
        let (number, scaled) = match s.strip_suffix('x') {
            Some(n) => (n, true),
            None => (s, false),
        };
        let v: f32 = number
            .parse()
            .map_err(|_| format!("{s:?} is not a length or a multiple like 2x"))?;
        if !(v > 0.0 && v.is_finite()) {
            return Err(format!("{s:?} must be positive and finite"));
        }
        Ok(if scaled {
            RadiusSpec::Scale(v)
        } else {
            RadiusSpec::Absolute(v)
        })
    }
}

impl std::fmt::Display for RadiusSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RadiusSpec::Absolute(r) => write!(f, "{r}"),
            RadiusSpec::Scale(s) => write!(f, "{s}x"),
        }
    }
}

/// Every run of a sweep: each photon count with each estimate's parameter list.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepPlan {
    pub photon_counts: Vec<usize>,
    pub cone_k: Vec<usize>,
    pub epanechnikov_radii: Vec<RadiusSpec>,
    pub diffusion_radii: Vec<RadiusSpec>,
    pub diffusivities: Vec<f64>,
    pub seed: u64,
}

impl SweepPlan {
    pub fn runs(&self) -> usize {
        self.photon_counts.len()
            * (self.cone_k.len()
                + self.epanechnikov_radii.len()
                + self.diffusion_radii.len() * self.diffusivities.len())
    }
}

/// The errors of one run; what each means for a target is documented by the target.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Errors {
    pub rmse: f64,
    pub relative_mse: f64,
    pub edge_band_rmse: f64,
    pub flat_noise: f64,
}

/// Which error a plot or a front uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum ErrorKind {
    Rmse,
    RelativeMse,
    EdgeBandRmse,
    FlatNoise,
}

impl ErrorKind {
    pub fn of(self, e: &Errors) -> f64 {
        match self {
            ErrorKind::Rmse => e.rmse,
            ErrorKind::RelativeMse => e.relative_mse,
            ErrorKind::EdgeBandRmse => e.edge_band_rmse,
            ErrorKind::FlatNoise => e.flat_noise,
        }
    }
    pub fn label(self) -> &'static str {
        match self {
            ErrorKind::Rmse => "RMSE",
            ErrorKind::RelativeMse => "relative MSE",
            ErrorKind::EdgeBandRmse => "edge-band RMSE",
            ErrorKind::FlatNoise => "flat-region noise",
        }
    }
}

/// One run: one estimate with one parameter set on one photon map.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    pub target: String,
    /// `cone`, `epanechnikov` or `diffusion`.
    pub estimate: &'static str,
    pub photons: usize,
    pub k: Option<usize>,
    pub radius: Option<f32>,
    pub gradient_radius: Option<f32>,
    pub diffusivity: Option<f64>,
    /// Tracing (or drawing) the photons and building the map, once per count.
    pub trace_seconds: f64,
    /// The gradient pass (diffusion only), once per (count, gradient radius).
    pub prepare_seconds: f64,
    /// Evaluating the estimate at every pixel.
    pub estimate_seconds: f64,
    pub errors: Errors,
    /// Passes averaged, for a row of a progressive series (cumulative times); `None` for a
    /// one-shot run.
    pub passes: Option<u64>,
}

impl Row {
    pub fn total_seconds(&self) -> f64 {
        self.trace_seconds + self.prepare_seconds + self.estimate_seconds
    }

    /// The parameters in one short label, e.g. `k=400` or `r=0.0056 K=0.2`.
    pub fn parameters(&self) -> String {
        let mut parts = Vec::new();
        if let Some(k) = self.k {
            parts.push(format!("k={k}"));
        }
        if let Some(r) = self.radius {
            parts.push(format!("r={r:.4}"));
        }
        if let Some(d) = self.diffusivity {
            parts.push(format!("K={d}"));
        }
        parts.join(" ")
    }
}

pub const CSV_HEADER: &str = "target,estimate,photons,k,radius,gradient_radius,diffusivity,\
trace_seconds,prepare_seconds,estimate_seconds,total_seconds,rmse,relative_mse,edge_band_rmse,\
flat_noise,passes";

/// The rows as CSV (header first); an unused parameter is an empty cell.
pub fn format_csv(rows: &[Row]) -> String {
    let mut out = String::from(CSV_HEADER);
    out.push('\n');
    let opt = |v: Option<String>| v.unwrap_or_default();
    for r in rows {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{:.6},{:.6},{:.6},{:.6},{:.6e},{:.6e},{:.6e},{:.6e},{}",
            r.target.replace(',', ";"),
            r.estimate,
            r.photons,
            opt(r.k.map(|k| k.to_string())),
            opt(r.radius.map(|v| v.to_string())),
            opt(r.gradient_radius.map(|v| v.to_string())),
            opt(r.diffusivity.map(|v| v.to_string())),
            r.trace_seconds,
            r.prepare_seconds,
            r.estimate_seconds,
            r.total_seconds(),
            r.errors.rmse,
            r.errors.relative_mse,
            r.errors.edge_band_rmse,
            r.errors.flat_noise,
            opt(r.passes.map(|p| p.to_string())),
        );
    }
    out
}

/// What a sweep runs against: a photon source, an image to evaluate estimates on, a score.
pub trait Target {
    /// Short name for the CSV and the plot title.
    fn name(&self) -> String;
    /// A photon map of about `count` stored photons, from pass `pass`'s random streams.
    fn photons(&mut self, count: usize, pass: u64) -> Result<PhotonMap, SweepError>;
    /// The estimate at every pixel (scalar per pixel, row by row).
    fn evaluate(&self, map: &PhotonMap, estimate: &dyn RadianceEstimate) -> Vec<f64>;
    /// The errors of an evaluated image.
    fn score(&self, values: &[f64]) -> Errors;
}

#[derive(Debug, thiserror::Error)]
pub enum SweepError {
    #[error("{0}")]
    Estimate(#[from] EstimateError),
    #[error("{0}")]
    Target(String),
}

fn settings(kind: EstimatorKind) -> EstimatorSettings {
    EstimatorSettings {
        estimator: kind,
        ..EstimatorSettings::default()
    }
}

fn radius_of(spec: RadiusSpec, unit: f32) -> f32 {
    match spec {
        RadiusSpec::Absolute(r) => r,
        RadiusSpec::Scale(s) => s * unit,
    }
}

/// Runs every run of `plan` against `target`, one map per photon count; `bar` counts runs.
pub fn run_sweep(
    plan: &SweepPlan,
    target: &mut dyn Target,
    bar: &ProgressBar,
) -> Result<Vec<Row>, SweepError> {
    let name = target.name();
    let mut rows = Vec::with_capacity(plan.runs());
    for &count in &plan.photon_counts {
        bar.set_message(format!("{count} photons: tracing"));
        let start = Instant::now();
        let mut map = target.photons(count, 0)?;
        let trace_seconds = start.elapsed().as_secs_f64();
        // `1x` radii follow the map, like dpm's default radius.
        let unit = k_equivalent_radius(&map, UNIT_RADIUS_K).unwrap_or(1.0);
        let photons = map.len();
        let row = |estimate, prepare_seconds, estimate_seconds, errors| Row {
            target: name.clone(),
            estimate,
            photons,
            k: None,
            radius: None,
            gradient_radius: None,
            diffusivity: None,
            trace_seconds,
            prepare_seconds,
            estimate_seconds,
            errors,
            passes: None,
        };
        let measure = |map: &PhotonMap, resolved: ResolvedEstimator| {
            let estimate = resolved.into_boxed();
            let start = Instant::now();
            let values = target.evaluate(map, estimate.as_ref());
            let seconds = start.elapsed().as_secs_f64();
            (seconds, target.score(&values))
        };

        for &k in &plan.cone_k {
            bar.set_message(format!("{count} photons: cone k={k}"));
            let resolved = EstimatorSettings {
                k,
                ..settings(EstimatorKind::Cone)
            }
            .resolve(&map)?;
            let (seconds, errors) = measure(&map, resolved);
            rows.push(Row {
                k: Some(k),
                ..row("cone", 0.0, seconds, errors)
            });
            bar.inc(1);
        }
        for &spec in &plan.epanechnikov_radii {
            let radius = radius_of(spec, unit);
            bar.set_message(format!("{count} photons: epanechnikov r={radius:.4}"));
            let resolved = EstimatorSettings {
                radius: Some(radius),
                ..settings(EstimatorKind::Epanechnikov)
            }
            .resolve(&map)?;
            let (seconds, errors) = measure(&map, resolved);
            rows.push(Row {
                radius: Some(radius),
                ..row("epanechnikov", 0.0, seconds, errors)
            });
            bar.inc(1);
        }
        for &spec in &plan.diffusion_radii {
            let radius = radius_of(spec, unit);
            let base = EstimatorSettings {
                radius: Some(radius),
                ..settings(EstimatorKind::Diffusion)
            };
            let diffusion = match base.resolve(&map)? {
                ResolvedEstimator::Diffusion(d) => d,
                _ => unreachable!("diffusion settings resolve to the diffusion estimate"),
            };
            // One gradient pass serves every K at this radius; each run is charged for it,
            // since a user making that one image would pay it once.
            bar.set_message(format!(
                "{count} photons: gradient pass r={:.4}",
                diffusion.gradient_radius()
            ));
            let start = Instant::now();
            diffusion.gradient_pass(&mut map);
            let prepare_seconds = start.elapsed().as_secs_f64();
            for &diffusivity in &plan.diffusivities {
                bar.set_message(format!(
                    "{count} photons: diffusion r={radius:.4} K={diffusivity}"
                ));
                let resolved = EstimatorSettings {
                    diffusivity,
                    ..base.clone()
                }
                .resolve(&map)?;
                let (seconds, errors) = measure(&map, resolved);
                rows.push(Row {
                    radius: Some(radius),
                    gradient_radius: Some(diffusion.gradient_radius()),
                    diffusivity: Some(diffusivity),
                    ..row("diffusion", prepare_seconds, seconds, errors)
                });
                bar.inc(1);
            }
        }
    }
    Ok(rows)
}
