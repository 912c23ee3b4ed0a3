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
pub mod sites;
pub mod structure;
pub mod tensor;

pub use gradient::{compute_gradients, gradient_pass};

use super::classic::{PhotonReader, power_of};
use super::kernel::RadialKernel;
use super::{NORMAL_AGREEMENT_MIN_COS, Query, RadianceEstimate, Scratch, to_irradiance};
use crate::photon::PhotonMap;
use crate::photon::map::GradientField;
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
    /// Gradient sites a smoothing disc keeps at least where the gradient pass thins them
    /// ([`sites`]); 0 gives every photon a gradient.
    pub gradient_sites: f64,
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
        runs.clear();
        inputs.clear();
        // Neighbouring one-surface leaves come in slot order and merge into runs, so each
        // run is one loop, not one per leaf of twenty photons.
        let mut mixed = Vec::new();
        tree.for_each_leaf_within(
            query.position,
            r2.max(rho2) as f32,
            |leaf, slots| match field.leaf_normal(leaf) {
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
            },
        );
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
        let floor = if inside <= 0.0 {
            1.0
        } else {
            let f = p.min_kernel_photons / inside;
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

/// The squared radii of one query's scans, and their inverses, in f32 for the leaf loops.
struct ScanRadii {
    r2: f32,
    rho2: f32,
    inv_r2: f32,
    inv_rho2: f32,
}

/// What the analysis sums over the photons on the query's surface: the structure tensor's
/// weighted world-space outer products (xx, xy, xz, yy, yz, zz) and their weight, and within
/// `r` the Epanechnikov sums of the channel sum and its square (without the kernel's
/// constant) and the count.
#[derive(Default)]
struct AnalysisSums {
    structure: [f64; 6],
    structure_weight: f64,
    isotropic: f64,
    second_moment: f64,
    /// Photons within `r`.
    inside: f64,
}

impl AnalysisSums {
    /// Adds a run of leaves whose photons all agree with the query's normal: its sites (every
    /// photon, but where sites are thinned: then each stands for its weight's worth) to the
    /// structure tensor, its photons to the isotropic sums, four lanes at a time over the
    /// field's arrays (f32 within a run, f64 across runs, all in the field's scaled units).
    #[inline]
    fn scan_run(
        &mut self,
        tree: &crate::photon::KdTree,
        field: &GradientField,
        q: Vec3,
        run: &LeafRun,
        radii: &ScanRadii,
    ) {
        let sites = field.leaf_site_range(run.leaves.start).start
            ..field.leaf_site_range(run.leaves.end - 1).end;
        self.scan_sites(field, q, sites, radii);
        // Leaves wholly inside the disc add their moments; the others are scanned, runs of
        // neighbouring ones together.
        let mut pending: Option<std::ops::Range<usize>> = None;
        let mut slot = run.slots.start;
        for leaf in run.leaves.clone() {
            let m = field.leaf_moments(leaf);
            let slots = slot..slot + m.count as usize;
            slot = slots.end;
            let far = (q - m.lower).abs().max((m.upper - q).abs());
            if far.length_squared() < radii.r2 * INSIDE_MARGIN {
                self.add_moments(m, q, radii);
                continue;
            }
            pending = match pending {
                Some(p) if p.end == slots.start => Some(p.start..slots.end),
                Some(p) => {
                    self.scan_isotropic(tree, field, q, p, radii);
                    Some(slots)
                }
                None => Some(slots),
            };
        }
        if let Some(p) = pending {
            self.scan_isotropic(tree, field, q, p, radii);
        }
    }

    /// Adds a leaf that lies wholly within `r` of `q` to the isotropic sums from its moments.
    #[inline]
    fn add_moments(&mut self, m: &crate::photon::map::LeafMoments, q: Vec3, radii: &ScanRadii) {
        // 1 − d²/r² with d² = |u|² + 2 u·e + |e|², e = c − q.
        let e = (m.centre - q).as_dvec3();
        let inv_r2 = 1.0 / radii.r2 as f64;
        let base = 1.0 - e.length_squared() * inv_r2;
        let sum =
            |(s0, s1, s2): (f64, glam::DVec3, f64)| s0 * base - (2.0 * e.dot(s1) + s2) * inv_r2;
        self.isotropic += sum(m.phi);
        self.second_moment += sum(m.phi2);
        self.inside += m.count as f64;
    }

    /// The isotropic sums over the photons of `slots` within `r`, four lanes at a time.
    #[inline]
    fn scan_isotropic(
        &mut self,
        tree: &crate::photon::KdTree,
        field: &GradientField,
        q: Vec3,
        slots: std::ops::Range<usize>,
        radii: &ScanRadii,
    ) {
        let (xs, ys, zs) = tree.coordinates();
        let phi = field.channel_sums();
        let Some(end) = lane_end(&slots, xs.len()) else {
            for s in slots {
                self.add_isotropic((tree.point(s) - q).length_squared(), phi[s], radii);
            }
            return;
        };
        let n = slots.len();
        let s = slots.start..end;
        let (xs, ys, zs) = (
            four(&xs[s.clone()]),
            four(&ys[s.clone()]),
            four(&zs[s.clone()]),
        );
        let phi = four(&phi[s]);
        let (mut iso, mut second, mut inside) = ([0.0f32; LANES], [0.0f32; LANES], [0u32; LANES]);
        for c in 0..xs.len() {
            let (x4, y4, z4, p4) = (xs[c], ys[c], zs[c], phi[c]);
            for lane in 0..LANES {
                let (dx, dy, dz) = (x4[lane] - q.x, y4[lane] - q.y, z4[lane] - q.z);
                let d2 = dx * dx + dy * dy + dz * dz;
                let within = (c * LANES + lane < n) & (d2 < radii.r2);
                let ep = masked(1.0 - d2 * radii.inv_r2, within) * p4[lane];
                iso[lane] += ep;
                second[lane] += ep * p4[lane];
                inside[lane] += u32::from(within);
            }
        }
        self.isotropic += total(iso);
        self.second_moment += total(second);
        self.inside += inside.iter().sum::<u32>() as f64;
    }

    /// Adds the sites `sites` (indices into the field's site arrays) within `ρ` to the
    /// structure tensor, four lanes at a time.
    #[inline]
    fn scan_sites(
        &mut self,
        field: &GradientField,
        q: Vec3,
        sites: std::ops::Range<usize>,
        radii: &ScanRadii,
    ) {
        let columns = field.site_columns();
        let [xs, ys, zs] = columns.position;
        let Some(end) = lane_end(&sites, xs.len()) else {
            for i in sites {
                self.add_site(field, i, q, radii);
            }
            return;
        };
        let n = sites.len();
        let s = sites.start..end;
        let [gx, gy, gz] = columns.gradient;
        let (xs, ys, zs) = (
            four(&xs[s.clone()]),
            four(&ys[s.clone()]),
            four(&zs[s.clone()]),
        );
        let (gx, gy, gz) = (
            four(&gx[s.clone()]),
            four(&gy[s.clone()]),
            four(&gz[s.clone()]),
        );
        let gw = four(&columns.weight[s]);
        let mut t = [[0.0f32; LANES]; 6];
        let mut tw = [0.0f32; LANES];
        for c in 0..xs.len() {
            let (x4, y4, z4) = (xs[c], ys[c], zs[c]);
            let (gx4, gy4, gz4, gw4) = (gx[c], gy[c], gz[c], gw[c]);
            for lane in 0..LANES {
                let (dx, dy, dz) = (x4[lane] - q.x, y4[lane] - q.y, z4[lane] - q.z);
                let d2 = dx * dx + dy * dy + dz * dz;
                let keep = (c * LANES + lane < n) & (d2 < radii.rho2);
                let w = masked((1.0 - d2 * radii.inv_rho2) * gw4[lane], keep);
                let (x, y, z) = (gx4[lane], gy4[lane], gz4[lane]);
                let (wx, wy) = (w * x, w * y);
                t[0][lane] += wx * x;
                t[1][lane] += wx * y;
                t[2][lane] += wx * z;
                t[3][lane] += wy * y;
                t[4][lane] += wy * z;
                t[5][lane] += w * z * z;
                tw[lane] += w;
            }
        }
        for (acc, v) in self.structure.iter_mut().zip(t) {
            *acc += total(v);
        }
        self.structure_weight += total(tw);
    }

    /// Adds site `i` to the structure tensor if it is within `ρ` of `q`.
    #[inline]
    fn add_site(&mut self, field: &GradientField, i: usize, q: Vec3, radii: &ScanRadii) {
        let c = field.site_columns();
        let [xs, ys, zs] = c.position;
        let [gx, gy, gz] = c.gradient;
        let d2 = (Vec3::new(xs[i], ys[i], zs[i]) - q).length_squared();
        if d2 < radii.rho2 {
            let w = ((1.0 - d2 * radii.inv_rho2) * c.weight[i]) as f64;
            let g = DVec3::new(gx[i] as f64, gy[i] as f64, gz[i] as f64);
            let o = [
                g.x * g.x,
                g.x * g.y,
                g.x * g.z,
                g.y * g.y,
                g.y * g.z,
                g.z * g.z,
            ];
            for (acc, v) in self.structure.iter_mut().zip(o) {
                *acc += w * v;
            }
            self.structure_weight += w;
        }
    }

    /// Adds one photon at squared distance `d2` with channel sum `phi` (scaled) to the
    /// isotropic sums; returns whether it is within `r`.
    #[inline]
    fn add_isotropic(&mut self, d2: f32, phi: f32, radii: &ScanRadii) -> bool {
        if d2 < radii.r2 {
            let e = (1.0 - d2 * radii.inv_r2) as f64;
            let phi = phi as f64;
            self.isotropic += e * phi;
            self.second_moment += e * phi * phi;
            self.inside += 1.0;
            return true;
        }
        false
    }

    /// Adds a leaf that holds several surfaces, testing each photon's normal, and copies the
    /// agreeing photons within `r` to the kernel's inputs.
    fn scan_mixed(
        &mut self,
        map: &PhotonMap,
        field: &GradientField,
        query: &Query,
        (leaf, slots): (usize, std::ops::Range<usize>),
        radii: &ScanRadii,
        inputs: &mut Vec<(Vec3, DVec3)>,
    ) {
        let mut reader = PhotonReader::new(query.normal);
        for i in field.leaf_site_range(leaf) {
            if reader.agrees(map.attributes(field.site_slot(i))) {
                self.add_site(field, i, query.position, radii);
            }
        }
        for slot in slots {
            let slot = slot as u32;
            let photon = map.attributes(slot);
            if !reader.agrees(photon) {
                continue;
            }
            let d = map.position(slot) - query.position;
            if self.add_isotropic(
                d.length_squared(),
                field.channel_sums()[slot as usize],
                radii,
            ) {
                inputs.push((d, power_of(photon)));
            }
        }
    }
}

/// Consecutive leaves, one surface each, that agree with a query's normal: the leaves and
/// their slots.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LeafRun {
    pub leaves: std::ops::Range<usize>,
    pub slots: std::ops::Range<usize>,
}

/// The sum of a lane accumulator's lanes, in f64.
#[inline(always)]
fn total(a: [f32; LANES]) -> f64 {
    ((a[0] + a[1]) + (a[2] + a[3])) as f64
}

/// A leaf is wholly inside a disc when its box's far corner is inside by this relative margin
/// (so that no photon rounds to the rim's other side).
const INSIDE_MARGIN: f32 = 1.0 - 1e-5;

/// Lanes of the leaf scans: four f32, one SSE register.
const LANES: usize = 4;

/// A run rounded to whole lane groups (see [`lane_end`]) as groups.
#[inline(always)]
fn four(a: &[f32]) -> &[[f32; LANES]] {
    a.as_chunks::<LANES>().0
}

/// The end of a run rounded up to whole groups of [`LANES`] (the last group runs on into the
/// next leaf's photons, which a lane mask leaves out), or `None` where that would run off
/// arrays of length `len`.
#[inline]
fn lane_end(slots: &std::ops::Range<usize>, len: usize) -> Option<usize> {
    let end = slots.start + slots.len().div_ceil(LANES) * LANES;
    (end <= len).then_some(end)
}

/// `v` where `keep`, else 0, by bits: a select the compiler would make a branch.
#[inline(always)]
fn masked(v: f32, keep: bool) -> f32 {
    f32::from_bits(v.to_bits() & u32::from(keep).wrapping_neg())
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
        let kernel = self.params.kernel.radial().prepare();
        let r2 = sq(self.params.radius);
        let metric = tensor.metric(r2);
        let field = self.field(map).expect("analysed above");
        // The photons the analysis kept: within r, on the query's surface (its normal is X3).
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
        for (d, power) in &scratch.kernel_inputs {
            sum += kernel.weight(metric.distance(d.as_dvec3())) * *power;
        }
        to_irradiance(sum * (tensor.plane_normalisation() / r2))
    }
}

/// The Epanechnikov kernel `1 − dᵀD⁻¹d/r²` over runs of slots, in f32 lanes: the metric's
/// three scaled axes, relative to the query.
struct EllipseScan {
    a: [Vec3; 3],
    q: Vec3,
}

impl EllipseScan {
    fn new(metric: &tensor::ScaledMetric, q: Vec3) -> Self {
        Self {
            a: metric.axes().map(|a| a.as_vec3()),
            q,
        }
    }

    /// `Σ (1 − y) Φ` over a run of leaves, skipping the leaves whose box lies outside the
    /// ellipsoid's bounding slab on some axis (most of them where the kernel is squeezed),
    /// scanning the others, runs of neighbouring ones together.
    fn run(&self, tree: &crate::photon::KdTree, field: &GradientField, run: &LeafRun) -> DVec3 {
        let mut sum = DVec3::ZERO;
        let mut pending: Option<std::ops::Range<usize>> = None;
        let mut slot = run.slots.start;
        for leaf in run.leaves.clone() {
            let m = field.leaf_moments(leaf);
            let slots = slot..slot + m.count as usize;
            slot = slots.end;
            if self.misses(m.lower, m.upper) {
                continue;
            }
            pending = match pending {
                Some(p) if p.end == slots.start => Some(p.start..slots.end),
                Some(p) => {
                    sum += self.sum(tree, field, p);
                    Some(slots)
                }
                None => Some(slots),
            };
        }
        if let Some(p) = pending {
            sum += self.sum(tree, field, p);
        }
        sum
    }

    /// Whether the box misses the ellipsoid: on some axis `a_i` the box's projection lies
    /// wholly outside [−1, 1] (with a margin on the safe side, so no photon inside is lost).
    #[inline]
    fn misses(&self, lower: Vec3, upper: Vec3) -> bool {
        let centre = (lower + upper) * 0.5 - self.q;
        let half = (upper - lower) * 0.5;
        self.a
            .iter()
            .any(|a| centre.dot(*a).abs() - half.dot(a.abs()) > 1.0 + 1e-4)
    }

    /// `Σ (1 − y) Φ` over the run's photons with `y = dᵀD⁻¹d/r² < 1`, four lanes at a time.
    #[inline]
    fn sum(
        &self,
        tree: &crate::photon::KdTree,
        field: &GradientField,
        slots: std::ops::Range<usize>,
    ) -> DVec3 {
        let (xs, ys, zs) = tree.coordinates();
        let [pr, pg, pb] = field.power_columns();
        let Some(end) = lane_end(&slots, xs.len()) else {
            let mut sum = DVec3::ZERO;
            for slot in slots {
                let y = self.distance(tree.point(slot) - self.q);
                let k = if y < 1.0 { 1.0 - y } else { 0.0 };
                sum += (k * field.power(slot as u32)).as_dvec3();
            }
            return sum;
        };
        let n = slots.len();
        let s = slots.start..end;
        let (xs, ys, zs) = (&xs[s.clone()], &ys[s.clone()], &zs[s.clone()]);
        let (pr, pg, pb) = (&pr[s.clone()], &pg[s.clone()], &pb[s.clone()]);
        let [a1, a2, a3] = self.a;
        let q = self.q;
        let (mut r, mut g, mut b) = ([0.0f32; LANES], [0.0f32; LANES], [0.0f32; LANES]);
        let (xs, ys, zs) = (four(xs), four(ys), four(zs));
        let (pr, pg, pb) = (four(pr), four(pg), four(pb));
        for c in 0..xs.len() {
            let (x4, y4, z4) = (xs[c], ys[c], zs[c]);
            let (pr4, pg4, pb4) = (pr[c], pg[c], pb[c]);
            for lane in 0..LANES {
                let (dx, dy, dz) = (x4[lane] - q.x, y4[lane] - q.y, z4[lane] - q.z);
                let u = dx * a1.x + dy * a1.y + dz * a1.z;
                let v = dx * a2.x + dy * a2.y + dz * a2.z;
                let w = dx * a3.x + dy * a3.y + dz * a3.z;
                let y = u * u + v * v + w * w;
                let k = masked(1.0 - y, (c * LANES + lane < n) & (y < 1.0));
                r[lane] += k * pr4[lane];
                g[lane] += k * pg4[lane];
                b[lane] += k * pb4[lane];
            }
        }
        DVec3::new(total(r), total(g), total(b))
    }

    #[inline]
    fn distance(&self, d: Vec3) -> f32 {
        let [a1, a2, a3] = self.a;
        let (u, v, w) = (d.dot(a1), d.dot(a2), d.dot(a3));
        u * u + v * v + w * w
    }
}
