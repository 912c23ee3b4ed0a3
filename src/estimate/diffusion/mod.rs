//! The diffusion based radiance estimate (Sections 3.1–3.4): a fixed-radius kernel whose shape
//! follows the local structure of the photon map, squeezed across edges and long along them.
//! Owns the per-query pipeline — gather, structure tensor, diffusion tensor, anisotropic kernel
//! — and the kernel-shape probe for debug images; the gradient pass is in [`gradient`], the
//! numerics in [`structure`] and [`tensor`]. Must not touch the classic estimates.
//!
//! Per query, one radius search (`max(r, ρ)`, into [`Scratch::neighbours`]) feeds both passes:
//! 1. the structure tensor, averaging the stored gradients of the photons within the
//!    smoothing radius `ρ` with weight `1 − d²/ρ²`, projected onto the query's tangent plane,
//!    and the isotropic Epanechnikov estimate `L̂` within `r` (for the dimensionless contrast);
//! 2. the estimate `Σ K(dᵀD⁻¹d / r²) Φ_i / (r² √(λ1 λ2))` over the photons within `r`.
//!
//! `λ2 = max(floor, 1/(1 + (c/K)^(1+α)))` where the contrast `c` is `μ1` (absolute units,
//! (W m⁻³)², as in the paper but without `f_r`) or `μ1 r² / L̂²` (dimensionless: the squared
//! relative change of irradiance over one kernel radius, unchanged by light power and scene
//! scale). The kernel's support is inside the disc of radius `r` because every `λ ≤ 1`, so
//! gathering within `r` loses nothing. For a uniform density the noise alone gives a
//! dimensionless contrast of about `64/N` with `r_g = r/2` (`N` photons in the disc), so `K`
//! must stay well above that for flat regions to keep a round kernel. At an edge the ellipse
//! holds only `√λ2` of the disc's photons, so the estimate there is noisier than the isotropic
//! one (standard deviation about 1.8× at the default floor with N = 1000) in exchange for
//! losing the blur (see `tests/estimate_diffusion.rs`).

pub mod gradient;
pub mod structure;
pub mod tensor;

pub use gradient::{compute_gradients, gradient_pass};

use super::classic::{PhotonReader, power_of};
use super::kernel::RadialKernel;
use super::{Query, RadianceEstimate, Scratch, to_irradiance};
use crate::photon::PhotonMap;
use glam::{DVec3, Vec3};
use structure::{StructureTensor, TangentFrame};
use tensor::{DiffusionTensor, diffusivity};

/// The units of the diffusivity coefficient `K`.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum DiffusivityUnits {
    /// `K` is compared with `μ1 r² / L̂²`: relative edge contrast over one kernel radius.
    Dimensionless,
    /// `K` is compared with `μ1` itself, (W m⁻³)²: depends on light power and scene scale.
    Absolute,
}

/// The kernel of the diffusion estimate.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum DiffusionKernel {
    Epanechnikov,
    Gaussian,
}

impl DiffusionKernel {
    pub fn radial(self) -> RadialKernel {
        match self {
            DiffusionKernel::Epanechnikov => RadialKernel::Epanechnikov,
            DiffusionKernel::Gaussian => RadialKernel::Gaussian,
        }
    }
}

/// Everything the diffusion estimate needs; see `EstimatorSettings` for the defaults.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusionParams {
    /// Support radius `r` of the estimate.
    pub radius: f32,
    /// Radius `r_g` of the gradient pass.
    pub gradient_radius: f32,
    /// Radius `ρ` over which the structure tensor is averaged.
    pub smoothing_radius: f32,
    /// Diffusivity coefficient `K` (≥ 0; `∞` keeps the kernel round).
    pub diffusivity: f64,
    pub units: DiffusivityUnits,
    /// Steepness `α > 0` of the diffusivity function.
    pub alpha: f64,
    /// Eigenvalue along the normal, `0 < λ3 ≤ 1`.
    pub lambda3: f64,
    /// Lower bound of `λ2`, `0 < floor ≤ 1`.
    pub lambda2_floor: f64,
    pub kernel: DiffusionKernel,
    /// Multiple `c ≥ 0` of the expected photon-noise variance of the gradient subtracted from
    /// `μ1` before the diffusivity (0: the paper's raw `μ1`). See [`gradient_noise`].
    pub noise_floor: f64,
    /// Fewest photons the kernel should hold (≥ 0): `λ2` is kept at least `(m/N)²` with `N`
    /// the photons in the disc, since the ellipse holds about `N √λ2` of them. A kernel
    /// squeezed onto a handful of photons is shaped by those photons' own noise, a bias that
    /// averaging passes does not remove; with this bound the estimate turns isotropic where a
    /// disc holds too few photons, as a progressive render's shrinking radii eventually make
    /// every disc. 0 turns it off.
    pub min_kernel_photons: f64,
}

impl DiffusionParams {
    /// The first invalid parameter, as (name, reason).
    pub fn check(&self) -> Result<(), (&'static str, &'static str)> {
        let positive = |v: f32| v > 0.0 && v.is_finite();
        if !positive(self.radius) {
            return Err(("radius", "must be a positive finite length"));
        }
        if !positive(self.gradient_radius) {
            return Err(("gradient-radius", "must be a positive finite length"));
        }
        if !positive(self.smoothing_radius) {
            return Err(("smoothing-radius", "must be a positive finite length"));
        }
        if self.diffusivity.is_nan() || self.diffusivity < 0.0 {
            return Err((
                "diffusivity",
                "must be zero or positive (inf keeps the kernel round)",
            ));
        }
        if !(self.alpha > 0.0 && self.alpha.is_finite()) {
            return Err(("alpha", "must be positive and finite"));
        }
        if !(self.lambda3 > 0.0 && self.lambda3 <= 1.0) {
            return Err(("lambda3", "must be in (0, 1]"));
        }
        if !(self.lambda2_floor > 0.0 && self.lambda2_floor <= 1.0) {
            return Err(("lambda2-floor", "must be in (0, 1]"));
        }
        if !(self.noise_floor >= 0.0 && self.noise_floor.is_finite()) {
            return Err(("noise-floor", "must be zero or positive and finite"));
        }
        if !(self.min_kernel_photons >= 0.0 && self.min_kernel_photons.is_finite()) {
            return Err(("min-kernel-photons", "must be zero or positive and finite"));
        }
        Ok(())
    }
}

/// The kernel's shape at a query, for debug images of the kernel field (the paper's Fig. 2b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelShape {
    /// `λ2` after the floor: 1 is round, small is squeezed across the edge.
    pub lambda2: f32,
    /// Edge direction `X1` (the long axis), a unit tangent vector.
    pub x1: Vec3,
    /// Across-edge direction `X2` (the structure tensor's major direction).
    pub x2: Vec3,
    /// Major eigenvalue of the structure tensor, absolute units (before the noise is removed).
    pub mu1: f64,
    /// Expected variance of one photon gradient per tangent axis from photon noise alone.
    pub noise: f64,
    /// Minor eigenvalue of the structure tensor, absolute units.
    pub mu2: f64,
    /// The value compared with `K` (`μ1` or `μ1 r²/L̂²`).
    pub contrast: f64,
    /// Isotropic Epanechnikov estimate at the query (channel mean), `L̂`.
    pub isotropic: f64,
}

/// The diffusion based radiance estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusionEstimate {
    params: DiffusionParams,
}

impl DiffusionEstimate {
    /// # Panics
    /// If a parameter is invalid (`EstimatorSettings` reports those as errors instead).
    pub fn new(params: DiffusionParams) -> Self {
        if let Err((name, why)) = params.check() {
            panic!("invalid diffusion parameter {name}: {why}");
        }
        Self { params }
    }

    pub fn params(&self) -> &DiffusionParams {
        &self.params
    }

    /// The radius the gradient pass runs with; pass it to [`gradient_pass`] to time the pass
    /// yourself before [`RadianceEstimate::prepare`], which then finds the gradients there.
    pub fn gradient_radius(&self) -> f32 {
        self.params.gradient_radius
    }

    /// The kernel shape at `query` (needs the gradient pass, like every query).
    pub fn kernel_at(&self, map: &PhotonMap, query: &Query, scratch: &mut Scratch) -> KernelShape {
        self.analyse(map, query, scratch).1
    }

    /// Gathers into `scratch.neighbours` and builds the diffusion tensor.
    fn analyse(
        &self,
        map: &PhotonMap,
        query: &Query,
        scratch: &mut Scratch,
    ) -> (DiffusionTensor, KernelShape) {
        let p = &self.params;
        let gradients = map.gradients_at(p.gradient_radius).expect(
            "diffusion estimate queried without gradients at its gradient radius (call prepare)",
        );
        let (r2, rho2) = (sq(p.radius), sq(p.smoothing_radius));
        let frame = TangentFrame::new(query.normal);
        let normal = frame.normal.as_vec3();
        map.tree()
            .within_radius(query.position, r2.max(rho2) as f32, &mut scratch.neighbours);

        let mut structure = StructureTensor::new(frame);
        let mut isotropic = 0.0;
        let mut second_moment = 0.0;
        let mut reader = PhotonReader::new(normal);
        let epanechnikov = RadialKernel::Epanechnikov.prepare().for_radius2(r2);
        let inv_rho2 = 1.0 / rho2;
        let inputs = &mut scratch.kernel_inputs;
        inputs.clear();
        for n in scratch.neighbours.as_slice() {
            let photon = map.attributes(n.slot);
            if !reader.agrees(photon) {
                continue;
            }
            let d2 = n.dist2 as f64;
            if d2 < rho2 {
                structure.add(gradients.get(n.slot), 1.0 - d2 * inv_rho2);
            }
            let power = power_of(photon);
            if d2 < r2 {
                inputs.push((map.position(n.slot) - query.position, power));
            }
            let w = epanechnikov.weight(d2);
            // Three times the channel mean (`gradient::scalar_power`); the thirds are taken
            // once after the loop rather than divided per photon.
            let phi3 = power.x + power.y + power.z;
            isotropic += w * phi3;
            second_moment += w * phi3 * phi3;
        }
        let isotropic = isotropic / (3.0 * r2);
        let noise = gradient_noise(second_moment / (9.0 * r2), p.gradient_radius as f64);
        let eigen = structure.average().eigen();
        let signal = (eigen.major - p.noise_floor * noise).max(0.0);
        let contrast = match p.units {
            DiffusivityUnits::Absolute => signal,
            DiffusivityUnits::Dimensionless => relative_contrast(signal, r2, isotropic),
        };
        let inside = inputs.len();
        let floor = if inside == 0 {
            1.0
        } else {
            let f = p.min_kernel_photons / inside as f64;
            (f * f).clamp(p.lambda2_floor, 1.0)
        };
        let lambda2 = diffusivity(contrast, p.diffusivity, p.alpha).max(floor);
        let across = frame.to_world(eigen.major_vector);
        let tensor = DiffusionTensor::new(across, frame.normal, lambda2, p.lambda3);
        let shape = KernelShape {
            lambda2: lambda2 as f32,
            x1: tensor.x1.as_vec3(),
            x2: tensor.x2.as_vec3(),
            mu1: eigen.major,
            noise,
            mu2: eigen.minor,
            contrast,
            isotropic,
        };
        (tensor, shape)
    }
}

/// Expected variance per tangent axis of the Eq. 6 gradient from photon noise alone, where the
/// photons' `Σ Φ²` per unit area is `second_moment`: the gradient is a sum of independent
/// terms `4/(π r_g⁴) (x_i − x) Φ_i`, so its variance is `(4/(π r_g⁴))² ∫ d_t² S dA` over the
/// disc, `4 S / (π r_g⁴)`. The smoothed structure tensor of a flat region is this times the
/// identity plus a fluctuation of similar size; the paper's `μ1` counts it as structure, which
/// squeezes the kernel wherever photons are sparse. It scales like `μ1` with light power and
/// scene size, so the dimensionless contrast stays invariant.
pub fn gradient_noise(second_moment: f64, gradient_radius: f64) -> f64 {
    let rg2 = gradient_radius * gradient_radius;
    4.0 * second_moment / (std::f64::consts::PI * rg2 * rg2)
}

/// `μ1 r² / L̂²`; no estimate at all with a nonzero gradient nearby is maximal contrast.
fn relative_contrast(mu1: f64, r2: f64, isotropic: f64) -> f64 {
    if mu1.is_nan() || mu1 <= 0.0 {
        0.0
    } else if isotropic > 0.0 {
        // Divide step by step: μ1 and L̂² may each overflow where their ratio does not.
        (mu1 / isotropic) * (r2 / isotropic)
    } else {
        f64::INFINITY
    }
}

fn sq(v: f32) -> f64 {
    v as f64 * v as f64
}

impl RadianceEstimate for DiffusionEstimate {
    fn name(&self) -> &'static str {
        "diffusion"
    }

    /// Runs the gradient pass unless the map already holds gradients taken at this estimate's
    /// gradient radius (from [`gradient_pass`] with [`DiffusionEstimate::gradient_radius`], run
    /// by a caller that times it separately). Gradients of any other radius are recomputed.
    fn prepare(&self, map: &mut PhotonMap) {
        if map.gradients_at(self.params.gradient_radius).is_none() {
            gradient_pass(map, self.params.gradient_radius);
        }
    }

    fn irradiance(&self, map: &PhotonMap, query: &Query, scratch: &mut Scratch) -> Vec3 {
        let (tensor, _) = self.analyse(map, query, scratch);
        let kernel = self.params.kernel.radial().prepare();
        let r2 = sq(self.params.radius);
        let metric = tensor.metric(r2);
        // The photons the analysis kept: within r, on the query's surface (its normal is X3).
        let mut sum = DVec3::ZERO;
        for (d, power) in &scratch.kernel_inputs {
            sum += kernel.weight(metric.distance(d.as_dvec3())) * *power;
        }
        to_irradiance(sum * (tensor.plane_normalisation() / r2))
    }
}
