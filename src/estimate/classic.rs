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
//! dense (half of k is wasted on a thin wall lit equally on both sides), but needs no search
//! beyond the one that finds `r_k` and no allocation.
//!
//! # Finding `r_k` fast, the same on any thread count
//! A k-nearest query at k = 400 costs about three radius searches holding as many photons
//! (it keeps its candidates by selection as the bound shrinks). Neighbouring pixels have
//! nearly the same `r_k`, so each thread remembers the last `r_k` and first gathers within it
//! plus a margin, then selects the k-th distance from what it found (see
//! `KnnEstimate::kth_radius2`). The sum runs over that radius search's photons in the tree's
//! visiting order, skipping those at or beyond `r_k`: the photons summed and their order
//! depend only on the query, not on the remembered radius, so the image is bit for bit the
//! same whatever the thread count and the order pixels are visited in.

use super::kernel::{PreparedKernel, RadialKernel};
use super::{
    NORMAL_AGREEMENT_MIN_COS, Query, RadianceEstimate, Receiver, Scratch, to_irradiance,
    weighed_power,
};
use crate::photon::{Neighbours, PhotonAttributes, PhotonMap};
use glam::{DVec3, Vec3};
use std::cell::RefCell;

/// The normal test of the estimates' inner loops (shared with the diffusion estimate): the same
/// answer as `normals_agree`, memoised on the encoded normal. Photons on one surface mostly
/// share it, so the test is usually one comparison of two integers.
pub(crate) struct PhotonReader {
    normal: Vec3,
    last_code: u32,
    last_agrees: bool,
}

impl PhotonReader {
    /// A reader for queries whose surface normal is `normal`.
    pub(crate) fn new(normal: Vec3) -> Self {
        Self {
            normal,
            last_code: u32::MAX,
            last_agrees: false,
        }
    }

    /// Whether the photon lies on the query's surface (`normals_agree`).
    #[inline(always)]
    pub(crate) fn agrees(&mut self, photon: &PhotonAttributes) -> bool {
        let code = u32::from(photon.normal_code());
        if code != self.last_code {
            self.last_code = code;
            self.last_agrees = photon.normal().dot(self.normal) >= NORMAL_AGREEMENT_MIN_COS;
        }
        self.last_agrees
    }
}

/// The photon's power as f64, equal to `power_f64`.
#[inline(always)]
pub(crate) fn power_of(photon: &PhotonAttributes) -> DVec3 {
    photon.power().as_dvec3()
}

/// A k-nearest-neighbour estimate with a radial kernel; the k-th photon sets the radius and is
/// left out of the sum (see the module notes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnnEstimate {
    kernel: RadialKernel,
    prepared: PreparedKernel,
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
            prepared: kernel.prepare(),
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
        self.kernel_sum(map, query, scratch, power_of, |_| {}).0
    }

    fn reflected(
        &self,
        map: &PhotonMap,
        query: &Query,
        receiver: &dyn Receiver,
        scratch: &mut Scratch,
    ) -> Vec3 {
        self.kernel_sum(map, query, scratch, |p| weighed_power(p, receiver), |_| {})
            .0
    }
}

impl KnnEstimate {
    /// This estimate with `k` photons instead (`k ≥ 2`).
    pub fn with_k(self, k: usize) -> Self {
        Self::new(self.kernel, k, self.max_radius)
    }

    /// The irradiance estimate and the squared radius it averaged over (0 when it found
    /// nothing).
    pub fn irradiance_and_radius2(
        &self,
        map: &PhotonMap,
        query: &Query,
        scratch: &mut Scratch,
    ) -> (Vec3, f32) {
        self.kernel_sum(map, query, scratch, power_of, |_| {})
    }

    /// The irradiance estimate and how far its photons lie off the query's tangent plane: the
    /// root mean square of `(x_i − x)·n` over the agreeing photons it summed, in radii (0 when
    /// it found nothing). Photons on one flat or gently curved surface give nearly 0 (a sphere
    /// of radius `R` read over radius `r` gives about `0.29 r/R`); photons scattered over many
    /// small surfaces in the sphere, as many as above the plane as below, about `√(1/5) ≈ 0.45`.
    /// There the estimate, which divides by the disc's area `π r²`, counts the photons of every
    /// surface in the sphere as if they lay on one (see [`super::THICK_GATHER`]).
    pub fn irradiance_and_thickness(
        &self,
        map: &PhotonMap,
        query: &Query,
        scratch: &mut Scratch,
    ) -> (Vec3, f32) {
        let (mut heights, mut count) = (0.0f32, 0u32);
        let (irradiance, radius2) = self.kernel_sum(map, query, scratch, power_of, |slot| {
            let height = (map.position(slot) - query.position).dot(query.normal);
            heights += height * height;
            count += 1;
        });
        let thickness = match count {
            0 => 0.0,
            _ => (heights / (count as f32 * radius2)).sqrt(),
        };
        (irradiance, thickness)
    }

    /// The kernel-weighted sum of `weigh` over the k nearest agreeing photons, per unit area,
    /// and the squared radius it used (0: none); `summed` sees the slot of each photon summed
    /// (a no-op where nothing else is wanted, which the compiler removes).
    fn kernel_sum(
        &self,
        map: &PhotonMap,
        query: &Query,
        scratch: &mut Scratch,
        weigh: impl Fn(&PhotonAttributes) -> DVec3,
        mut summed: impl FnMut(u32),
    ) -> (Vec3, f32) {
        let Some(found2) = self.kth_radius2(map, query.position, scratch) else {
            return (Vec3::ZERO, 0.0);
        };
        let radius2 = found2 as f64;
        // Coincident photons give no area to divide by.
        if radius2.is_nan() || radius2 <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        // `scratch.second` holds every photon within some R ≥ r_k in the tree's visiting
        // order; those at or beyond r_k weigh nothing (the k-th lies at y = 1, where every
        // kernel is zero, so it is left out without a test). The photons summed and their
        // order depend only on the query, not on R, so the image is the same whatever R was.
        let mut reader = PhotonReader::new(query.normal);
        let kernel = self.prepared.for_radius2(radius2);
        let mut sum = DVec3::ZERO;
        for n in scratch.second.as_slice() {
            let d2 = n.dist2 as f64;
            if d2 >= radius2 {
                continue;
            }
            let photon = map.attributes(n.slot);
            if reader.agrees(photon) {
                sum += kernel.weight(d2) * weigh(photon);
                summed(n.slot);
            }
        }
        (to_irradiance(sum / radius2), found2)
    }
}

/// Squared-radius margin of a predicted search over the previous query's `r_k²`: 1.1 in
/// radius, about four standard deviations of `r_k` at k = 400 (`r_k` varies by `1/(2√k)`).
const PREDICTION_MARGIN2: f32 = 1.21;
/// Largest growth of the searched area when a predicted search found fewer than `k`.
const MAX_GROWTH: f32 = 4.0;

/// Per-thread memory of the k-NN estimates: the last `r_k²` per (map, k), the hint that makes a
/// radius search plus a selection replace the k-nearest query, and the selection's buffer.
#[derive(Default)]
struct Prediction {
    /// (map address, k, last r_k²), a few so that a render alternating between its caustic and
    /// global maps keeps a hint for each.
    hints: [(usize, usize, f32); 4],
    next: usize,
    keys: Vec<u32>,
}

impl Prediction {
    fn hint(&self, map: usize, k: usize) -> Option<f32> {
        self.hints
            .iter()
            .find(|h| h.0 == map && h.1 == k)
            .map(|h| h.2)
    }

    fn remember(&mut self, map: usize, k: usize, radius2: f32) {
        if !(radius2 > 0.0 && radius2.is_finite()) {
            return;
        }
        if let Some(h) = self.hints.iter_mut().find(|h| h.0 == map && h.1 == k) {
            h.2 = radius2;
        } else {
            self.hints[self.next] = (map, k, radius2);
            self.next = (self.next + 1) % self.hints.len();
        }
    }

    /// The k-th smallest squared distance among `found` (at least `k` of them, all within
    /// `search2`). A selection over all of them is mostly mispredicted branches; instead the
    /// distances are counted into buckets by their bits (non-negative floats order like
    /// their bits), and only the bucket holding the k-th is selected in. Buckets are 1/64 of
    /// the binade below `search2` wide, nearest `search2` first; everything below that binade
    /// shares the last bucket. The bucket of `d²` never increases with `d²`, so the result is
    /// exactly the k-th.
    fn kth(&mut self, found: &Neighbours, k: usize, search2: f32) -> f32 {
        const BUCKETS: usize = 64;
        let top = search2.to_bits();
        let bucket = |d2: f32| (top.saturating_sub(d2.to_bits()) >> 17).min(BUCKETS as u32 - 1);
        // Four histograms, so that neighbours falling in one bucket do not wait on each
        // other's increments.
        let mut counts = [[0u32; BUCKETS]; 4];
        let items = found.as_slice();
        for (i, n) in items.iter().enumerate() {
            counts[i & 3][bucket(n.dist2) as usize] += 1;
        }
        // Buckets run from far to near: the k-th nearest is the (len − k + 1)-th farthest.
        let want = items.len() - k;
        let (mut before, mut chosen) = (0usize, BUCKETS as u32 - 1);
        for b in 0..BUCKETS as u32 {
            let c: u32 = counts.iter().map(|h| h[b as usize]).sum();
            if before + c as usize > want {
                chosen = b;
                break;
            }
            before += c as usize;
        }
        self.keys.clear();
        self.keys.extend(
            items
                .iter()
                .filter(|n| bucket(n.dist2) == chosen)
                .map(|n| n.dist2.to_bits()),
        );
        // Within the bucket, the (want − before)-th farthest.
        let i = self.keys.len() - 1 - (want - before);
        f32::from_bits(*self.keys.select_nth_unstable(i).1)
    }
}

thread_local! {
    static PREDICTION: RefCell<Prediction> = RefCell::default();
}

impl KnnEstimate {
    /// The estimate's squared radius (`r_k²`, or the cap when fewer than `k` photons lie
    /// within it), leaving in `scratch.second` every photon within a radius at least that, in
    /// the tree's visiting order; `None` when nothing is found.
    ///
    /// Neighbouring pixels have nearly the same `r_k`, so the search first gathers within the
    /// previous query's `r_k` plus a margin and selects the k-th distance from what it found: a
    /// radius search and a selection cost about half a k-nearest query at k = 400. When that
    /// finds fewer than `k` (a sparser region) it widens once; failing that, or with no hint,
    /// a k-nearest query gives `r_k` and a radius search of exactly `r_k` the photons.
    fn kth_radius2(&self, map: &PhotonMap, position: Vec3, scratch: &mut Scratch) -> Option<f32> {
        let (tree, k) = (map.tree(), self.k);
        let cap2 = self.max_radius.map_or(f32::INFINITY, |r| r * r);
        let id = map as *const PhotonMap as usize;
        PREDICTION.with(|cell| {
            let mut prediction = cell.borrow_mut();
            if let Some(hint) = prediction.hint(id, k) {
                let mut search2 = (hint * PREDICTION_MARGIN2).min(cap2);
                for _ in 0..2 {
                    tree.within_radius(position, search2, &mut scratch.second);
                    let found = scratch.second.len();
                    if found >= k {
                        let radius2 = prediction.kth(&scratch.second, k, search2);
                        prediction.remember(id, k, radius2);
                        return Some(radius2);
                    }
                    if self.max_radius.is_some() && search2 >= cap2 {
                        // Fewer than k within the cap: the cap is the radius.
                        return (found > 0).then_some(cap2);
                    }
                    if found == 0 {
                        break;
                    }
                    let growth = (k as f32 / found as f32).min(MAX_GROWTH);
                    search2 = (search2 * growth * PREDICTION_MARGIN2).min(cap2);
                }
            }
            let nearest = &mut scratch.neighbours;
            tree.k_nearest(position, k, cap2, nearest);
            let farthest = nearest.farthest()?;
            // Full k (or a map smaller than k with no cap): the farthest photon sets the
            // radius. Fewer than k inside the cap: the cap is the radius.
            let radius2 = if nearest.len() >= k || self.max_radius.is_none() {
                farthest.dist2
            } else {
                cap2
            };
            if nearest.len() >= k {
                prediction.remember(id, k, radius2);
            }
            tree.within_radius(position, radius2, &mut scratch.second);
            Some(radius2)
        })
    }
}

/// A fixed-radius estimate (Eq. 2 with `r` independent of `x`; with the Epanechnikov kernel
/// this is Eq. 5). Unbiased on a uniform density for any kernel normalised over the disc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedRadiusEstimate {
    kernel: RadialKernel,
    prepared: PreparedKernel,
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
        Self {
            kernel,
            prepared: kernel.prepare(),
            radius,
        }
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
        self.kernel_sum(map, query, power_of)
    }

    fn reflected(
        &self,
        map: &PhotonMap,
        query: &Query,
        receiver: &dyn Receiver,
        _scratch: &mut Scratch,
    ) -> Vec3 {
        self.kernel_sum(map, query, |p| weighed_power(p, receiver))
    }
}

impl FixedRadiusEstimate {
    /// The kernel-weighted sum of `weigh` over the agreeing photons within the radius, per
    /// unit area.
    fn kernel_sum(
        &self,
        map: &PhotonMap,
        query: &Query,
        weigh: impl Fn(&PhotonAttributes) -> DVec3,
    ) -> Vec3 {
        let radius2 = self.radius as f64 * self.radius as f64;
        let mut reader = PhotonReader::new(query.normal);
        let kernel = self.prepared.for_radius2(radius2);
        let mut sum = DVec3::ZERO;
        map.tree()
            .for_each_within(query.position, radius2 as f32, |slot, dist2| {
                let photon = map.attributes(slot);
                if reader.agrees(photon) {
                    sum += kernel.weight(dist2 as f64) * weigh(photon);
                }
            });
        to_irradiance(sum / radius2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::{normals_agree, power_f64};
    use crate::photon::Photon;

    #[test]
    fn bucketed_selection_finds_the_kth_distance() {
        use crate::photon::KdTree;
        let mut state = 12345u64;
        let mut next = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        // Clusters and duplicates, so that buckets are uneven and distances tie.
        let mut points: Vec<Vec3> = (0..4000)
            .map(|i| {
                let s = if i % 3 == 0 { 0.01 } else { 1.0 };
                Vec3::new(next() * s, next() * s, 0.0)
            })
            .collect();
        points.extend(std::iter::repeat_n(Vec3::new(0.2, 0.2, 0.0), 50));
        let tree = KdTree::build(&points);
        let mut found = Neighbours::new();
        let mut prediction = Prediction::default();
        for (q, search2) in [
            (Vec3::new(0.5, 0.5, 0.0), 0.02),
            (Vec3::ZERO, 0.5),
            (Vec3::new(0.2, 0.2, 0.0), 0.001),
            (Vec3::new(0.005, 0.005, 0.0), 3.0),
        ] {
            tree.within_radius(q, search2, &mut found);
            let mut sorted: Vec<f32> = found.as_slice().iter().map(|n| n.dist2).collect();
            sorted.sort_by(f32::total_cmp);
            for k in [1, 2, 7, sorted.len() / 2, sorted.len()] {
                if k == 0 {
                    continue;
                }
                assert_eq!(prediction.kth(&found, k, search2), sorted[k - 1], "{q} {k}");
            }
        }
    }

    #[test]
    fn reader_matches_the_record_decoders_bit_for_bit() {
        let query = Vec3::new(0.3, -0.2, 0.9).normalize();
        let mut reader = PhotonReader::new(query);
        for code in (0..=u16::MAX)
            .step_by(7)
            .chain([0, 127 * 256 + 127, u16::MAX])
        {
            for e in [0u8, 1, 2, 100, 127, 128, 129, 200, 254, 255] {
                let [a, b] = code.to_be_bytes();
                let mut bytes = [0u8; 20];
                bytes[12..20].copy_from_slice(&[3, 255, 128, e, 7, 9, a, b]);
                let photon = Photon::from_le_bytes(bytes);
                let attributes = photon.attributes();
                assert_eq!(
                    reader.agrees(&attributes),
                    normals_agree(&photon, query),
                    "{code}"
                );
                let (fast, slow) = (power_of(&attributes), power_f64(&photon));
                assert_eq!(
                    fast.to_array().map(f64::to_bits),
                    slow.to_array().map(f64::to_bits)
                );
            }
        }
    }
}
