//! Precomputed irradiance for final gathering (Christensen, "Faster photon map global
//! illumination", JGT 1999; Jensen, *Realistic Image Synthesis Using Photon Mapping* §7.6),
//! and for a sparse global map shown directly ([`ShownIrradiance`]). Owns the tables of
//! irradiance values at a global map's photons, their own kd-trees over them, and the lookups
//! a gather ray or an eye hit makes; must not change the photon map, its tree, or the k-NN
//! estimate it is computed with (it only calls the estimate's irradiance).
//!
//! Building: one photon in `stride` of the map, chosen by a hash of its index in tracing
//! order (a uniform random thinning, whatever regularity that order has: a path's photons
//! are consecutive), gets the global estimate at its position with its stored normal, once,
//! in parallel. Not every `stride`-th tree slot: the order of the photons inside a kd-tree
//! leaf follows the build's partitioning, which a rounding difference reshuffles (the same
//! scene at another scale picked another subset, a 5–7% different image), while the tracing
//! index is the same for the same photons, and a map saved and loaded keeps it. Each value
//! depends only on the map, the estimate and the photon (the k-NN estimate is the same on any
//! thread; see [`super::classic`]), and the values are collected in slot order, so the table,
//! and every image made with it, is the same whatever the thread count.
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

use super::{KnnEstimate, NORMAL_AGREEMENT_MIN_COS, Query, RadianceEstimate, Scratch};
use crate::photon::{KdTree, PhotonMap};
use glam::Vec3;
use indicatif::ProgressBar;
use rayon::prelude::*;

/// Nearest table points a lookup considers for one whose normal agrees.
pub const LOOKUP_K: usize = 8;

/// Default stride (`--irradiance-stride`): irradiance at every 4th photon, as Christensen did.
pub const DEFAULT_STRIDE: usize = 4;

/// A directly shown global map is read through a [`ShownIrradiance`] table when the eye pass
/// would make more than this many estimates per photon (one a pixel): a sparse map (the floor
/// a glass object lights through itself holds a thousand photons) then costs an estimate a
/// photon and two nearest-site lookups a pixel instead of a `global_k` estimate a pixel.
pub const SHOWN_TABLE_QUERIES_PER_PHOTON: usize = 16;

/// How far from a table point of a shown map, in units of the radius its estimate averaged
/// over, a lookup may take its value.
pub const SHOWN_TABLE_REACH: f32 = 0.5;

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
    /// The point in each slot of `tree`.
    points: Vec<TablePoint>,
    /// Squared search radius of a lookup.
    max_dist2: f32,
    /// A half of a shown map's table: the nearest point within its own reach answers. Else
    /// (final gathering) only one of the [`LOOKUP_K`] nearest.
    nearest_in_reach: bool,
}

#[derive(Clone, Copy, Debug, Default)]
struct TablePoint {
    normal: Vec3,
    irradiance: Vec3,
    /// Squared distance within which the point may answer a lookup.
    reach2: f32,
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
        let max_dist2 = max_radius.map_or(f32::INFINITY, |r| r * r);
        progress.set_length(slots.len() as u64);
        Self::estimated_at(
            &slots,
            progress,
            max_dist2,
            false,
            |query, scratch| (estimate.irradiance(map, query, scratch), f32::INFINITY),
            map,
        )
    }

    /// The table of `value(query)` (irradiance and a lookup's squared reach) at each of the
    /// photons of `map` in `slots`, queried at its position with its normal.
    fn estimated_at(
        slots: &[u32],
        progress: &ProgressBar,
        max_dist2: f32,
        nearest_in_reach: bool,
        value: impl Fn(&Query, &mut Scratch) -> (Vec3, f32) + Sync,
        map: &PhotonMap,
    ) -> Self {
        let mut estimated: Vec<(Vec3, TablePoint)> = Vec::new();
        slots
            .par_chunks(CHUNK)
            .map_init(Scratch::default, |scratch, chunk| {
                let out: Vec<(Vec3, TablePoint)> = chunk
                    .iter()
                    .map(|&slot| {
                        let photon = map.photon(slot);
                        let query = Query {
                            position: photon.position(),
                            normal: photon.normal(),
                        };
                        let (irradiance, reach2) = value(&query, scratch);
                        let point = TablePoint {
                            normal: query.normal,
                            irradiance,
                            reach2,
                        };
                        (query.position, point)
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
        let points: Vec<TablePoint> = (0..tree.len())
            .map(|s| estimated[tree.source_index(s) as usize].1)
            .collect();
        // No lookup reaches farther than the farthest-reaching point.
        let reach2 = points.iter().map(|p| p.reach2).fold(0.0, f32::max);
        let max_dist2 = max_dist2.min(reach2);
        Self {
            tree,
            points,
            max_dist2,
            nearest_in_reach,
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
        let takes = |point: &TablePoint, dist2: f32| {
            point.normal.dot(query.normal) >= NORMAL_AGREEMENT_MIN_COS && dist2 <= point.reach2
        };
        let slot = if self.nearest_in_reach {
            self.tree
                .nearest_where(query.position, self.max_dist2, |slot, dist2| {
                    takes(&self.points[slot as usize], dist2)
                })?
                .slot
        } else {
            let found = &mut scratch.neighbours;
            self.tree
                .k_nearest(query.position, LOOKUP_K, self.max_dist2, found);
            // Ties broken by slot, so the answer never depends on the order found.
            found
                .as_slice()
                .iter()
                .filter(|n| takes(&self.points[n.slot as usize], n.dist2))
                .min_by_key(|n| (n.dist2.to_bits(), n.slot))?
                .slot
        };
        Some(self.points[slot as usize].irradiance)
    }

    /// Heap bytes held.
    pub fn heap_bytes(&self) -> usize {
        self.tree.heap_bytes() + self.points.capacity() * size_of::<TablePoint>()
    }
}

/// The table a sparse global map is read through where it is shown directly (see
/// [`SHOWN_TABLE_QUERIES_PER_PHOTON`]). Its photons are split at random into two halves; each
/// half's photons are the sites where the other half's estimate is stored (k/2 photons, at
/// twice the power: the estimate of the whole map over about the same radius). A lookup
/// averages the nearest site of each half.
///
/// Why not every photon with the whole map's estimate (Christensen's table at stride 1): a
/// random point's nearest photon is more likely one with a large empty cell around it, whose
/// estimate is low, so the lookups come out low on average: 0.85% on a uniform density at
/// k = 100, 9% at k = 10 (tested). With sites from one half and values from the other, which
/// site is nearest does not depend on the photons that make its value, and the lookup is as
/// unbiased as the estimate. A site answers within [`SHOWN_TABLE_REACH`] of the radius its
/// value averaged over: inside the photons that always holds, and past the edge of their
/// cloud, where a value would spread outwards, the lookup answers `None` and the caller runs
/// the estimate itself.
#[derive(Clone, Debug, Default)]
pub struct ShownIrradiance {
    halves: [PrecomputedIrradiance; 2],
}

impl ShownIrradiance {
    /// The two halves of `map`, chosen by a hash of each photon's tracing index (so the same
    /// whatever the tree's order), each with `estimate` at k/2 on the other half.
    pub fn build(map: &PhotonMap, estimate: &KnnEstimate, progress: &ProgressBar) -> Self {
        let tree = map.tree();
        let mut halves: [Vec<_>; 2] = Default::default();
        for slot in 0..map.len() as u32 {
            let half =
                crate::sampling::mix(0x5B1_7AB1E, u64::from(tree.source_index(slot as usize))) & 1;
            halves[half as usize].push(map.photon(slot));
        }
        let maps = halves.map(|photons| PhotonMap::build(photons, map.emitted));
        let half_estimate = estimate.with_k((estimate.k() / 2).max(2));
        let reach2 = SHOWN_TABLE_REACH * SHOWN_TABLE_REACH;
        progress.set_length(map.len() as u64);
        let table = |sites: &PhotonMap, values: &PhotonMap| {
            let slots: Vec<u32> = (0..sites.len() as u32).collect();
            PrecomputedIrradiance::estimated_at(
                &slots,
                progress,
                f32::INFINITY,
                true,
                |query, scratch| {
                    let (e, r2) = half_estimate.irradiance_and_radius2(values, query, scratch);
                    (2.0 * e, r2 * reach2)
                },
                sites,
            )
        };
        Self {
            halves: [table(&maps[0], &maps[1]), table(&maps[1], &maps[0])],
        }
    }

    /// The mean of the two halves' answers, `None` unless both answer.
    pub fn lookup(&self, query: &Query, scratch: &mut Scratch) -> Option<Vec3> {
        let a = self.halves[0].lookup(query, scratch)?;
        let b = self.halves[1].lookup(query, scratch)?;
        Some(0.5 * (a + b))
    }

    /// Sites in both halves.
    pub fn len(&self) -> usize {
        self.halves[0].len() + self.halves[1].len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
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
