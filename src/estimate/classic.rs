//! The classic radiance estimates: k-nearest-neighbour estimates with a radial kernel (the
//! simple estimate of Eq. 1, Jensen's cone filter of Eq. 3, a Gaussian) and the fixed-radius
//! estimate (the Epanechnikov kernel of Eq. 4/5). Owns photon gathering for these estimates;
//! must not touch the diffusion estimate's gradients or tensors.
//!
//! # Why the k-th photon is left out
//! With the radius `r_k` set by the k-th nearest photon, the other `k − 1` photons are, given
//! `r_k`, uniformly distributed in the disc, and for a uniform density `ρ` the area
//! `ρ π r_k²` is Gamma(k)-distributed, so `E[(k − 1)/(π r_k²)] = ρ`. Any kernel normalised
//! over the unit disc therefore gives an unbiased estimate when it sums the `k − 1` inner
//! photons and divides by `r_k²` (García et al., CGF 2012). Summing the k-th photon as well
//! adds `K(1⁻) Φ / r_k²` on average, a relative bias `π K(1⁻)/(k − 1)`: `1/(k − 1)` for the
//! simple estimate; for the cone filter `(1 − 1/s)/((1 − 2/(3s))(k − 1))`, which vanishes only
//! for slope `s = 1` (the cone is zero at its rim) — so leaving the k-th out makes the cone
//! filter unbiased for every slope, and changes nothing when `s = 1`.
//!
//! # A capped search
//! With a maximum radius `R`, a query that finds fewer than `k` photons within `R` uses `R` as
//! the radius and sums every photon found. The combination is still unbiased on a uniform
//! density: `P(Poisson(ρπR²) ≥ k − 1) ρ + P(Poisson(ρπR²) ≤ k − 2) ρ = ρ`.
//!
//! # Normal agreement and k
//! The k nearest photons are found in 3-D regardless of their normals; the k-th sets the
//! radius; photons whose normal disagrees with the query's are then skipped in the sum (they
//! still count towards k). On a uniform density this keeps the estimate unbiased, because the
//! foreign photons only thin the process: given `r_k`, each inner photon lies on the query's
//! plane with probability `π r_k² / A(r_k)` where `A(r)` is the total surface area inside the
//! sphere, and `ρ A(r_k)` is Gamma(k)-distributed. It costs variance where foreign photons are
//! dense (half of k is wasted on a thin wall lit equally on both sides), but needs no second
//! search and no allocation.

use super::kernel::RadialKernel;
use super::{Query, RadianceEstimate, Scratch, normals_agree, power_f64, to_irradiance};
use crate::photon::PhotonMap;
use glam::{DVec3, Vec3};

/// A k-nearest-neighbour estimate with a radial kernel; the k-th photon sets the radius and is
/// left out of the sum (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnnEstimate {
    kernel: RadialKernel,
    k: usize,
    max_radius: Option<f32>,
}

impl KnnEstimate {
    /// # Panics
    /// If `k < 2` (the k-th photon is left out, so one photon can never estimate anything) or
    /// `max_radius` is not positive and finite.
    pub fn new(kernel: RadialKernel, k: usize, max_radius: Option<f32>) -> Self {
        assert!(k >= 2, "k-NN estimates need k >= 2, got {k}");
        if let Some(r) = max_radius {
            assert!(
                r > 0.0 && r.is_finite(),
                "max radius must be positive, got {r}"
            );
        }
        Self {
            kernel,
            k,
            max_radius,
        }
    }
    pub fn kernel(&self) -> RadialKernel {
        self.kernel
    }
    pub fn k(&self) -> usize {
        self.k
    }
    pub fn max_radius(&self) -> Option<f32> {
        self.max_radius
    }
}

impl RadianceEstimate for KnnEstimate {
    fn name(&self) -> &'static str {
        match self.kernel {
            RadialKernel::Constant => "simple",
            RadialKernel::Cone { .. } => "cone",
            RadialKernel::Gaussian => "gaussian",
            RadialKernel::Epanechnikov => "knn-epanechnikov",
        }
    }

    fn irradiance(&self, map: &PhotonMap, query: &Query, scratch: &mut Scratch) -> Vec3 {
        let cap2 = self.max_radius.map_or(f32::INFINITY, |r| r * r);
        let found = &mut scratch.neighbours;
        map.tree().k_nearest(query.position, self.k, cap2, found);
        let Some(farthest) = found.farthest() else {
            return Vec3::ZERO;
        };
        // Full k (or a map smaller than k with no cap): the farthest photon sets the radius.
        // It lies at y = 1, where every kernel is zero, so it is left out of the sum without
        // a test. Fewer than k inside the cap: the cap is the radius and every photon counts.
        let radius2 = if found.len() >= self.k || self.max_radius.is_none() {
            farthest.dist2 as f64
        } else {
            cap2 as f64
        };
        // Coincident photons give no area to divide by.
        if radius2.is_nan() || radius2 <= 0.0 {
            return Vec3::ZERO;
        }
        let mut sum = DVec3::ZERO;
        for n in found.as_slice() {
            let photon = &map.photon(n.slot);
            if normals_agree(photon, query.normal) {
                sum += self.kernel.weight(n.dist2 as f64 / radius2) * power_f64(photon);
            }
        }
        to_irradiance(sum / radius2)
    }
}

/// A fixed-radius estimate (Eq. 2 with `r` independent of `x`; with the Epanechnikov kernel
/// this is Eq. 5). Unbiased on a uniform density for any kernel normalised over the disc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedRadiusEstimate {
    kernel: RadialKernel,
    radius: f32,
}

impl FixedRadiusEstimate {
    /// # Panics
    /// If `radius` is not positive and finite.
    pub fn new(kernel: RadialKernel, radius: f32) -> Self {
        assert!(
            radius > 0.0 && radius.is_finite(),
            "radius must be positive, got {radius}"
        );
        Self { kernel, radius }
    }
    pub fn radius(&self) -> f32 {
        self.radius
    }
    pub fn kernel(&self) -> RadialKernel {
        self.kernel
    }
}

impl RadianceEstimate for FixedRadiusEstimate {
    fn name(&self) -> &'static str {
        match self.kernel {
            RadialKernel::Epanechnikov => "epanechnikov",
            RadialKernel::Constant => "fixed-simple",
            RadialKernel::Cone { .. } => "fixed-cone",
            RadialKernel::Gaussian => "fixed-gaussian",
        }
    }

    fn irradiance(&self, map: &PhotonMap, query: &Query, _scratch: &mut Scratch) -> Vec3 {
        let radius2 = self.radius as f64 * self.radius as f64;
        let mut sum = DVec3::ZERO;
        map.tree()
            .for_each_within(query.position, radius2 as f32, |slot, dist2| {
                let photon = &map.photon(slot);
                if normals_agree(photon, query.normal) {
                    sum += self.kernel.weight(dist2 as f64 / radius2) * power_f64(photon);
                }
            });
        to_irradiance(sum / radius2)
    }
}
