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

pub mod edge;
pub mod field_colour;
pub mod gradient;
mod scan;
pub mod shaped;
pub mod sites;
pub mod structure;
pub mod tensor;

pub use gradient::{compute_gradients, gradient_pass};
pub use scan::LeafRun;

use super::classic::power_of;
use super::kernel::RadialKernel;
use super::{
    NORMAL_AGREEMENT_MIN_COS, Query, RadianceEstimate, Receiver, Scratch, to_irradiance,
    weighed_power,
};
use crate::photon::PhotonMap;
use crate::photon::map::GradientField;
use glam::{DVec3, Vec3};
use scan::{AnalysisSums, EllipseScan, ScanRadii};
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

/// What the kernel does where the structure tensor sees more than one direction (crossing
/// or folded filaments: both eigenvalues large).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Crossings {
    /// λ1 follows the minor eigenvalue as λ2 the major one: at a crossing the kernel shrinks
    /// along both axes (down to the fewest photons it should hold) instead of staying long.
    Shrink,
    /// The paper's λ1 = 1: the kernel keeps its length along X1 whatever the minor eigenvalue.
    Keep,
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
    /// Gradient sites a smoothing disc keeps at least where the gradient pass thins them
    /// ([`sites`]); 0 gives every photon a gradient.
    pub gradient_sites: f64,
    /// What the kernel does at crossings.
    pub crossings: Crossings,
    /// Whether a kernel shaped on another map cuts itself at the edge that map's photons show
    /// ([`edge`]); needs the Epanechnikov kernel.
    pub edge_cut: bool,
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
        if self.edge_cut && self.kernel != DiffusionKernel::Epanechnikov {
            return Err(("edge-cut", "needs --kernel epanechnikov"));
        }
        if !(self.gradient_sites == 0.0 || (1.0..=1e9).contains(&self.gradient_sites)) {
            return Err((
                "gradient-sites",
                "must be 0 (every photon) or from 1 to 1e9",
            ));
        }
        Ok(())
    }
}

/// The kernel's shape at a query, for debug images of the kernel field (the paper's Fig. 2b).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelShape {
    /// `λ1` after the floors: 1 keeps the kernel long along the edge, small shrinks it there
    /// too (a crossing, with [`Crossings::Shrink`]).
    pub lambda1: f32,
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

    /// Scans the leaves within `max(r, ρ)` and builds the diffusion tensor; leaves the
    /// kernel's inputs in `scratch` (runs of one-surface leaves, and the agreeing photons of
    /// leaves that hold several surfaces one by one).
    fn analyse(
        &self,
        map: &PhotonMap,
        query: &Query,
        scratch: &mut Scratch,
    ) -> (DiffusionTensor, KernelShape) {
        let p = &self.params;
        let field = self
            .field(map)
            .expect("diffusion estimate queried without gradients at its radii (call prepare)");
        let (r2, rho2) = (sq(p.radius), sq(p.smoothing_radius));
        let frame = TangentFrame::new(query.normal);
        let normal = frame.normal.as_vec3();
        let mut sums = AnalysisSums::default();
        let radii = ScanRadii {
            r2: r2 as f32,
            rho2: rho2 as f32,
            inv_r2: (1.0 / r2) as f32,
            inv_rho2: (1.0 / rho2) as f32,
        };
        let tree = map.tree();
        let (runs, inputs) = (&mut scratch.kernel_runs, &mut scratch.kernel_inputs);
        inputs.clear();
        let reach2 = r2.max(rho2) as f32;
        let mixed = surface_leaves(map, field, (query.position, normal), reach2, runs);
        for run in runs.iter() {
            sums.scan_run(tree, field, query.position, run, &radii);
        }
        for leaf in mixed {
            sums.scan_mixed(map, field, query, leaf, &radii, inputs);
        }
        // Back from the field's scaled units.
        let (gs, ps) = (field.gradient_scale(), field.power_scale());
        let mut structure = StructureTensor::new(frame);
        structure.add_world_sum(sums.structure.map(|v| v * gs * gs), sums.structure_weight);
        let (iso_sum, second_sum) = (sums.isotropic * ps, sums.second_moment * ps * ps);
        // Three times the channel mean (`gradient::scalar_power`) was summed; the thirds and
        // the Epanechnikov constant 2/π are taken here once.
        let epanechnikov = 2.0 / std::f64::consts::PI;
        let isotropic = epanechnikov * iso_sum / (3.0 * r2);
        let noise = gradient_noise(
            epanechnikov * second_sum / (9.0 * r2),
            p.gradient_radius as f64,
        );
        let eigen = structure.average().eigen();
        let signal = (eigen.major - p.noise_floor * noise).max(0.0);
        let contrast = match p.units {
            DiffusivityUnits::Absolute => signal,
            DiffusivityUnits::Dimensionless => relative_contrast(signal, r2, isotropic),
        };
        let inside = sums.inside;
        // The kernel holds about inside·√(λ1 λ2) photons: at least the fewest it should.
        let fewest = if inside <= 0.0 {
            1.0
        } else {
            let f = p.min_kernel_photons / inside;
            (f * f).min(1.0)
        };
        let lambda2 =
            diffusivity(contrast, p.diffusivity, p.alpha).max(fewest.max(p.lambda2_floor));
        let lambda1 = match p.crossings {
            Crossings::Keep => 1.0,
            Crossings::Shrink => {
                let minor = (eigen.minor - p.noise_floor * noise).max(0.0);
                let contrast = match p.units {
                    DiffusivityUnits::Absolute => minor,
                    DiffusivityUnits::Dimensionless => relative_contrast(minor, r2, isotropic),
                };
                let along = diffusivity(contrast, p.diffusivity, p.alpha);
                along.max(p.lambda2_floor).max(fewest / lambda2).min(1.0)
            }
        };
        let across = frame.to_world(eigen.major_vector);
        let tensor =
            DiffusionTensor::new(across, frame.normal, lambda2, p.lambda3).with_lambda1(lambda1);
        let shape = KernelShape {
            lambda1: lambda1 as f32,
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

    /// The kernel `tensor` shapes at the query, summed over the photons `scratch` holds of
    /// `map` (runs of its leaves on the query's surface, and single photons within `r`):
    /// irradiance.
    fn kernel_sum(
        &self,
        map: &PhotonMap,
        field: &GradientField,
        tensor: &DiffusionTensor,
        query: &Query,
        scratch: &Scratch,
    ) -> Vec3 {
        let kernel = self.params.kernel.radial().prepare();
        let r2 = sq(self.params.radius);
        let metric = tensor.metric(r2);
        let mut sum = match self.params.kernel {
            DiffusionKernel::Epanechnikov => {
                let scan = EllipseScan::new(&metric, query.position);
                let mut s = DVec3::ZERO;
                for run in &scratch.kernel_runs {
                    s += scan.run(map.tree(), field, run);
                }
                s * (2.0 / std::f64::consts::PI)
            }
            DiffusionKernel::Gaussian => {
                let mut s = DVec3::ZERO;
                for run in &scratch.kernel_runs {
                    for slot in run.slots.clone() {
                        let slot = slot as u32;
                        let d = map.position(slot) - query.position;
                        let power = power_of(map.attributes(slot));
                        s += kernel.weight(metric.distance(d.as_dvec3())) * power;
                    }
                }
                s
            }
        };
        for (d, power, _) in &scratch.kernel_inputs {
            sum += kernel.weight(metric.distance(d.as_dvec3())) * *power;
        }
        to_irradiance(sum * (tensor.plane_normalisation() / r2))
    }

    /// The gradient pass this estimate reads: gradients at its gradient radius, on sites
    /// thinned for its smoothing radius (see [`sites`]). [`RadianceEstimate::prepare`] runs
    /// it when the map holds no such field; call it yourself to time it as its own phase.
    pub fn gradient_pass(&self, map: &mut PhotonMap) {
        let p = &self.params;
        gradient_pass(map, p.gradient_radius, self.thinning());
    }

    /// How the gradient pass thins sites: (smoothing radius, sites per disc), or `None`.
    fn thinning(&self) -> Option<(f32, f64)> {
        let p = &self.params;
        (p.gradient_sites > 0.0).then_some((p.smoothing_radius, p.gradient_sites))
    }

    /// The map's gradient field if it was made for this estimate's radii and thinning.
    fn field<'m>(&self, map: &'m PhotonMap) -> Option<&'m GradientField> {
        map.gradients_at(self.params.gradient_radius, self.thinning())
    }
}

/// The leaves of `map` within `reach2` of the query that lie on its surface: neighbouring
/// one-surface leaves merged into runs in `runs` (cleared first: they come in slot order, so
/// each run is one loop, not one per leaf of twenty photons), and the leaves that hold several
/// surfaces returned, to be read photon by photon.
fn surface_leaves(
    map: &PhotonMap,
    field: &GradientField,
    (position, normal): (Vec3, Vec3),
    reach2: f32,
    runs: &mut Vec<LeafRun>,
) -> Vec<(usize, std::ops::Range<usize>)> {
    runs.clear();
    let mut mixed = Vec::new();
    map.tree()
        .for_each_leaf_within(position, reach2, |leaf, slots| {
            match field.leaf_normal(leaf) {
                Some(n) if n.dot(normal) < NORMAL_AGREEMENT_MIN_COS => {}
                Some(_) => match runs.last_mut() {
                    Some(run) if run.slots.end == slots.start => {
                        run.slots.end = slots.end;
                        run.leaves.end = leaf + 1;
                    }
                    _ => runs.push(LeafRun {
                        leaves: leaf..leaf + 1,
                        slots,
                    }),
                },
                None => mixed.push((leaf, slots)),
            }
        });
    mixed
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
        if self.field(map).is_none() {
            self.gradient_pass(map);
        }
    }

    fn irradiance(&self, map: &PhotonMap, query: &Query, scratch: &mut Scratch) -> Vec3 {
        let (tensor, _) = self.analyse(map, query, scratch);
        let field = self.field(map).expect("analysed above");
        self.kernel_sum(map, field, &tensor, query, scratch)
    }

    /// The same kernel over the same photons as [`DiffusionEstimate::irradiance`], photon by
    /// photon (a glossy receiver is rare enough not to need the leaf moments and lanes).
    fn reflected(
        &self,
        map: &PhotonMap,
        query: &Query,
        receiver: &dyn Receiver,
        scratch: &mut Scratch,
    ) -> Vec3 {
        let (tensor, _) = self.analyse(map, query, scratch);
        let kernel = self.params.kernel.radial().prepare();
        let r2 = sq(self.params.radius);
        let metric = tensor.metric(r2);
        let mut sum = DVec3::ZERO;
        let mut add = |d: Vec3, slot: u32| {
            let k = kernel.weight(metric.distance(d.as_dvec3()));
            if k > 0.0 {
                sum += k * weighed_power(map.attributes(slot), receiver);
            }
        };
        for run in &scratch.kernel_runs {
            for slot in run.slots.clone() {
                let slot = slot as u32;
                add(map.position(slot) - query.position, slot);
            }
        }
        for &(d, _, slot) in &scratch.kernel_inputs {
            add(d, slot);
        }
        to_irradiance(sum * (tensor.plane_normalisation() / r2))
    }
}
