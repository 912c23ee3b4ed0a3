//! The diffusion estimate with its kernels shaped on another map than the one it sums: the
//! structure tensor, and so each kernel's direction and squeeze, taken on earlier passes'
//! photons (the tensor history, `render::tensor_history`) at the pass's own radii, the density
//! summed over the pass's own photons. The shape is then independent of the photons it
//! weighs: a kernel shaped by the same photons it sums leans on their noise, which lost 0.6% of
//! the constructed distribution's interior energy after 16 passes and 1.1% of caustic-glass's
//! caustic, and which averaging passes does not remove. With `--edge-cut` a squeezed kernel is
//! also cut at the edge the other map's photons show ([`super::edge`]). Owns that sum; must
//! not trace rays.

use super::super::classic::{PhotonReader, power_of};
use super::super::{Query, Receiver, Scratch, to_irradiance, weighed_power};
use super::edge::{self, Strip};
use super::structure::TangentFrame;
use super::tensor::DiffusionTensor;
use super::{DiffusionEstimate, surface_leaves};
use crate::photon::{Photon, PhotonMap};
use glam::{DVec3, Vec3};

/// Which photons of the earlier passes shape a pass's kernels (`--history-photons`).
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum HistoryPhotons {
    /// One pass's worth: of N earlier passes, one photon in N of each (every N-th in the
    /// map's spatial order, offset by the pass; the first passes keep more), kept as the pass
    /// ends. The shapes cost what a pass's own would and are independent of the photons they
    /// spread, and the history holds about one pass's photons (at most 1 + 1/2 + ... + 1/N).
    OnePass,
    /// Every photon of the N passes at 1/N of its power: shapes from N times the photons,
    /// sharper where edges are faint, at N times the gradient pass and the tensor's scan.
    All,
}

impl HistoryPhotons {
    /// One photon in how many of pass `pass` a history of `depth` passes keeps. One-pass:
    /// `depth`, but fewer for the first passes, which serve the passes right after them with
    /// fewer passes beside them (pass 0 all, pass 1 one in two, ...); all: 1.
    pub fn stride(self, pass: u64, depth: u64) -> u64 {
        match self {
            HistoryPhotons::OnePass => (pass + 1).min(depth).max(1),
            HistoryPhotons::All => 1,
        }
    }

    /// The photons of pass `pass` that a history of `depth` passes keeps: every
    /// [`Self::stride`]-th in the order given, from the pass's index modulo it (consecutive
    /// passes keep interleaved strata).
    pub fn kept(self, pass: u64, depth: u64, photons: impl Iterator<Item = Photon>) -> Vec<Photon> {
        let stride = self.stride(pass, depth);
        photons
            .skip((pass % stride) as usize)
            .step_by(stride as usize)
            .collect()
    }

    /// Passes' worth of photons a history of `depth` passes holds at most: all of them, or
    /// for one-pass the first passes' larger shares, 1 + 1/2 + ... + 1/depth.
    pub fn passes_kept(self, depth: u32) -> f64 {
        match self {
            HistoryPhotons::OnePass => (1..=depth).map(|i| 1.0 / f64::from(i)).sum(),
            HistoryPhotons::All => f64::from(depth),
        }
    }
}

/// The map that shapes a pass's kernels, from what a history of `depth` passes kept of the
/// earlier ones (`(pass, photons)` as [`HistoryPhotons::kept`] kept them): its density is one
/// pass's. For all, every kept photon at `1/n` of its power (`n` passes). For one pass's
/// worth, each of the `n` passes gives `1/n` of its photons at their own power: the first
/// passes kept more (pass 0 all of its photons, for pass 1), and only the share the window
/// needs is taken, evenly through what was kept, so that a pass's history holds one pass's
/// photons (and costs one pass's gradient pass) from pass 1 on, not up to twice as many.
/// `None` when there is no earlier pass.
pub fn history_map(
    kept: &[(u64, &[Photon])],
    depth: u64,
    photons: HistoryPhotons,
) -> Option<PhotonMap> {
    if kept.is_empty() {
        return None;
    }
    let n = kept.len() as u64;
    let map: Vec<Photon> = match photons {
        HistoryPhotons::All => {
            let scale = 1.0 / n as f32;
            (kept.iter())
                .flat_map(|&(_, kept)| kept.iter())
                .map(|p| Photon::new(p.position(), p.power() * scale, p.direction(), p.normal()))
                .collect()
        }
        HistoryPhotons::OnePass => (kept.iter())
            .flat_map(|&(pass, kept)| {
                // Pass `pass` kept one photon in `stride`; the window wants one in `n`.
                let stride = photons.stride(pass, depth);
                evenly(kept, stride, n).copied()
            })
            .collect(),
    };
    let emitted = map.len() as u64;
    Some(PhotonMap::build(map, emitted))
}

/// `stride/n` of `items` (`stride ≤ n`), evenly spread: item `m` is taken where
/// `⌊(m + 1)·stride/n⌋` steps past `⌊m·stride/n⌋`.
fn evenly<T>(items: &[T], stride: u64, n: u64) -> impl Iterator<Item = &T> {
    debug_assert!(
        stride <= n,
        "a pass kept fewer photons than its window takes"
    );
    (items.iter().enumerate())
        .filter(move |&(m, _)| ((m as u64 + 1) * stride) / n > (m as u64 * stride) / n)
        .map(|(_, item)| item)
}

/// Gives a map that [`ShapedBy`] sums its leaf sums (powers, leaf normals and moments, no
/// gradients), unless it holds a field already.
pub fn prepare_summed(map: &mut PhotonMap) {
    if map.leaf_sums().is_none() {
        let field = crate::photon::map::GradientField::leaf_sums_of(map);
        map.set_gradient_field(field);
    }
}

/// A diffusion estimate whose kernels take their shapes from `analysis` (which must hold
/// gradients at the estimate's radii, [`DiffusionEstimate::gradient_pass`]); the density comes
/// from the map queried.
pub struct ShapedBy<'a> {
    pub estimate: DiffusionEstimate,
    pub analysis: &'a PhotonMap,
}

impl super::super::RadianceEstimate for ShapedBy<'_> {
    fn name(&self) -> &'static str {
        "diffusion"
    }

    /// Gives the summed map its leaf sums (no gradients: the shapes come from `analysis`),
    /// so that the kernel sums whole leaves.
    fn prepare(&self, map: &mut PhotonMap) {
        prepare_summed(map);
    }

    fn irradiance(&self, map: &PhotonMap, query: &Query, scratch: &mut Scratch) -> Vec3 {
        (self.estimate).shaped_irradiance(self.analysis, map, query, scratch)
    }

    fn reflected(
        &self,
        map: &PhotonMap,
        query: &Query,
        receiver: &dyn Receiver,
        scratch: &mut Scratch,
    ) -> Vec3 {
        let (tensor, shape) = self.estimate.analyse(self.analysis, query, scratch);
        let strip =
            (self.estimate).edge_strip(self.analysis, query, &tensor, shape.lambda2, scratch);
        let weigh = |p: &crate::photon::PhotonAttributes| weighed_power(p, receiver);
        (self.estimate).photon_by_photon(&tensor, strip.as_ref(), map, query, weigh)
    }
}

impl DiffusionEstimate {
    /// The query-centred kernel shaped on `analysis`, summed over `map`'s photons: by leaf
    /// runs and their moments as the own-map estimate sums them where `map` holds its leaf
    /// sums ([`prepare_summed`]; the Lambert receivers' irradiance), else photon by photon (as
    /// for a glossy receiver's weights).
    fn shaped_irradiance(
        &self,
        analysis: &PhotonMap,
        map: &PhotonMap,
        query: &Query,
        scratch: &mut Scratch,
    ) -> Vec3 {
        let (tensor, shape) = self.analyse(analysis, query, scratch);
        let strip = self.edge_strip(analysis, query, &tensor, shape.lambda2, scratch);
        let Some(field) = map.leaf_sums().filter(|_| strip.is_none()) else {
            return self.photon_by_photon(&tensor, strip.as_ref(), map, query, power_of);
        };
        let r2 = sq(self.params.radius) as f32;
        let normal = TangentFrame::new(query.normal).normal.as_vec3();
        let mixed = surface_leaves(
            map,
            field,
            (query.position, normal),
            r2,
            &mut scratch.kernel_runs,
        );
        let inputs = &mut scratch.kernel_inputs;
        inputs.clear();
        let mut reader = PhotonReader::new(query.normal);
        for (_, slots) in mixed {
            for slot in slots {
                let slot = slot as u32;
                let photon = map.attributes(slot);
                let d = map.position(slot) - query.position;
                if d.length_squared() < r2 && reader.agrees(photon) {
                    inputs.push((d, power_of(photon), slot));
                }
            }
        }
        self.kernel_sum(map, field, &tensor, query, scratch)
    }

    /// With `--edge-cut`, where the kernel is squeezed: the strip of its disc on the query's
    /// side of the edge `analysis`'s photons show.
    fn edge_strip(
        &self,
        analysis: &PhotonMap,
        query: &Query,
        tensor: &DiffusionTensor,
        lambda2: f32,
        scratch: &mut Scratch,
    ) -> Option<Strip> {
        if !self.params.edge_cut || lambda2 >= edge::GATE_LAMBDA2 {
            return None;
        }
        let r2 = sq(self.params.radius);
        let axes = (tensor.x1, tensor.x2);
        edge::locate(analysis, query, axes, r2, &mut scratch.edge)
    }

    /// The kernel `tensor` shapes at the query, summed over `map`'s photons within `r` on the
    /// query's surface one by one, each weighed by `weigh`. With a `strip`, the round kernel
    /// (`λ3` along the normal as the tensor's) over the strip only, divided by the kernel's
    /// share inside it.
    fn photon_by_photon(
        &self,
        tensor: &DiffusionTensor,
        strip: Option<&Strip>,
        map: &PhotonMap,
        query: &Query,
        weigh: impl Fn(&crate::photon::PhotonAttributes) -> DVec3,
    ) -> Vec3 {
        let r2 = sq(self.params.radius);
        match strip {
            None => {
                let sum = self.weighed_sum(tensor, map, query, |_| true, weigh);
                to_irradiance(sum * (tensor.plane_normalisation() / r2))
            }
            Some(strip) => {
                let round = DiffusionTensor::new(tensor.x2, tensor.x3, 1.0, tensor.lambda3);
                let sum = self.weighed_sum(&round, map, query, |d| strip.keeps(d), weigh);
                to_irradiance(sum / (r2 * strip.epanechnikov_share(r2.sqrt())))
            }
        }
    }

    /// `Σ K(dᵀD⁻¹d / r²) weigh(photon)` over `map`'s photons within `r` on the query's surface
    /// whose offsets `d` pass `keeps`.
    fn weighed_sum(
        &self,
        tensor: &DiffusionTensor,
        map: &PhotonMap,
        query: &Query,
        keeps: impl Fn(DVec3) -> bool,
        weigh: impl Fn(&crate::photon::PhotonAttributes) -> DVec3,
    ) -> DVec3 {
        let r2 = sq(self.params.radius);
        let metric = tensor.metric(r2);
        let kernel = self.params.kernel.radial().prepare();
        let mut reader = PhotonReader::new(query.normal);
        let mut sum = DVec3::ZERO;
        map.tree()
            .for_each_within(query.position, r2 as f32, |slot, _| {
                let photon = map.attributes(slot);
                if reader.agrees(photon) {
                    let d = (map.position(slot) - query.position).as_dvec3();
                    if keeps(d) {
                        sum += kernel.weight(metric.distance(d)) * weigh(photon);
                    }
                }
            });
        sum
    }
}

fn sq(v: f32) -> f64 {
    v as f64 * v as f64
}

#[cfg(test)]
mod tests {
    use super::super::super::RadianceEstimate;
    use super::*;

    fn pass_photons(count: usize) -> Vec<Photon> {
        (0..count)
            .map(|i| {
                let x = i as f32 * 0.01;
                Photon::new(
                    Vec3::new(x, 0.0, 0.0),
                    Vec3::splat(1.0 + x),
                    Vec3::NEG_Z,
                    Vec3::Z,
                )
            })
            .collect()
    }

    fn power(map: &PhotonMap) -> Vec3 {
        map.photons().map(|p| p.power()).sum()
    }

    #[test]
    fn one_pass_of_history_holds_one_pass_and_all_holds_every_photon_at_its_share() {
        let photons = pass_photons(1001);
        let one = power(&PhotonMap::build(photons.clone(), 1001));
        let close =
            |map: &PhotonMap| (power(map) - one).abs().max_element() < 1e-2 * one.max_element();
        for history in [HistoryPhotons::OnePass, HistoryPhotons::All] {
            let kept: Vec<(u64, Vec<Photon>)> = (0..12)
                .map(|p| (p, history.kept(p, 4, photons.iter().copied())))
                .collect();
            let slices: Vec<(u64, &[Photon])> =
                kept.iter().map(|(p, k)| (*p, k.as_slice())).collect();
            // Pass 1 is shaped by pass 0, pass 3 by passes 0-2, pass 12 by passes 8-11 (four
            // passes of the same photons: one-pass strata cover every slot once).
            for earlier in [&slices[..1], &slices[..3], &slices[..4], &slices[8..12]] {
                let map = history_map(earlier, 4, history).unwrap();
                assert!(close(&map), "{history:?}");
                if history == HistoryPhotons::OnePass {
                    // One pass's photons from pass 1 on, though the first passes kept more.
                    let n = earlier.len();
                    assert!(
                        map.len().abs_diff(photons.len()) <= n,
                        "{} photons",
                        map.len()
                    );
                }
            }
            let steady = history_map(&slices[8..12], 4, history).unwrap();
            let passes = if history == HistoryPhotons::OnePass {
                1
            } else {
                4
            };
            assert_eq!(steady.len(), passes * photons.len(), "{history:?}");
        }
        assert_eq!(
            HistoryPhotons::OnePass
                .kept(0, 4, photons.iter().copied())
                .len(),
            1001
        );
        assert_eq!(
            HistoryPhotons::OnePass
                .kept(2, 4, photons.iter().copied())
                .len(),
            333 // slots 2, 5, ..., 998 of 1001: pass 2 keeps one in three
        );
        assert!((HistoryPhotons::OnePass.passes_kept(4) - 25.0 / 12.0).abs() < 1e-12);
        assert!(history_map(&[], 4, HistoryPhotons::OnePass).is_none());
    }

    fn uniform(i: u64, salt: u64) -> f32 {
        (crate::sampling::mix(i, salt) >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A floor with a bright band along y (so kernels squeeze) and a wall standing on it at
    /// x = 0.5 (so leaves near the corner hold both surfaces).
    fn corner_map(salt: u64) -> PhotonMap {
        let photons = (0..40_000u64)
            .map(|i| {
                let (u, v) = (uniform(i, salt), uniform(i, salt + 1));
                if i % 4 == 3 {
                    let p = Vec3::new(0.5, u, 0.3 * v);
                    Photon::new(p, Vec3::splat(0.5), Vec3::NEG_X, Vec3::X)
                } else {
                    let band = (u - 0.3).abs() < 0.05;
                    let power = if band { 4.0 } else { 1.0 };
                    let p = Vec3::new(u, v, 0.0);
                    Photon::new(p, Vec3::splat(power), Vec3::NEG_Z, Vec3::Z)
                }
            })
            .collect();
        PhotonMap::build(photons, 40_000)
    }

    #[test]
    fn a_shaped_kernel_sums_whole_leaves_as_it_sums_photons_one_by_one() {
        let settings = crate::estimate::EstimatorSettings {
            radius: Some(0.06),
            ..Default::default()
        };
        let mut analysis = corner_map(11);
        let mut map = corner_map(23);
        let crate::estimate::ResolvedEstimator::Diffusion(d) = settings.resolve(&map).unwrap()
        else {
            panic!("the default estimate is the diffusion estimate");
        };
        d.gradient_pass(&mut analysis);
        let shaped = ShapedBy {
            estimate: d,
            analysis: &analysis,
        };
        shaped.prepare(&mut map);
        let mut scratch = Scratch::default();
        let mut squeezed = 0;
        for i in 0..200u64 {
            let position = Vec3::new(0.2 + 0.35 * uniform(i, 5), 0.1 + 0.8 * uniform(i, 6), 0.0);
            let query = Query {
                position,
                normal: Vec3::Z,
            };
            let (tensor, shape) = d.analyse(&analysis, &query, &mut scratch);
            squeezed += usize::from(shape.lambda2 < 0.5);
            let one_by_one = d.photon_by_photon(&tensor, None, &map, &query, power_of);
            let by_leaves = shaped.irradiance(&map, &query, &mut scratch);
            let scale = one_by_one.max_element().max(1e-6);
            assert!(
                (by_leaves - one_by_one).abs().max_element() < 1e-4 * scale,
                "{position}: {by_leaves} by leaves, {one_by_one} one by one"
            );
        }
        // The band's edges and the corner are in the sample.
        assert!(squeezed > 10, "{squeezed} squeezed kernels");
    }

    /// Photons uniform on the unit square, one in four kept where x > 0.5: a step of 4 to 1.
    fn step_map(salt: u64) -> (PhotonMap, f64, f64) {
        let photons: Vec<Photon> = (0..200_000u64)
            .filter_map(|i| {
                let (u, v) = (uniform(i, salt), uniform(i, salt + 1));
                (u < 0.5 || i % 4 == 0)
                    .then(|| Photon::new(Vec3::new(u, v, 0.0), Vec3::ONE, Vec3::NEG_Z, Vec3::Z))
            })
            .collect();
        let high = photons.iter().filter(|p| p.position().x < 0.5).count() as f64 / 0.5;
        let low = (photons.len() as f64 - 0.5 * high) / 0.5;
        (PhotonMap::build(photons, 200_000), high, low)
    }

    #[test]
    fn an_edge_cut_keeps_a_kernel_beside_an_edge_on_its_own_side() {
        let estimate = |edge_cut| {
            let settings = crate::estimate::EstimatorSettings {
                radius: Some(0.03),
                edge_cut,
                ..Default::default()
            };
            let (map, ..) = step_map(1);
            match settings.resolve(&map).unwrap() {
                crate::estimate::ResolvedEstimator::Diffusion(d) => d,
                _ => panic!("the default estimate is the diffusion estimate"),
            }
        };
        let (mut analysis, ..) = step_map(11);
        let (mut map, high, low) = step_map(23);
        let mut scratch = Scratch::default();
        // Mean estimate over 200 queries at `x` (0.003 from the edge: a tenth of r).
        let mut mean_at = |cut: bool, x: f32| {
            let d = estimate(cut);
            d.gradient_pass(&mut analysis);
            let shaped = ShapedBy {
                estimate: d,
                analysis: &analysis,
            };
            shaped.prepare(&mut map);
            let sum: f64 = (0..200)
                .map(|i| {
                    let query = Query {
                        position: Vec3::new(x, 0.1 + 0.004 * i as f32, 0.0),
                        normal: Vec3::Z,
                    };
                    f64::from(shaped.irradiance(&map, &query, &mut scratch).x)
                })
                .sum();
            sum / 200.0
        };
        let (cut_high, cut_low) = (mean_at(true, 0.497), mean_at(true, 0.503));
        let (plain_high, plain_low) = (mean_at(false, 0.497), mean_at(false, 0.503));
        assert!(
            (cut_high / high - 1.0).abs() < 0.03,
            "{cut_high} against {high}"
        );
        assert!(
            (cut_low / low - 1.0).abs() < 0.05,
            "{cut_low} against {low}"
        );
        // The squeezed ellipse, as wide across as the query's distance to the edge at the λ2
        // floor, still reaches over it from the bright side (10% here).
        assert!(plain_high < 0.95 * high, "{plain_high} against {high}");
        assert!((cut_low - low).abs() < (plain_low - low).abs());
    }
}
