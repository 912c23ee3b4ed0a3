//! The gradient pass (Eq. 6): the gradient of the fixed-radius Epanechnikov estimate at every
//! photon, `∇L(x) = 4/(π r_g⁴) Σ (x_i − x) Φ_i` over the photons within `r_g` whose normal
//! agrees with the photon's own. Owns that pass only; must not build tensors or estimates.
//!
//! The scalar photon power `Φ_i` is the mean of the three channels: it is linear (so the
//! dimensionless contrast, which divides by an estimate made the same way, is colour-neutral)
//! and does not favour green as luminance would. `f_r` is left out, as in the rest of the
//! estimates. Gradients are summed in f64; a gradient too large for f32 keeps its direction and
//! is clamped in length.
//!
//! Speed: the sum is linear in the photons, so a kd-tree node whose box lies wholly inside the
//! disc and whose photons' normals all agree with the query's contributes
//! `Σ (x_i − c) Φ_i + (c − x) Σ Φ_i` from sums kept per node (`NodeSums`) instead of photon
//! by photon. Only nodes that straddle the disc's rim are opened, so a photon's cost grows with
//! the rim, not with the number of photons inside: dense caustics, where a disc holds tens of
//! thousands of photons, no longer make the pass quadratic. The photons summed are exactly the
//! ones a photon-by-photon search would find (the box tests have margins on the safe side and
//! the rim's photons are tested like a radius search does). The result does not depend on the
//! number of threads: each photon's sum is made by one thread in a fixed node order.

use super::super::{NORMAL_AGREEMENT_MIN_COS, power_f64};
use crate::photon::kdtree::LEAF_SIZE;
use crate::photon::map::GradientField;
use crate::photon::{KdTree, PhotonAttributes, PhotonMap};
use glam::{DVec3, Vec3};
use rayon::prelude::*;
use std::f64::consts::PI;

/// Scalar power of a photon for the structure analysis: the channel mean.
#[inline]
pub fn scalar_power(photon: &crate::photon::Photon) -> f64 {
    let p = power_f64(photon);
    (p.x + p.y + p.z) / 3.0
}

#[inline]
fn scalar_power_of(attributes: &PhotonAttributes) -> f64 {
    channel_sum(attributes) / 3.0
}

/// Three times the scalar power: the node sums and leaf scans add this, and the pass divides
/// by three once at the end instead of per photon.
#[inline]
fn channel_sum(attributes: &PhotonAttributes) -> f64 {
    let p = attributes.power().as_dvec3();
    p.x + p.y + p.z
}

/// The gradient at every photon, in tree order, computed in parallel.
///
/// # Panics
/// If `radius` is not positive and finite.
pub fn compute_gradients(map: &PhotonMap, radius: f32) -> Vec<Vec3> {
    compute_site_gradients(map, radius, None)
}

/// The gradient at the photons whose `weights` entry is positive (all of them for `None`), in
/// tree order, zero elsewhere; computed in parallel, the same whatever the thread count.
///
/// # Panics
/// If `radius` is not positive and finite, or `weights` is not one per photon.
pub fn compute_site_gradients(map: &PhotonMap, radius: f32, weights: Option<&[f32]>) -> Vec<Vec3> {
    assert!(
        radius > 0.0 && radius.is_finite(),
        "gradient radius must be positive, got {radius}"
    );
    if let Some(w) = weights {
        assert_eq!(w.len(), map.len(), "one site weight per photon");
    }
    let sums = NodeSums::build(map);
    // The sums are of channel sums, three times the scalar power.
    let scale = 4.0 / (3.0 * PI * (radius as f64).powi(4));
    let tree = map.tree();
    // Each leaf writes its own run of the result (leaves own contiguous slots), so there is
    // no per-leaf vector to gather and copy.
    let mut gradients = vec![Vec3::ZERO; map.len()];
    let mut runs = Vec::with_capacity(tree.node_end() - tree.leaf_base());
    let mut rest = gradients.as_mut_slice();
    for leaf in tree.leaf_base()..tree.node_end() {
        let slots = tree.node_slots(leaf);
        let (run, after) = std::mem::take(&mut rest).split_at_mut(slots.len());
        rest = after;
        let sites = match weights {
            None => full_mask(slots.len()),
            Some(w) => slots
                .clone()
                .enumerate()
                .filter(|&(_, s)| w[s] > 0.0)
                .fold(0u32, |m, (i, _)| m | (1 << i)),
        };
        if sites != 0 {
            runs.push((leaf, sites, run));
        }
    }
    runs.into_par_iter().with_min_len(16).for_each_init(
        Vec::new,
        |sums_of_leaf, (leaf, sites, run)| {
            sums.leaf_sums(map, leaf, sites, radius, sums_of_leaf);
            let mut bits = sites;
            for &sum in sums_of_leaf.iter() {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                run[i] = to_f32_direction_kept(sum * scale);
            }
        },
    );
    gradients
}

/// The gradient pass: gradients at radius `radius`, on the sites thinned for `thinning` =
/// (smoothing radius, sites per smoothing disc) ([`super::sites`]; `None`: every photon),
/// stored in the map as its [`GradientField`]. The diffusion estimate's `prepare` runs it
/// (`DiffusionEstimate::gradient_pass`); call that yourself to time it as a phase of its own.
pub fn gradient_pass(map: &mut PhotonMap, radius: f32, thinning: Option<(f32, f64)>) {
    let weights = match thinning {
        Some((rho, sites)) => super::sites::site_weights(map, rho, sites),
        None => vec![1.0; map.len()],
    };
    let gradients = compute_site_gradients(map, radius, thinning.map(|_| weights.as_slice()));
    let field = GradientField::new(map, &gradients, weights, radius, thinning);
    map.set_gradient_field(field);
}

/// The photon-by-photon sum `Σ (x_i − x) Φ_i` (unscaled), for tests of the node sums.
pub fn brute_force_sum(map: &PhotonMap, slot: u32, radius: f32) -> DVec3 {
    let x = map.position(slot);
    let normal = map.attributes(slot).normal();
    let mut sum = DVec3::ZERO;
    map.tree().for_each_within(x, radius * radius, |other, _| {
        let a = map.attributes(other);
        if a.normal().dot(normal) >= NORMAL_AGREEMENT_MIN_COS {
            sum += (map.position(other) - x).as_dvec3() * scalar_power_of(a);
        }
    });
    sum
}

/// What a kd-tree node holds, summed: enough to add all of its photons to a gradient at once.
#[derive(Clone, Copy, Debug)]
struct NodeSum {
    /// Tight box of the node's photons (`lower > upper` when it has none).
    lower: Vec3,
    upper: Vec3,
    /// `Σ Φ_i`.
    power: f64,
    /// `Σ (x_i − c) Φ_i` about the box centre `c` (small numbers, so no cancellation).
    moment: DVec3,
    /// Unit mean direction of the photons' normals, and the largest angle (radians) between it
    /// and any of them: a cone holding every normal.
    axis: Vec3,
    spread: f32,
}

impl NodeSum {
    const EMPTY: Self = Self {
        lower: Vec3::INFINITY,
        upper: Vec3::NEG_INFINITY,
        power: 0.0,
        moment: DVec3::ZERO,
        axis: Vec3::Z,
        spread: std::f32::consts::PI,
    };

    fn centre(&self) -> DVec3 {
        (self.lower.as_dvec3() + self.upper.as_dvec3()) * 0.5
    }

    fn of_slots(map: &PhotonMap, slots: std::ops::Range<usize>) -> Self {
        if slots.is_empty() {
            return Self::EMPTY;
        }
        let (mut lower, mut upper, mut normals) = (Vec3::INFINITY, Vec3::NEG_INFINITY, Vec3::ZERO);
        for s in slots.clone() {
            let p = map.position(s as u32);
            lower = lower.min(p);
            upper = upper.max(p);
            normals += map.attributes(s as u32).normal();
        }
        let mut node = Self {
            lower,
            upper,
            axis: normals.normalize_or_zero(),
            spread: 0.0,
            ..Self::EMPTY
        };
        let c = node.centre();
        for s in slots {
            let a = map.attributes(s as u32);
            let phi = channel_sum(a);
            node.power += phi;
            node.moment += (map.position(s as u32).as_dvec3() - c) * phi;
            node.spread = node.spread.max(angle_between(node.axis, a.normal()));
        }
        node
    }

    fn merge(left: &Self, right: &Self) -> Self {
        if left.upper.x < left.lower.x {
            return *right;
        }
        if right.upper.x < right.lower.x {
            return *left;
        }
        let mut node = Self {
            lower: left.lower.min(right.lower),
            upper: left.upper.max(right.upper),
            power: left.power + right.power,
            axis: (left.axis * left.power as f32 + right.axis * right.power as f32)
                .normalize_or_zero(),
            ..Self::EMPTY
        };
        if node.axis == Vec3::ZERO {
            node.axis = (left.axis + right.axis).normalize_or_zero();
        }
        let c = node.centre();
        node.moment = left.moment
            + (left.centre() - c) * left.power
            + right.moment
            + (right.centre() - c) * right.power;
        // Each child's cone fits in a cone about the new axis widened by the angle between axes.
        node.spread = (angle_between(node.axis, left.axis) + left.spread)
            .max(angle_between(node.axis, right.axis) + right.spread)
            .min(std::f32::consts::PI);
        node
    }
}

/// Angle between two unit vectors (π when either is zero), never below the true angle by more
/// than float rounding; the cone test below keeps a margin far above that.
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a == Vec3::ZERO || b == Vec3::ZERO {
        return std::f32::consts::PI;
    }
    a.dot(b).clamp(-1.0, 1.0).acos()
}

/// Per-node sums over a photon map's kd-tree, indexed by node number (see
/// [`KdTree::leaf_base`]). About 88 bytes per node, 1/7 of a node per photon: freed after the
/// pass.
struct NodeSums<'a> {
    tree: &'a KdTree,
    nodes: Vec<NodeSum>,
    /// Channel sum of the photon in each slot, for the leaf scan without decoding.
    powers: Vec<f64>,
    /// The normal every photon of leaf `j` shares, if they all share one (decoded here once,
    /// not per scan).
    leaf_normals: Vec<Option<Vec3>>,
}

/// Largest angle between a node's cone and the query normal for the whole node to agree: the
/// normal test's 60°, less a margin far above the rounding of `acos` and the dot products.
const AGREEMENT_ANGLE: f32 = std::f32::consts::FRAC_PI_3 - 1e-3;
/// Relative margins of the box tests. The tests are made in f32 with the operations of a
/// photon's own distance test, in its order, so by the monotonicity of rounding a box's near
/// and far distances already bound every computed photon distance; the margins are a second
/// guard, cheap because they only move a few boxes from skipped or whole to opened.
const SKIP_MARGIN: f32 = 1.0 + 1e-5;
const TAKE_MARGIN: f32 = 1.0 - 1e-5;

impl<'a> NodeSums<'a> {
    fn build(map: &'a PhotonMap) -> Self {
        let tree = map.tree();
        let (leaf_base, end) = (tree.leaf_base(), tree.node_end());
        let mut nodes = vec![NodeSum::EMPTY; end];
        nodes[leaf_base..end]
            .par_iter_mut()
            .enumerate()
            .with_min_len(64)
            .for_each(|(leaf, sum)| {
                *sum = NodeSum::of_slots(map, tree.node_slots(leaf_base + leaf))
            });
        // Level by level towards the root; each level's nodes are independent.
        let mut level = leaf_base / 2;
        while level >= 1 {
            let (upper, lower) = nodes.split_at_mut(2 * level);
            upper[level..2 * level]
                .par_iter_mut()
                .enumerate()
                .with_min_len(256)
                .for_each(|(i, sum)| {
                    *sum = NodeSum::merge(&lower[2 * i], &lower[2 * i + 1]);
                });
            level /= 2;
        }
        let powers = (0..map.len() as u32)
            .into_par_iter()
            .with_min_len(4096)
            .map(|s| channel_sum(map.attributes(s)))
            .collect();
        let leaf_normals = crate::photon::map::leaf_normals(map);
        Self {
            tree,
            nodes,
            powers,
            leaf_normals,
        }
    }

    /// `Σ (x_i − x) Φ_i` for the photons of the leaf `leaf` whose bits are set in `sites`, into
    /// `out` (one per such photon, in slot order). Dual-tree: a node wholly within `radius`
    /// of every one of them, with normals agreeing with all of theirs, is added once for all
    /// of them; nodes straddling the rim of some of them are opened down to leaves, which each
    /// photon tests on its own.
    fn leaf_sums(
        &self,
        map: &PhotonMap,
        leaf: usize,
        sites: u32,
        radius: f32,
        out: &mut Vec<DVec3>,
    ) {
        out.clear();
        let slots = self.tree.node_slots(leaf);
        let group = &self.nodes[leaf];
        if slots.is_empty() || sites == 0 {
            return;
        }
        let queries: Vec<Query> = slots
            .clone()
            .enumerate()
            .filter(|&(i, _)| sites & (1 << i) != 0)
            .map(|(_, s)| Query {
                x: map.position(s as u32),
                normal: map.attributes(s as u32).normal(),
                radius2: radius * radius,
            })
            .collect();
        out.resize(queries.len(), DVec3::ZERO);
        let mut shared = Shared {
            centre: group.centre(),
            power: 0.0,
            moment: DVec3::ZERO,
        };
        let all = full_mask(queries.len());
        self.visit_group(map, 1, group, &queries, all, &mut shared, out);
        for (sum, q) in out.iter_mut().zip(&queries) {
            *sum += shared.moment + (shared.centre - q.x.as_dvec3()) * shared.power;
        }
    }

    /// Walks `node` for the photons of the group whose bits are set in `active` (a leaf holds
    /// at most 20 photons, so a `u32` names them).
    #[allow(clippy::too_many_arguments)]
    fn visit_group(
        &self,
        map: &PhotonMap,
        node: usize,
        group: &NodeSum,
        queries: &[Query],
        mut active: u32,
        shared: &mut Shared,
        out: &mut [DVec3],
    ) {
        let n = &self.nodes[node];
        if n.upper.x < n.lower.x {
            return;
        }
        let r2 = queries[0].radius2;
        let (gl, gu, nl, nu) = (group.lower, group.upper, n.lower, n.upper);
        let near = (nl - gu).max(gl - nu).max(Vec3::ZERO);
        if near.length_squared() > r2 * SKIP_MARGIN {
            return;
        }
        let everyone = active == full_mask(queries.len());
        let far = (nu - gl).max(gu - nl);
        if everyone
            && far.length_squared() <= r2 * TAKE_MARGIN
            && angle_between(n.axis, group.axis) + n.spread + group.spread <= AGREEMENT_ANGLE
        {
            shared.power += n.power;
            shared.moment += n.moment + (n.centre() - shared.centre) * n.power;
            return;
        }
        // Each photon on its own: drop those the node is clear of or wholly inside. A node wider
        // than a disc is wholly inside none, and its children sort the photons out as well, so
        // that work is only done once nodes are small (it is most of the pass otherwise).
        let is_leaf = node >= self.tree.leaf_base();
        let wide = (nu - nl).length_squared() > 4.0 * r2;
        let mut bits = if wide && !is_leaf { 0 } else { active };
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            match classify(n, &queries[i]) {
                Cover::None => active &= !(1 << i),
                Cover::Whole => {
                    out[i] += n.moment + (n.centre() - queries[i].x.as_dvec3()) * n.power;
                    active &= !(1 << i);
                }
                Cover::Part => {}
            }
        }
        if active == 0 {
            return;
        }
        if is_leaf {
            let mut bits = active;
            while bits != 0 {
                let i = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                self.scan_leaf(map, node, &queries[i], &mut out[i]);
            }
            return;
        }
        self.visit_group(map, 2 * node, group, queries, active, shared, out);
        self.visit_group(map, 2 * node + 1, group, queries, active, shared, out);
    }

    /// Adds the photons of leaf `node` within the query's radius whose normals agree.
    fn scan_leaf(&self, map: &PhotonMap, node: usize, q: &Query, sum: &mut DVec3) {
        let (xs, ys, zs) = self.tree.coordinates();
        if let Some(normal) = self.leaf_normals[node - self.tree.leaf_base()] {
            // One surface: one normal test, then a straight loop over the leaf's arrays.
            if normal.dot(q.normal) < NORMAL_AGREEMENT_MIN_COS {
                return;
            }
            *sum += self.scan_one_surface(self.tree.node_slots(node), q);
            return;
        }
        let (mut last_code, mut last_agrees) = (u32::MAX, false);
        // Summed in a local so it stays in registers rather than going through `sum` each time.
        let mut local = DVec3::ZERO;
        for other in self.tree.node_slots(node) {
            let d = Vec3::new(xs[other] - q.x.x, ys[other] - q.x.y, zs[other] - q.x.z);
            let a = map.attributes(other as u32);
            // Photons of one leaf mostly share a surface: test each normal code once.
            let code = u32::from(a.normal_code());
            if code != last_code {
                last_code = code;
                last_agrees = a.normal().dot(q.normal) >= NORMAL_AGREEMENT_MIN_COS;
            }
            // The radius search's distance, operation for operation; a weight rather than a
            // branch, since about half of a rim leaf's photons are inside.
            let inside = d.x * d.x + d.y * d.y + d.z * d.z <= q.radius2;
            let weight = if inside && last_agrees {
                channel_sum(a)
            } else {
                0.0
            };
            local += d.as_dvec3() * weight;
        }
        *sum += local;
    }

    /// The sum over the photons of `slots` (one leaf, whose normals all agree with the
    /// query's) within the query's radius, by [`sum_within`] in whole groups of four: a leaf's
    /// last group runs on into the next leaf's photons, which the lane mask leaves out; the
    /// tree's last leaf, which has no next one, goes through a padded copy.
    #[inline]
    fn scan_one_surface(&self, slots: std::ops::Range<usize>, q: &Query) -> DVec3 {
        let (xs, ys, zs) = self.tree.coordinates();
        let n = slots.len();
        let end = slots.start + n.div_ceil(4) * 4;
        if end <= xs.len() {
            return sum_within(
                [
                    &xs[slots.start..end],
                    &ys[slots.start..end],
                    &zs[slots.start..end],
                ],
                &self.powers[slots.start..end],
                n,
                q,
            );
        }
        // The tree's last leaf: its last group would run off the arrays.
        let mut padded = [[0.0f32; LEAF_SIZE + 3]; 3];
        let mut powers = [0.0f64; LEAF_SIZE + 3];
        for (i, s) in slots.clone().enumerate() {
            padded[0][i] = xs[s];
            padded[1][i] = ys[s];
            padded[2][i] = zs[s];
            powers[i] = self.powers[s];
        }
        let len = n.div_ceil(4) * 4;
        let [px, py, pz] = &padded;
        sum_within([&px[..len], &py[..len], &pz[..len]], &powers[..len], n, q)
    }

    /// `Σ (x_i − x) Φ_i` over the photons within `radius` of the photon in `slot` whose normals
    /// agree with its own, one photon at a time (for tests of the dual walk).
    #[cfg(test)]
    fn sum_at(&self, map: &PhotonMap, slot: u32, radius: f32) -> DVec3 {
        let query = Query {
            x: map.position(slot),
            normal: map.attributes(slot).normal(),
            radius2: radius * radius,
        };
        let mut sum = DVec3::ZERO;
        if !self.tree.is_empty() {
            self.visit(map, 1, &query, &mut sum);
        }
        sum / 3.0
    }

    #[cfg(test)]
    fn visit(&self, map: &PhotonMap, node: usize, q: &Query, sum: &mut DVec3) {
        let n = &self.nodes[node];
        match classify(n, q) {
            Cover::None => {}
            Cover::Whole => *sum += n.moment + (n.centre() - q.x.as_dvec3()) * n.power,
            Cover::Part if node >= self.tree.leaf_base() => self.scan_leaf(map, node, q, sum),
            Cover::Part => {
                self.visit(map, 2 * node, q, sum);
                self.visit(map, 2 * node + 1, q, sum);
            }
        }
    }
}

/// `Σ (x_i − x) Φ_i` over the first `n` photons of the arrays (whose length is a multiple of
/// four) within the query's radius. Four independent partial sums per axis, because one
/// running sum is a chain of dependent adds that neither vectorises nor pipelines; a mask and
/// not a branch, because about half of a rim leaf's photons are inside. Lanes past `n` are
/// masked out, so the caller may pass the start of the next leaf there.
#[inline(always)]
fn sum_within([xs, ys, zs]: [&[f32]; 3], powers: &[f64], n: usize, q: &Query) -> DVec3 {
    let mut acc = [[0.0f64; 4]; 3];
    let (qx, qy, qz, r2) = (q.x.x, q.x.y, q.x.z, q.radius2);
    let groups = xs
        .chunks_exact(4)
        .zip(ys.chunks_exact(4))
        .zip(zs.chunks_exact(4))
        .zip(powers.chunks_exact(4));
    for (first, (((x, y), z), w)) in (0..).step_by(4).zip(groups) {
        for lane in 0..4 {
            let (dx, dy, dz) = (x[lane] - qx, y[lane] - qy, z[lane] - qz);
            let take = (first + lane < n) & (dx * dx + dy * dy + dz * dz <= r2);
            // Bits rather than a select, which the compiler makes a branch.
            let w = f64::from_bits(w[lane].to_bits() & u64::from(take).wrapping_neg());
            acc[0][lane] += dx as f64 * w;
            acc[1][lane] += dy as f64 * w;
            acc[2][lane] += dz as f64 * w;
        }
    }
    let [sx, sy, sz] = acc.map(|[a, b, c, d]| (a + b) + (c + d));
    DVec3::new(sx, sy, sz)
}

/// How a node's photons stand towards one query's disc.
enum Cover {
    /// None of them is inside (or the node is empty).
    None,
    /// All of them are inside and their normals agree with the query's: add the node's sums.
    Whole,
    /// Open it.
    Part,
}

fn classify(n: &NodeSum, q: &Query) -> Cover {
    if n.upper.x < n.lower.x {
        return Cover::None;
    }
    let (x, lower, upper, r2) = (q.x, n.lower, n.upper, q.radius2);
    if (lower - x).max(x - upper).max(Vec3::ZERO).length_squared() > r2 * SKIP_MARGIN {
        return Cover::None;
    }
    if (x - lower).max(upper - x).length_squared() <= r2 * TAKE_MARGIN
        && angle_between(n.axis, q.normal) + n.spread <= AGREEMENT_ANGLE
    {
        return Cover::Whole;
    }
    Cover::Part
}

// A leaf's photons must fit the bits of one `u32`.
const _: () = assert!(crate::photon::kdtree::LEAF_SIZE <= 32);

fn full_mask(len: usize) -> u32 {
    if len >= 32 {
        u32::MAX
    } else {
        (1u32 << len) - 1
    }
}

/// Nodes added whole for a leaf's photons: `Σ Φ` and `Σ (x_i − centre) Φ_i`.
struct Shared {
    centre: DVec3,
    power: f64,
    moment: DVec3,
}

struct Query {
    x: Vec3,
    normal: Vec3,
    radius2: f32,
}

/// f64 → f32, scaling the whole vector down if a component would overflow.
fn to_f32_direction_kept(g: DVec3) -> Vec3 {
    if !g.is_finite() {
        return Vec3::ZERO;
    }
    let largest = g.abs().max_element();
    let limit = f32::MAX as f64 * 0.5;
    if largest > limit {
        (g * (limit / largest)).as_vec3()
    } else {
        g.as_vec3()
    }
}

#[cfg(test)]
mod tests;
