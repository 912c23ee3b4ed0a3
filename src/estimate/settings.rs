//! Estimator settings shared by `dpm render` and `dpm density` (a `clap::Args` struct to
//! flatten into both), their validation, the defaults derived from the photon map, and the
//! construction of the chosen estimate. Owns the command-line surface of the estimates; must
//! not parse anything else or run queries beyond the few that derive a default radius.

use super::RadianceEstimate;
use super::classic::{FixedRadiusEstimate, KnnEstimate};
use super::diffusion::{DiffusionEstimate, DiffusionKernel, DiffusionParams, DiffusivityUnits};
use super::kernel::RadialKernel;
use crate::photon::{Neighbours, PhotonMap};
use std::fmt;

/// Which radiance estimate to use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum EstimatorKind {
    /// k nearest photons, constant kernel (Eq. 1).
    Simple,
    /// k nearest photons, Jensen's cone filter (Eq. 3).
    Cone,
    /// k nearest photons, Gaussian kernel, exactly normalised.
    Gaussian,
    /// Fixed radius, Epanechnikov kernel (Eq. 5).
    Epanechnikov,
    /// Fixed radius, anisotropic kernel steered by the structure tensor (Eq. 14).
    Diffusion,
}

/// A setting that cannot work, naming the flag.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum EstimateError {
    #[error("--{flag} {value}: {reason}")]
    InvalidSetting {
        flag: &'static str,
        value: String,
        reason: &'static str,
    },
    #[error(
        "cannot derive --radius from the photon map: the sampled photons' k-th nearest \
         neighbours coincide with them; give --radius"
    )]
    DegenerateMap,
}

/// Radiance-estimate settings.
#[derive(Clone, Debug, PartialEq, clap::Args)]
pub struct EstimatorSettings {
    /// Radiance estimate. `diffusion` is the paper's method; `cone` with k = 400 is the
    /// paper's baseline; `simple`, `gaussian` (k-NN) and `epanechnikov` (fixed radius) are the
    /// other classic estimates. Every k-NN estimate leaves the k-th photon out of its sum, so
    /// all of them are unbiased on a uniform density.
    #[arg(long, value_enum, default_value_t = EstimatorKind::Diffusion)]
    pub estimator: EstimatorKind,

    /// Photons per estimate for the k-NN estimates (the k-th sets the radius and is left out,
    /// so k ≥ 2). For the fixed-radius estimates it sets the default --radius. 400 is the
    /// paper's cone-filter setting, the baseline the diffusion estimate is compared with;
    /// the diffusion estimate's flat regions are quieter with ~1000 (see --diffusivity).
    #[arg(long, default_value_t = 400, allow_negative_numbers = true)]
    pub k: usize,

    /// Support radius of the fixed-radius estimates (epanechnikov, diffusion), in scene units.
    /// For the k-NN estimates it caps the search instead (default: no cap). Default for the
    /// fixed-radius estimates: the k-equivalent radius, the median over up to 256 photons
    /// spread through the map of the distance to their k-th nearest other photon, so a disc
    /// holds about k photons where photons typically are.
    #[arg(long, allow_negative_numbers = true)]
    pub radius: Option<f32>,

    /// Slope constant of the cone filter (≥ 1; the weight is 1 − d/(slope·r)). 1.1 is
    /// Jensen's suggestion; leaving the k-th photon out keeps every slope unbiased.
    #[arg(long, default_value_t = 1.1, allow_negative_numbers = true)]
    pub cone_slope: f64,

    /// Radius of the diffusion estimate's gradient pass (Eq. 6). Default: radius/2 — small
    /// enough that thin lines still show in the gradient (with radius itself they vanished in
    /// the design notes' experiment), large enough to keep the gradient's noise down.
    #[arg(long, allow_negative_numbers = true)]
    pub gradient_radius: Option<f32>,

    /// Radius over which the diffusion estimate averages the structure tensor. Default:
    /// radius, so one search serves both the tensor and the estimate.
    #[arg(long, allow_negative_numbers = true)]
    pub smoothing_radius: Option<f32>,

    /// Diffusivity coefficient K (Eq. 9): the edge contrast above which the kernel narrows
    /// across the edge (≥ 0; 0 narrows it wherever there is any gradient, inf keeps it round).
    /// In dimensionless units 0.2 means the irradiance changes by about √0.2 ≈ 45% of itself
    /// over one radius; 0.2 kept edges and thin lines best in the design notes' experiment.
    /// Noise alone reaches a contrast of about 64/N with N photons per disc (gradient radius
    /// r/2), so flat regions stay round, with noise within ~1.1× of the isotropic estimate,
    /// for N ≳ 1000; at N = 400 expect ~1.4×: raise --k or --radius, or K, if flat regions
    /// look noisy.
    #[arg(long, default_value_t = 0.2, allow_negative_numbers = true)]
    pub diffusivity: f64,

    /// Units of --diffusivity. `dimensionless` compares K with μ1·r²/L̂² (L̂: the isotropic
    /// estimate at the point), which does not change with light power or scene scale, so one
    /// K serves every scene; `absolute` compares it with μ1 in (W m⁻³)², as in the paper,
    /// where K must be retuned whenever the power or the scale changes.
    #[arg(long, value_enum, default_value_t = DiffusivityUnits::Dimensionless)]
    pub k_units: DiffusivityUnits,

    /// Steepness α > 0 of the diffusivity function λ2 = 1/(1 + (contrast/K)^(1+α)). 1 gives a
    /// gradual transition between flat regions and edges.
    #[arg(long, default_value_t = 1.0, allow_negative_numbers = true)]
    pub alpha: f64,

    /// Eigenvalue λ3 of the diffusion tensor along the surface normal, in (0, 1]: the kernel
    /// reaches r·√λ3 off the tangent plane. 0.1 is the paper's value (a disc rather than a
    /// sphere, to limit bias in corners).
    #[arg(long, default_value_t = 0.1, allow_negative_numbers = true)]
    pub lambda3: f64,

    /// Lower bound of λ2, in (0, 1]: the kernel is at least r·√floor wide across an edge.
    /// 0.01 (a tenth of the radius) sharpened edges most in the design notes' experiment;
    /// 0.05 lost a third of the gain there; without a bound the kernel degenerates to a
    /// segment.
    #[arg(long, default_value_t = 0.01, allow_negative_numbers = true)]
    pub lambda2_floor: f64,

    /// Photon noise removed from the structure tensor before the diffusivity: μ1 is reduced by
    /// this many times the gradient variance that photon noise alone would give (computed from
    /// the photons' Σ Φ² around the point). 0 is the paper's raw μ1, which reads noise as
    /// structure and squeezes the kernel wherever photons are sparse (wormy flat regions);
    /// 2 removes the noise's mean and its typical fluctuation after smoothing, and leaves edges,
    /// whose μ1 is far above it, untouched.
    #[arg(long, default_value_t = 2.0, allow_negative_numbers = true)]
    pub noise_floor: f64,

    /// Kernel of the diffusion estimate, evaluated at the Mahalanobis distance. Epanechnikov
    /// is the paper's choice and the cheapest; gaussian is Jensen's shape, exactly normalised.
    #[arg(long, value_enum, default_value_t = DiffusionKernel::Epanechnikov)]
    pub kernel: DiffusionKernel,
}

impl Default for EstimatorSettings {
    fn default() -> Self {
        Self {
            estimator: EstimatorKind::Diffusion,
            k: 400,
            radius: None,
            cone_slope: 1.1,
            gradient_radius: None,
            smoothing_radius: None,
            diffusivity: 0.2,
            k_units: DiffusivityUnits::Dimensionless,
            alpha: 1.0,
            lambda3: 0.1,
            lambda2_floor: 0.01,
            kernel: DiffusionKernel::Epanechnikov,
            noise_floor: 2.0,
        }
    }
}

/// An estimate with every default resolved, ready to box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ResolvedEstimator {
    Knn(KnnEstimate),
    FixedRadius(FixedRadiusEstimate),
    Diffusion(DiffusionEstimate),
}

impl ResolvedEstimator {
    pub fn into_boxed(self) -> Box<dyn RadianceEstimate> {
        match self {
            ResolvedEstimator::Knn(e) => Box::new(e),
            ResolvedEstimator::FixedRadius(e) => Box::new(e),
            ResolvedEstimator::Diffusion(e) => Box::new(e),
        }
    }
}

impl fmt::Display for ResolvedEstimator {
    /// One line with every resolved number, for logs.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ResolvedEstimator::Knn(e) => {
                write!(f, "{} k={}", e.name(), e.k())?;
                if let RadialKernel::Cone { slope } = e.kernel() {
                    write!(f, " cone-slope={slope}")?;
                }
                match e.max_radius() {
                    Some(r) => write!(f, " max-radius={r}"),
                    None => Ok(()),
                }
            }
            ResolvedEstimator::FixedRadius(e) => write!(f, "{} radius={}", e.name(), e.radius()),
            ResolvedEstimator::Diffusion(e) => {
                let p = e.params();
                write!(
                    f,
                    "diffusion radius={} gradient-radius={} smoothing-radius={} K={} ({:?}) \
                     alpha={} lambda3={} lambda2-floor={} noise-floor={} kernel={:?}",
                    p.radius,
                    p.gradient_radius,
                    p.smoothing_radius,
                    p.diffusivity,
                    p.units,
                    p.alpha,
                    p.lambda3,
                    p.lambda2_floor,
                    p.noise_floor,
                    p.kernel
                )
            }
        }
    }
}

fn invalid(flag: &'static str, value: impl fmt::Display, reason: &'static str) -> EstimateError {
    EstimateError::InvalidSetting {
        flag,
        value: value.to_string(),
        reason,
    }
}

/// Photons sampled to derive the k-equivalent radius.
const RADIUS_SAMPLES: usize = 256;

/// Median, over up to 256 photons evenly spread through the map's tree order, of the distance
/// to the k-th nearest other photon. `None` for an empty map or when every sampled distance
/// is zero.
pub fn k_equivalent_radius(map: &PhotonMap, k: usize) -> Option<f32> {
    let n = map.len();
    if n == 0 {
        return None;
    }
    let samples = n.min(RADIUS_SAMPLES);
    let mut found = Neighbours::with_capacity(k + 1);
    let mut distances: Vec<f32> = (0..samples)
        .filter_map(|i| {
            let slot = (i * n / samples) as u32;
            // k + 1: the photon itself is its own nearest neighbour.
            map.tree().k_nearest(
                map.photon(slot).position(),
                k + 1,
                f32::INFINITY,
                &mut found,
            );
            found
                .farthest()
                .map(|f| f.dist2.sqrt())
                .filter(|d| *d > 0.0 && d.is_finite())
        })
        .collect();
    if distances.is_empty() {
        return None;
    }
    distances.sort_by(f32::total_cmp);
    Some(distances[distances.len() / 2])
}

impl EstimatorSettings {
    /// Checks every flag, whether or not the chosen estimate uses it.
    pub fn validate(&self) -> Result<(), EstimateError> {
        let positive = |v: f32| v > 0.0 && v.is_finite();
        if self.k < 2 {
            return Err(invalid(
                "k",
                self.k,
                "must be at least 2 (the k-th photon is left out)",
            ));
        }
        for (flag, value) in [
            ("radius", self.radius),
            ("gradient-radius", self.gradient_radius),
            ("smoothing-radius", self.smoothing_radius),
        ] {
            if let Some(v) = value.filter(|v| !positive(*v)) {
                return Err(invalid(flag, v, "must be a positive finite length"));
            }
        }
        if !(self.cone_slope >= 1.0 && self.cone_slope.is_finite()) {
            return Err(invalid(
                "cone-slope",
                self.cone_slope,
                "must be finite and at least 1",
            ));
        }
        // The rest are the diffusion parameters; check them with a stand-in radius.
        let params = self.diffusion_params(1.0);
        if let Err((flag, reason)) = params.check() {
            let value = match flag {
                "diffusivity" => self.diffusivity.to_string(),
                "alpha" => self.alpha.to_string(),
                "lambda3" => self.lambda3.to_string(),
                "lambda2-floor" => self.lambda2_floor.to_string(),
                "noise-floor" => self.noise_floor.to_string(),
                _ => String::new(),
            };
            return Err(EstimateError::InvalidSetting {
                flag,
                value,
                reason,
            });
        }
        Ok(())
    }

    fn diffusion_params(&self, radius: f32) -> DiffusionParams {
        DiffusionParams {
            radius,
            gradient_radius: self.gradient_radius.unwrap_or(radius * 0.5),
            smoothing_radius: self.smoothing_radius.unwrap_or(radius),
            diffusivity: self.diffusivity,
            units: self.k_units,
            alpha: self.alpha,
            lambda3: self.lambda3,
            lambda2_floor: self.lambda2_floor,
            kernel: self.kernel,
            noise_floor: self.noise_floor,
        }
    }

    /// The fixed radius: --radius, else the k-equivalent radius; an empty map gathers nothing
    /// whatever the radius, so it gets 1.
    fn fixed_radius(&self, map: &PhotonMap) -> Result<f32, EstimateError> {
        if let Some(r) = self.radius {
            return Ok(r);
        }
        if map.is_empty() {
            return Ok(1.0);
        }
        k_equivalent_radius(map, self.k).ok_or(EstimateError::DegenerateMap)
    }

    /// Validates and resolves every default against `map`.
    pub fn resolve(&self, map: &PhotonMap) -> Result<ResolvedEstimator, EstimateError> {
        self.validate()?;
        let knn = |kernel| ResolvedEstimator::Knn(KnnEstimate::new(kernel, self.k, self.radius));
        Ok(match self.estimator {
            EstimatorKind::Simple => knn(RadialKernel::Constant),
            EstimatorKind::Cone => knn(RadialKernel::Cone {
                slope: self.cone_slope,
            }),
            EstimatorKind::Gaussian => knn(RadialKernel::Gaussian),
            EstimatorKind::Epanechnikov => ResolvedEstimator::FixedRadius(
                FixedRadiusEstimate::new(RadialKernel::Epanechnikov, self.fixed_radius(map)?),
            ),
            EstimatorKind::Diffusion => {
                let params = self.diffusion_params(self.fixed_radius(map)?);
                if let Err((flag, reason)) = params.check() {
                    // Only a derived radius can get here (e.g. radius/2 underflowing).
                    return Err(invalid(flag, params.radius, reason));
                }
                ResolvedEstimator::Diffusion(DiffusionEstimate::new(params))
            }
        })
    }

    /// Validates, resolves the defaults against `map` and builds the estimate.
    pub fn build(&self, map: &PhotonMap) -> Result<Box<dyn RadianceEstimate>, EstimateError> {
        self.resolve(map).map(ResolvedEstimator::into_boxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        settings: EstimatorSettings,
    }

    fn parse(args: &[&str]) -> EstimatorSettings {
        let mut all = vec!["dpm"];
        all.extend_from_slice(args);
        Cli::try_parse_from(all).expect("parses").settings
    }

    #[test]
    fn command_line_is_well_formed_and_every_flag_has_help() {
        use clap::CommandFactory;
        let mut cmd = Cli::command();
        cmd.clone().debug_assert();
        let help = cmd.render_long_help().to_string();
        for flag in [
            "--estimator",
            "--k",
            "--radius",
            "--cone-slope",
            "--gradient-radius",
            "--smoothing-radius",
            "--diffusivity",
            "--k-units",
            "--alpha",
            "--lambda3",
            "--lambda2-floor",
            "--kernel",
        ] {
            assert!(help.contains(flag), "{flag} missing from\n{help}");
        }
    }

    #[test]
    fn default_matches_the_command_line_defaults() {
        assert_eq!(parse(&[]), EstimatorSettings::default());
    }

    #[test]
    fn flags_parse() {
        let s = parse(&[
            "--estimator",
            "cone",
            "--k",
            "50",
            "--radius",
            "0.5",
            "--cone-slope",
            "2",
            "--k-units",
            "absolute",
            "--kernel",
            "gaussian",
            "--diffusivity",
            "inf",
        ]);
        assert_eq!(s.estimator, EstimatorKind::Cone);
        assert_eq!((s.k, s.radius, s.cone_slope), (50, Some(0.5), 2.0));
        assert_eq!(s.k_units, DiffusivityUnits::Absolute);
        assert_eq!(s.kernel, DiffusionKernel::Gaussian);
        assert_eq!(s.diffusivity, f64::INFINITY);
        assert!(s.validate().is_ok());
    }

    #[test]
    fn bad_values_name_their_flag() {
        let cases: &[(&[&str], &str)] = &[
            (&["--k", "0"], "k"),
            (&["--k", "1"], "k"),
            (&["--radius", "0"], "radius"),
            (&["--radius", "-1"], "radius"),
            (&["--radius", "NaN"], "radius"),
            (&["--radius", "inf"], "radius"),
            (&["--gradient-radius", "0"], "gradient-radius"),
            (&["--smoothing-radius", "-0.1"], "smoothing-radius"),
            (&["--cone-slope", "0.9"], "cone-slope"),
            (&["--diffusivity", "-0.2"], "diffusivity"),
            (&["--diffusivity", "NaN"], "diffusivity"),
            (&["--alpha", "0"], "alpha"),
            (&["--alpha", "-1"], "alpha"),
            (&["--lambda3", "0"], "lambda3"),
            (&["--lambda3", "1.5"], "lambda3"),
            (&["--lambda2-floor", "0"], "lambda2-floor"),
        ];
        for (args, flag) in cases {
            let err = parse(args).validate().expect_err("invalid");
            let EstimateError::InvalidSetting { flag: named, .. } = &err else {
                panic!("{err}")
            };
            assert_eq!(named, flag, "{args:?}");
            assert!(err.to_string().starts_with(&format!("--{flag} ")), "{err}");
        }
        assert!(parse(&["--diffusivity", "0"]).validate().is_ok());
    }
}
