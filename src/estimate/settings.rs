//! Estimator settings as plain, serialisable values (the command-line layer is
//! [`super::flags`]), their validation, the defaults derived from the photon map, and the
//! construction of the chosen estimate. Must not parse anything or run queries beyond the few
//! that derive a default radius.

use super::RadianceEstimate;
use super::classic::{FixedRadiusEstimate, KnnEstimate};
use super::diffusion::shaped::HistoryPhotons;
use super::diffusion::{
    Crossings, DiffusionEstimate, DiffusionKernel, DiffusionParams, DiffusivityUnits,
};
use super::kernel::RadialKernel;
use crate::photon::{Neighbours, PhotonMap};
use std::fmt;

/// Which radiance estimate to use.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
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

impl EstimatorKind {
    /// Whether the estimate has a fixed radius (`k` then only sets its default).
    pub fn is_fixed_radius(self) -> bool {
        matches!(self, EstimatorKind::Epanechnikov | EstimatorKind::Diffusion)
    }
}

/// Earlier passes whose photons shape a pass's diffusion kernels by default. A kernel shaped
/// by the photons it sums loses energy, and more as the radii shrink: caustic-glass's image mean
/// fell to 0.9966 of pbrt's after 100 s with none, and stays at 0.9993 with one pass's worth
/// of the four passes before (`--history-photons one-pass`, which costs about what a pass's own
/// shapes do; BENCHMARKS.md, "A structure tensor across passes").
pub const DEFAULT_TENSOR_HISTORY: u32 = 4;

/// `k` of the paper's baseline, the cone filter with 400 photons an estimate.
pub const PAPER_K: usize = 400;

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

/// Radiance-estimate settings, plain values: what a film records and a merge compares. The
/// command-line layer with every flag's help is [`super::flags::EstimatorFlags`].
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub struct EstimatorSettings {
    /// Which estimate.
    pub estimator: EstimatorKind,
    /// Photons per k-NN estimate; sets the default radius of the fixed-radius ones.
    pub k: usize,
    /// Fixed radius, or the k-NN search cap.
    pub radius: Option<f32>,
    /// Slope constant of the cone filter.
    pub cone_slope: f64,
    /// Radius of the gradient pass (default radius/2).
    pub gradient_radius: Option<f32>,
    /// Radius of the structure tensor's average (default radius).
    pub smoothing_radius: Option<f32>,
    /// Diffusivity coefficient K.
    pub diffusivity: f64,
    /// Units of K.
    pub k_units: DiffusivityUnits,
    /// Steepness of the diffusivity function.
    pub alpha: f64,
    /// Eigenvalue along the normal.
    pub lambda3: f64,
    /// Lower bound of λ2.
    pub lambda2_floor: f64,
    /// Photon noise removed from μ1, in multiples of its variance.
    pub noise_floor: f64,
    /// Fewest photons the anisotropic kernel should hold.
    pub min_kernel_photons: f64,
    /// Gradient sites a smoothing disc keeps at least where they are thinned (0: all).
    #[serde(default = "default_gradient_sites")]
    pub gradient_sites: f64,
    /// Kernel of the diffusion estimate.
    pub kernel: DiffusionKernel,
    /// What the diffusion kernel does at crossings. Films written before it existed kept it
    /// long.
    #[serde(default = "keep_at_crossings")]
    pub crossings: Crossings,
    /// Earlier passes whose photons shape the diffusion kernels of a progressive pass (0: its
    /// own). Films written before it existed used their own.
    #[serde(default)]
    pub tensor_history: u32,
    /// Which of the history's photons shape the kernels. Films written before it existed
    /// used all.
    #[serde(default = "all_history_photons")]
    pub history_photons: HistoryPhotons,
    /// Whether kernels shaped on the tensor history cut themselves at the edge its photons
    /// show. Films written before it existed did not.
    #[serde(default)]
    pub edge_cut: bool,
}

fn all_history_photons() -> HistoryPhotons {
    HistoryPhotons::All
}

fn keep_at_crossings() -> Crossings {
    Crossings::Keep
}

impl Default for EstimatorSettings {
    fn default() -> Self {
        Self {
            estimator: EstimatorKind::Diffusion,
            k: PAPER_K,
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
            min_kernel_photons: 8.0,
            gradient_sites: default_gradient_sites(),
            crossings: Crossings::Shrink,
            tensor_history: DEFAULT_TENSOR_HISTORY,
            history_photons: HistoryPhotons::OnePass,
            edge_cut: false,
        }
    }
}

fn default_gradient_sites() -> f64 {
    super::diffusion::sites::SITES_PER_SMOOTHING_DISC
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
                     alpha={} lambda3={} lambda2-floor={} noise-floor={} min-kernel-photons={} \
                     gradient-sites={} kernel={:?} crossings={:?} edge-cut={}",
                    p.radius,
                    p.gradient_radius,
                    p.smoothing_radius,
                    p.diffusivity,
                    p.units,
                    p.alpha,
                    p.lambda3,
                    p.lambda2_floor,
                    p.noise_floor,
                    p.min_kernel_photons,
                    p.gradient_sites,
                    p.kernel,
                    p.crossings,
                    p.edge_cut
                )
            }
        }
    }
}

/// A setting's value as the command line spells it.
fn cli_name(value: &impl clap::ValueEnum) -> String {
    (value.to_possible_value()).map_or_else(String::new, |v| v.get_name().to_string())
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
        if self.edge_cut && self.estimator != EstimatorKind::Diffusion {
            return Err(invalid(
                "edge-cut",
                format!("with --estimator {}", cli_name(&self.estimator)),
                "only the diffusion estimate cuts its kernel",
            ));
        }
        if self.edge_cut && self.tensor_history == 0 {
            return Err(invalid(
                "edge-cut",
                "with --tensor-history 0",
                "the edge is located on earlier passes' photons, never on those the estimate \
                 sums: give --tensor-history 1 or more",
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
                "min-kernel-photons" => self.min_kernel_photons.to_string(),
                "gradient-sites" => self.gradient_sites.to_string(),
                "edge-cut" => format!("with --kernel {}", cli_name(&self.kernel)),
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
            min_kernel_photons: self.min_kernel_photons,
            gradient_sites: self.gradient_sites,
            crossings: self.crossings,
            edge_cut: self.edge_cut,
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
