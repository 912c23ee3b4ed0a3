//! Precomputed irradiance for final gathering (Christensen, "Faster photon map global
//! illumination", JGT 1999; Jensen, *Realistic Image Synthesis Using Photon Mapping* §7.6).
//! Owns the table of irradiance values at a subset of a global map's photons, its own kd-tree
//! over them, and the lookup a gather ray makes; must not change the photon map, its tree, or
//! the k-NN estimate it is computed with (it only calls [`RadianceEstimate::irradiance`]).
//!
//! Building: one photon in `stride` of the map, chosen by a hash of its index in tracing
//! order (a uniform random thinning, whatever regularity that order has: a path's photons
//! are consecutive), gets the global estimate at its position with its stored normal, once,
//! in parallel. Not every `stride`-th tree slot: the order of the photons inside a kd-tree
//! leaf follows the build's partitioning, which a rounding difference reshuffles (the same
//! scene at another scale picked another subset, a 5–7% different image), while the tracing
//! index is the same for the same photons, and a map saved and loaded keeps it. Each value depends only on the
//! map, the estimate and the photon (the k-NN estimate is the same on any thread; see
//! [`super::classic`]), and the values are collected in slot order, so the table, and every
//! image made with it, is the same whatever the thread count.
//!
//! Lookup: the nearest of the [`LOOKUP_K`] nearest points within the search radius whose normal
//! agrees with the query's (`n_i · n ≥` [`NORMAL_AGREEMENT_MIN_COS`], the rule every estimate
//! uses). A final-gather ray then costs one small k-nearest query instead of a `global_k`
//! estimate. When no point agrees (a surface holding fewer than about `stride` photons, the
//! far side of a thin wall, a corner) the lookup answers `None` and the caller runs the full
//! estimate: answering zero would darken exactly the small and thin surfaces a sparse table
//! misses, while the full estimate there costs no more than the per-ray estimate always did.
//!
//! What it measures: irradiance of every photon in the map. A final-gathering render's global
//! map holds direct photons as well (`MapKind::Global { with_direct: true }`), so this is the
//! total irradiance `E` at the point, and a gather ray landing on a diffuse surface of albedo
//! `ρ` sees the radiance `ρ/π · E` it saw with the per-ray estimate.

use super::{NORMAL_AGREEMENT_MIN_COS, Query, RadianceEstimate, Scratch};
use crate::photon::{KdTree, PhotonMap};
use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

/// Nearest table points a lookup considers for one whose normal agrees.
pub const LOOKUP_K: usize = 8;

/// Default stride (`--irradiance-stride`): irradiance at every 4th photon, as Christensen did.
pub const DEFAULT_STRIDE: usize = 4;

/// Photons estimated per progress-bar tick.
const CHUNK: usize = 1024;

/// Whether the photon traced `source`-th is one of the table's (one in `stride`).
fn chosen(source: u32, stride: usize) -> bool {
    stride == 1 || crate::sampling::mix(0x7AB1_E000, source as u64).is_multiple_of(stride as u64)
}

/// Irradiance precomputed at a subset of a photon map's photons.
#[derive(Clone, Debug, Default)]
pub struct PrecomputedIrradiance {
    tree: KdTree,
    /// Normal and irradiance of the point in each slot of `tree`.
    points: Vec<(Vec3, Vec3)>,
    /// Squared search radius of a lookup.
    max_dist2: f32,
}

impl PrecomputedIrradiance {
    /// The table of one photon in `stride` of `map` (`stride ≥ 1`; see the module notes), each
    /// with `estimate`'s irradiance at the photon; lookups search within `max_radius` (`None`:
    /// anywhere). `progress` gets the number of photons to estimate as its length, and
    /// advances by each one estimated.
    pub fn build(
        map: &PhotonMap,
        estimate: &dyn RadianceEstimate,
        stride: usize,
        max_radius: Option<f32>,
        progress: &ProgressBar,
    ) -> Self {
        assert!(stride >= 1, "stride must be at least 1");
        let tree = map.tree();
        let slots: Vec<u32> = (0..map.len())
            .filter(|&s| chosen(tree.source_index(s), stride))
            .map(|s| s as u32)
            .collect();
        progress.set_length(slots.len() as u64);
        let mut estimated: Vec<(Vec3, Vec3, Vec3)> = Vec::new();
        slots
            .par_chunks(CHUNK)
            .map_init(Scratch::default, |scratch, chunk| {
                let out: Vec<(Vec3, Vec3, Vec3)> = chunk
                    .iter()
                    .map(|&slot| {
                        let photon = map.photon(slot);
                        let query = Query {
                            position: photon.position(),
                            normal: photon.normal(),
                        };
                        let e = estimate.irradiance(map, &query, scratch);
                        (query.position, query.normal, e)
                    })
                    .collect();
                progress.inc(chunk.len() as u64);
                out
            })
            .collect::<Vec<_>>()
            .into_iter()
            .for_each(|c| estimated.extend(c));
        let positions: Vec<Vec3> = estimated.iter().map(|p| p.0).collect();
        let tree = KdTree::build(&positions);
        drop(positions);
        let points = (0..tree.len())
            .map(|s| {
                let (_, n, e) = estimated[tree.source_index(s) as usize];
                (n, e)
            })
            .collect();
        let max_dist2 = max_radius.map_or(f32::INFINITY, |r| r * r);
        Self {
            tree,
            points,
            max_dist2,
        }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The irradiance of the nearest table point whose normal agrees with `query`'s, `None`
    /// when none of the [`LOOKUP_K`] nearest within the search radius does (see the module
    /// notes: the caller then runs the full estimate).
    pub fn lookup(&self, query: &Query, scratch: &mut Scratch) -> Option<Vec3> {
        let found = &mut scratch.neighbours;
        self.tree
            .k_nearest(query.position, LOOKUP_K, self.max_dist2, found);
        let mut best: Option<(f32, u32)> = None;
        for n in found.as_slice() {
            let (normal, _) = self.points[n.slot as usize];
            if normal.dot(query.normal) < NORMAL_AGREEMENT_MIN_COS {
                continue;
            }
            // Ties broken by slot, so the answer never depends on the order found.
            if best.is_none_or(|b| (n.dist2, n.slot) < b) {
                best = Some((n.dist2, n.slot));
            }
        }
        best.map(|(_, slot)| self.points[slot as usize].1)
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.tree.heap_bytes() + self.points.capacity() * size_of::<(Vec3, Vec3)>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::{KnnEstimate, RadialKernel};
    use crate::photon::Photon;

    fn plane(n: usize) -> PhotonMap {
        let photons = (0..n)
            .map(|i| {
                let t = i as f32 * 0.618_034;
                Photon::new(
                    Vec3::new(t.fract(), (i as f32 / n as f32).fract(), 0.0),
                    Vec3::ONE,
                    -Vec3::Z,
                    Vec3::Z,
                )
            })
            .collect();
        PhotonMap::build(photons, n as u64)
    }

    #[test]
    fn a_stride_keeps_one_photon_in_n_and_lookups_respect_normals() {
        let map = plane(4000);
        let est = KnnEstimate::new(RadialKernel::Constant, 20, None);
        let bar = ProgressBar::hidden();
        let table = PrecomputedIrradiance::build(&map, &est, 4, Some(0.2), &bar);
        // One in 4, chosen at random: 1000 ± 27.
        assert!((900..1100).contains(&table.len()), "{}", table.len());
        assert_eq!(bar.position(), table.len() as u64);
        assert_eq!(bar.length(), Some(table.len() as u64));
        let every = PrecomputedIrradiance::build(&map, &est, 1, Some(0.2), &bar);
        assert_eq!(every.len(), 4000);
        let mut scratch = Scratch::default();
        let up = Query {
            position: Vec3::new(0.5, 0.5, 0.0),
            normal: Vec3::Z,
        };
        assert!(table.lookup(&up, &mut scratch).is_some());
        // The far side of the plane, and a point beyond the search radius, find nothing.
        let down = Query {
            normal: -Vec3::Z,
            ..up
        };
        assert_eq!(table.lookup(&down, &mut scratch), None);
        let far = Query {
            position: Vec3::new(0.5, 0.5, 1.0),
            ..up
        };
        assert_eq!(table.lookup(&far, &mut scratch), None);
    }
}
