//! Radiance estimates: one interface ([`RadianceEstimate`]), its implementations side by side.
//! An estimate turns the photons near a surface point into photon power per unit area
//! (irradiance, W/m² per channel), which a Lambert receiver scales by its albedo/π, or into
//! reflected radiance at a receiver that weighs each photon by its BSDF for the photon's
//! direction ([`Receiver`]: a glossy surface). Owns kernels and their normalisation; must not
//! trace rays or know about Embree, cameras, BSDF lobes or images.
//!
//! - [`kernel`]: the radial kernels, each normalised over the unit disc.
//! - [`classic`]: k-nearest-neighbour estimates (simple, cone, Gaussian) and the fixed-radius
//!   Epanechnikov estimate.
//! - [`diffusion`]: the diffusion based estimate (gradient pass, structure and diffusion tensors).
//! - [`precomputed`]: irradiance precomputed at a subset of a global map's photons, read by
//!   final-gather rays instead of a k-NN estimate each.
//! - [`settings`]: the command-line settings shared by `dpm render` and `dpm density`, their
//!   validation and the construction of an estimate from them.
//!
//! Normal agreement, shared by every estimate: a photon is gathered only when its stored
//! surface normal `n_i` satisfies `n_i · n ≥` [`NORMAL_AGREEMENT_MIN_COS`] (cos 60°) with the
//! query normal `n`. That rejects the far side of a thin wall (`n_i · n ≈ −1`) and a
//! perpendicular wall at a corner (`≈ 0`), and accepts a curved surface whose normal turns by
//! less than 60° within one radius. The stored normal is quantised to about 1°, far inside
//! that margin. How rejection interacts with k is documented in [`classic`].

pub mod beam;
pub mod classic;
pub mod diffusion;
pub mod flags;
pub mod kernel;
pub mod precomputed;
pub mod settings;

pub use classic::{FixedRadiusEstimate, KnnEstimate};
pub use diffusion::{
    Crossings, DiffusionEstimate, DiffusionKernel, DiffusionParams, DiffusivityUnits, KernelShape,
};
pub use flags::EstimatorFlags;
pub use kernel::RadialKernel;
pub use precomputed::PrecomputedIrradiance;
pub use settings::{EstimateError, EstimatorKind, EstimatorSettings, ResolvedEstimator};

use crate::photon::{Neighbours, Photon, PhotonAttributes, PhotonMap};
use glam::Vec3;

/// Where an estimate is asked for: a surface point and its unit normal (on the side light
/// arrives from).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Query {
    pub position: Vec3,
    pub normal: Vec3,
}

/// Per-thread scratch space so that queries allocate nothing.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    pub neighbours: Neighbours,
    /// The beam radiance estimate's photons along a segment: where, and what each brings.
    pub beam: Vec<(f32, glam::Vec3)>,
    pub second: Neighbours,
    /// The diffusion estimate's kernel inputs: offset from the query and power of each
    /// agreeing photon within the radius, gathered once by its analysis and summed by its
    /// kernel without reading the map again.
    pub kernel_inputs: Vec<(Vec3, glam::DVec3, u32)>,
    /// The diffusion estimate's leaf runs of slots whose photons all lie on the query's
    /// surface: its kernel streams them again instead of copying each photon out.
    pub kernel_runs: Vec<diffusion::LeafRun>,
    /// The edge cut's buffers.
    pub edge: diffusion::edge::EdgeScratch,
}

pub trait RadianceEstimate: Send + Sync {
    /// Short name, as on the command line.
    fn name(&self) -> &'static str;

    /// Work on the whole map before any query (the diffusion estimate's gradient pass).
    /// The default does nothing, so no pass runs for an estimate that does not need it.
    /// Callers time this call as its own phase.
    fn prepare(&self, _map: &mut PhotonMap) {}

    /// Photon power per unit area arriving at `query`.
    fn irradiance(&self, map: &PhotonMap, query: &Query, scratch: &mut Scratch) -> Vec3;

    /// Radiance reflected at `query` towards the receiver's viewer: the same kernel as
    /// [`RadianceEstimate::irradiance`] over the same photons, each photon's power times the
    /// receiver's BSDF for the direction it arrived from. For a receiver whose BSDF is the
    /// constant ρ/π this is ρ/π times the irradiance.
    fn reflected(
        &self,
        map: &PhotonMap,
        query: &Query,
        receiver: &dyn Receiver,
        scratch: &mut Scratch,
    ) -> Vec3;
}

/// A surface that weighs each photon it receives: a glossy BSDF seen from one direction.
pub trait Receiver: Sync {
    /// f(ωo, ωi) per channel for a photon that travelled along `travel` (unit; ωi = −travel).
    fn bsdf(&self, travel: Vec3) -> Vec3;
}

/// A photon's power weighed by `receiver`, as f64.
#[inline]
pub(crate) fn weighed_power(photon: &PhotonAttributes, receiver: &dyn Receiver) -> glam::DVec3 {
    (photon.power() * receiver.bsdf(photon.direction())).as_dvec3()
}

/// Smallest cosine between a photon's stored normal and the query normal for the photon to
/// be gathered (60°).
pub const NORMAL_AGREEMENT_MIN_COS: f32 = 0.5;

/// Whether `photon` lies on the surface seen from `normal` (see the module notes).
#[inline]
pub fn normals_agree(photon: &Photon, normal: Vec3) -> bool {
    photon.normal().dot(normal) >= NORMAL_AGREEMENT_MIN_COS
}

/// The thickness ([`KnnEstimate::irradiance_and_thickness`]) past which a global-map estimate
/// is not read: its photons lie on many surfaces within its sphere, not on the query's, so it
/// overstates the irradiance by about the ratio of their area to the disc's (a cluster of
/// 25,250 small statues read this way came out twice as bright as pbrt's path tracer). A
/// sphere read over half its own radius stays below it.
pub const THICK_GATHER: f32 = 0.15;

/// Photon power as f64, for sums that must not overflow or lose the small terms.
#[inline]
pub(crate) fn power_f64(photon: &Photon) -> glam::DVec3 {
    photon.power().as_dvec3()
}

/// Converts an f64 irradiance to f32, saturating instead of overflowing to infinity so that
/// an absurd radius or power never puts inf or NaN into an image.
#[inline]
pub(crate) fn to_irradiance(e: glam::DVec3) -> Vec3 {
    let clamp = |v: f64| {
        if v.is_nan() {
            0.0
        } else {
            v.clamp(-(f32::MAX as f64), f32::MAX as f64) as f32
        }
    };
    Vec3::new(clamp(e.x), clamp(e.y), clamp(e.z))
}
