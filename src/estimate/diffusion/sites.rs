//! Gradient sites: which photons carry a gradient, and what each one stands for. The
//! structure tensor of a query averages the gradients of the photons within the smoothing
//! radius `ρ`; a few hundred of them fix that average as well as tens of thousands do, since
//! gradients taken over discs of radius `r_g ≈ ρ/2` around neighbouring photons are almost the
//! same numbers. Where a smoothing disc would hold far more photons than that (a concentrated
//! caustic, or a radius much larger than the photon spacing), only every `m`-th photon (by a
//! hash of its slot, so the thinning is uniform in space and the same on every run and thread
//! count) gets a gradient, weighted `m` in the tensor's average. The gradient pass then costs
//! what the tensors need, not what the photon pile-up holds. Owns the choice of sites; must
//! not compute gradients or tensors.
//!
//! The local `m` comes from the photon density of the kd-tree node [`DENSITY_LEVELS`] above
//! each leaf (about 640 photons): the count of its photons on the photon's surface (normals
//! agreeing, as the estimates count them) over the area of the node's box's two largest
//! extents (the box of a patch of surface). A curved or folded patch has a larger box than
//! area, which only makes `m` smaller: thinning errs towards more sites.

use crate::estimate::NORMAL_AGREEMENT_MIN_COS;
use crate::photon::PhotonMap;
use glam::Vec3;
use rayon::prelude::*;

/// The default of the sites a smoothing disc should hold at least (in expectation) wherever
/// thinning applies (`--gradient-sites`).
pub const SITES_PER_SMOOTHING_DISC: f64 = 512.0;

/// Levels above a leaf of the node whose box gives the local density (2⁵ leaves of up to 20
/// photons: big enough for a steady count, small enough to follow a caustic's focus).
pub const DENSITY_LEVELS: u32 = 5;

/// The site weight of every photon in slot order: 0 for a photon without a gradient, `m ≥ 1`
/// for a site standing for `m` photons. All ones where no disc of radius `smoothing_radius`
/// would hold more than twice `sites_per_disc` photons.
pub fn site_weights(map: &PhotonMap, smoothing_radius: f32, sites_per_disc: f64) -> Vec<f32> {
    let tree = map.tree();
    let mut weights = vec![1.0f32; map.len()];
    if map.is_empty() || !(smoothing_radius > 0.0 && smoothing_radius.is_finite()) {
        return weights;
    }
    let depth = tree.leaf_base().trailing_zeros();
    let levels = DENSITY_LEVELS.min(depth);
    // The density nodes: one level of the tree, each owning a contiguous run of slots.
    let first = 1usize << (depth - levels);
    let disc = std::f64::consts::PI * (smoothing_radius as f64).powi(2);
    let (xs, ys, zs) = tree.coordinates();
    let mut runs = Vec::with_capacity(first);
    let mut rest = weights.as_mut_slice();
    let mut start = 0;
    for node in first..2 * first {
        let slots = tree.node_slots(node);
        debug_assert_eq!(slots.start, start);
        let (run, after) = std::mem::take(&mut rest).split_at_mut(slots.len());
        runs.push((slots.clone(), run));
        rest = after;
        start = slots.end;
    }
    runs.into_par_iter().for_each(|(slots, run)| {
        if slots.is_empty() {
            return;
        }
        let (mut lower, mut upper) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for s in slots.clone() {
            let p = Vec3::new(xs[s], ys[s], zs[s]);
            lower = lower.min(p);
            upper = upper.max(p);
        }
        // Photons count towards a photon's density only if they lie on its surface (as its
        // estimates count them): a bright sheet behind a thin wall must not thin the front.
        let mut surfaces: Vec<(u16, Vec3, usize)> = Vec::new();
        for s in slots.clone() {
            let a = map.attributes(s as u32);
            match surfaces
                .iter_mut()
                .find(|(code, ..)| *code == a.normal_code())
            {
                Some(entry) => entry.2 += 1,
                None => surfaces.push((a.normal_code(), a.normal(), 1)),
            }
        }
        let thinned: Vec<(u16, u32)> = surfaces
            .iter()
            .map(|&(code, normal, _)| {
                let agreeing = surfaces
                    .iter()
                    .filter(|(_, n, _)| n.dot(normal) >= NORMAL_AGREEMENT_MIN_COS)
                    .map(|(.., count)| count)
                    .sum();
                (
                    code,
                    thinning(agreeing, upper - lower, disc, sites_per_disc),
                )
            })
            .collect();
        if thinned.iter().all(|&(_, m)| m <= 1) {
            return;
        }
        for (w, slot) in run.iter_mut().zip(slots) {
            let code = map.attributes(slot as u32).normal_code();
            let m = thinned.iter().find(|(c, _)| *c == code).map_or(1, |e| e.1);
            *w = if m <= 1 {
                1.0
            } else if is_site(slot as u32, m) {
                m as f32
            } else {
                0.0
            };
        }
    });
    weights
}

/// `m` for `count` photons spread over a box of extent `extent`, for smoothing discs of area
/// `disc`: the expected photons per disc over `sites_per_disc`, rounded down, and never more
/// than the node's photons (so a node keeps about one site at least).
fn thinning(count: usize, extent: Vec3, disc: f64, sites_per_disc: f64) -> u32 {
    let mut e = extent.as_dvec3().to_array();
    e.sort_by(|a, b| b.total_cmp(a));
    let area = e[0] * e[1];
    let per_disc = if area > 0.0 {
        count as f64 * disc / area
    } else {
        f64::INFINITY
    };
    let m = (per_disc / sites_per_disc).floor();
    if m.is_nan() || m < 2.0 {
        1
    } else {
        m.min(count as f64).min(u32::MAX as f64) as u32
    }
}

/// Whether the photon in `slot` is a site when one in `m` is: a hash of the slot, uniform and
/// independent of the photons' order within a leaf.
#[inline]
pub fn is_site(slot: u32, m: u32) -> bool {
    let mut h = (slot as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    h ^= h >> 32;
    h = h.wrapping_mul(0xD6E8_FEB8_6659_FD93);
    h ^= h >> 32;
    h.is_multiple_of(m as u64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photon::Photon;

    fn grid_map(n: usize, side: f32) -> PhotonMap {
        let photons = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f32 + 0.5, (i / n) as f32 + 0.5);
                Photon::new(
                    Vec3::new(x * side / n as f32, y * side / n as f32, 0.0),
                    Vec3::ONE,
                    -Vec3::Z,
                    Vec3::Z,
                )
            })
            .collect();
        PhotonMap::build(photons, (n * n) as u64)
    }

    #[test]
    fn sparse_maps_keep_every_photon_and_dense_ones_keep_enough_sites_with_the_mass() {
        // 300² photons on a unit square: a disc of radius 0.01 holds ~28, one of 0.2 ~11,300.
        let map = grid_map(300, 1.0);
        assert!(
            site_weights(&map, 0.01, SITES_PER_SMOOTHING_DISC)
                .iter()
                .all(|&w| w == 1.0)
        );
        let weights = site_weights(&map, 0.2, SITES_PER_SMOOTHING_DISC);
        let sites = weights.iter().filter(|&&w| w > 0.0).count();
        assert!(sites < map.len() / 10, "{sites} sites");
        // Weighted, the sites stand for every photon (within the hash's sampling noise).
        let mass: f64 = weights.iter().map(|&w| w as f64).sum();
        assert!((mass / map.len() as f64 - 1.0).abs() < 0.03, "{mass}");
        // Every disc of radius 0.2 well inside the square holds the target, to within three
        // standard deviations of the hash's sampling noise.
        let tree = map.tree();
        for &(x, y) in &[(0.5, 0.5), (0.3, 0.7), (0.25, 0.25)] {
            let mut held = 0;
            tree.for_each_within(Vec3::new(x, y, 0.0), 0.04, |slot, _| {
                held += (weights[slot as usize] > 0.0) as usize;
            });
            let t = SITES_PER_SMOOTHING_DISC;
            assert!(held as f64 >= t - 3.0 * t.sqrt(), "{held} at {x},{y}");
        }
    }

    #[test]
    fn thinning_follows_the_local_density() {
        // A dense spot beside a sparse field: only the spot is thinned.
        let mut photons: Vec<Photon> = (0..200_000)
            .map(|i| {
                let t = i as f32 * 0.618_034;
                let (x, y) = (t.fract(), (i as f32 * 0.754_878).fract());
                Photon::new(
                    Vec3::new(0.5 + 0.02 * x, 0.5 + 0.02 * y, 0.0),
                    Vec3::ONE,
                    -Vec3::Z,
                    Vec3::Z,
                )
            })
            .collect();
        let sparse = grid_map(100, 1.0);
        photons.extend(sparse.photons());
        let map = PhotonMap::build(photons, 210_000);
        let weights = site_weights(&map, 0.01, SITES_PER_SMOOTHING_DISC);
        let (mut spot, mut field) = ((0usize, 0usize), (0usize, 0usize));
        for (slot, &w) in weights.iter().enumerate() {
            let p = map.position(slot as u32);
            let inside = (p.x - 0.51).abs() < 0.01 && (p.y - 0.51).abs() < 0.01;
            let counter = if inside { &mut spot } else { &mut field };
            counter.0 += 1;
            counter.1 += (w > 0.0) as usize;
        }
        assert!(spot.1 * 10 < spot.0, "spot {spot:?}");
        assert!(field.1 * 10 > field.0 * 9, "field {field:?}");
    }

    #[test]
    fn degenerate_boxes_do_not_divide_by_zero() {
        let t = SITES_PER_SMOOTHING_DISC;
        assert_eq!(thinning(640, Vec3::ZERO, 1.0, t), 640);
        assert_eq!(thinning(640, Vec3::new(1.0, 0.0, 0.0), 1.0, t), 640);
        assert_eq!(thinning(640, Vec3::ONE, 1e-9, t), 1);
        assert_eq!(thinning(0, Vec3::ONE, f64::NAN, t), 1);
    }
}
