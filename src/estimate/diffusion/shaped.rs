//! The diffusion estimate with its kernels shaped on another map than the one it sums: the
//! structure tensor, and so each kernel's direction and squeeze, taken on earlier passes'
//! photons (the tensor history, `render::tensor_history`) at the pass's own radii, the density
//! summed over the pass's own photons. The shape is then independent of the photons it
//! weighs: a kernel shaped by the same photons it sums leans on their noise, which lost 0.6% of
//! the constructed distribution's interior energy after 16 passes and 1.1% of caustic-glass's
//! caustic, and which averaging passes does not remove. Owns that sum; must not trace rays.

use super::super::classic::{PhotonReader, power_of};
use super::super::{Query, Receiver, Scratch, to_irradiance, weighed_power};
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
    /// map's spatial order, offset by the pass), at full power. The shapes cost what a pass's
    /// own would and are independent of the photons they spread.
    OnePass,
    /// Every photon of the N passes at 1/N of its power: shapes from N times the photons,
    /// sharper where edges are faint, at N + 1 times the gradient pass and N times the
    /// tensor's scan.
    All,
}

/// Gives a map that [`ShapedBy`] sums its leaf sums (powers, leaf normals and moments, no
/// gradients), unless it holds a field already.
pub fn prepare_summed(map: &mut PhotonMap) {
    if map.leaf_sums().is_none() {
        let field = crate::photon::map::GradientField::leaf_sums_of(map);
        map.set_gradient_field(field);
    }
}

/// The map that shapes a pass's kernels, from the earlier passes' photons (`(pass, photons)`,
/// in any order): its density is one pass's whichever `photons` it keeps. `None` when there
/// is no earlier pass.
pub fn history_map(passes: &[(u64, &[Photon])], photons: HistoryPhotons) -> Option<PhotonMap> {
    let n = passes.len() as u64;
    if n == 0 {
        return None;
    }
    let (stride, scale) = match photons {
        HistoryPhotons::OnePass => (n, 1.0),
        HistoryPhotons::All => (1, 1.0 / n as f32),
    };
    let kept: Vec<Photon> = (passes.iter())
        .flat_map(|&(pass, photons)| {
            // Pass p keeps slots p, p + n, ...: the passes keep interleaved strata.
            let offset = (pass % stride) as usize;
            photons.iter().skip(offset).step_by(stride as usize)
        })
        .map(|p| Photon::new(p.position(), p.power() * scale, p.direction(), p.normal()))
        .collect();
    let emitted = kept.len() as u64;
    Some(PhotonMap::build(kept, emitted))
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
        let (tensor, _) = self.estimate.analyse(self.analysis, query, scratch);
        (self.estimate).photon_by_photon(&tensor, map, query, |p| weighed_power(p, receiver))
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
        let (tensor, _) = self.analyse(analysis, query, scratch);
        let Some(field) = map.leaf_sums() else {
            return self.photon_by_photon(&tensor, map, query, power_of);
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

    /// The kernel `tensor` shapes at the query, summed over `map`'s photons within `r` on the
    /// query's surface one by one, each weighed by `weigh`.
    fn photon_by_photon(
        &self,
        tensor: &DiffusionTensor,
        map: &PhotonMap,
        query: &Query,
        weigh: impl Fn(&crate::photon::PhotonAttributes) -> DVec3,
    ) -> Vec3 {
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
                    sum += kernel.weight(metric.distance(d)) * weigh(photon);
                }
            });
        to_irradiance(sum * (tensor.plane_normalisation() / r2))
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
        // Four consecutive passes of the same photons: their offsets cover every slot once.
        let passes: Vec<(u64, &[Photon])> = (7..11).map(|p| (p, photons.as_slice())).collect();
        let thinned = history_map(&passes, HistoryPhotons::OnePass).unwrap();
        assert_eq!(thinned.len(), photons.len());
        assert!((power(&thinned) - one).abs().max_element() < 1e-3 * one.max_element());
        let all = history_map(&passes, HistoryPhotons::All).unwrap();
        assert_eq!(all.len(), 4 * photons.len());
        assert!((power(&all) - one).abs().max_element() < 1e-3 * one.max_element());
        assert!(history_map(&[], HistoryPhotons::OnePass).is_none());
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
            let one_by_one = d.photon_by_photon(&tensor, &map, &query, power_of);
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
}
