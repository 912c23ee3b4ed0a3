//! A binary tree over the bounded lights (and each mesh emitter's triangles) that picks one in
//! proportion to a bound on what it can give a shading point: its power, its distance, the
//! cone of directions it emits into and how the point's normal faces it (the light-bounds
//! importance of Conty Estevez and Kulla, "Importance sampling of many lights with adaptive
//! tree splitting", 2018, as pbrt-v4 uses it). A pick's probability is exact and can be
//! worked out again for any leaf ([`LightTree::pmf`]), so a BSDF sample that finds a light
//! weighs itself against the pick as MIS needs. Owns the bounds, the build and the descent;
//! must not sample points on lights or trace rays.

use glam::Vec3;
use std::f32::consts::PI;

/// What bounds one light or a group of them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Power (a luminance-like weight, [`super::weight`]); the unit only has to agree
    /// between lights.
    pub phi: f32,
    /// Axis of the cone holding every emitting surface's normal (or a spot's axis).
    pub axis: Vec3,
    /// Cosine of that cone's half-angle (−1: every direction).
    pub cos_normals: f32,
    /// Cosine of the angle past the normals' cone within which light still leaves (0 for a
    /// Lambertian surface: light leaves up to 90° from its normal).
    pub cos_emission: f32,
    /// Whether light leaves both sides of a surface.
    pub two_sided: bool,
}

impl LightBounds {
    /// A light emitting every way from `lo`–`hi` (a point, a sphere).
    pub fn everywhere(lo: Vec3, hi: Vec3, phi: f32) -> Self {
        Self {
            lo,
            hi,
            phi,
            axis: Vec3::Z,
            cos_normals: -1.0,
            cos_emission: 0.0,
            two_sided: false,
        }
    }

    /// A flat emitter in `lo`–`hi` facing `normal`, Lambertian.
    pub fn flat(lo: Vec3, hi: Vec3, phi: f32, normal: Vec3, two_sided: bool) -> Self {
        Self {
            lo,
            hi,
            phi,
            axis: normal,
            cos_normals: 1.0,
            cos_emission: 0.0,
            two_sided,
        }
    }

    fn centre(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// Both: the box round both, the cone round both cones, the wider emission.
    fn union(&self, other: &Self) -> Self {
        if self.phi <= 0.0 {
            return *other;
        }
        if other.phi <= 0.0 {
            return *self;
        }
        let (axis, cos_normals) = cone_union(
            (self.axis, self.cos_normals),
            (other.axis, other.cos_normals),
        );
        Self {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: self.phi + other.phi,
            axis,
            cos_normals,
            cos_emission: self.cos_emission.min(other.cos_emission),
            two_sided: self.two_sided || other.two_sided,
        }
    }

    /// A bound on what these lights give the point `p` whose unit normal is `n` (zero: none;
    /// `Vec3::ZERO`: a point in a medium, which takes light from every side): power over the
    /// squared distance, times the cosines of the smallest angles the box allows, at the
    /// emitters' cone and at the receiver.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        let centre = self.centre();
        let half_diagonal = 0.5 * (self.hi - self.lo).length();
        // Inside or near the box the distance says nothing: a bound, not the light.
        let d2 = p
            .distance_squared(centre)
            .max(half_diagonal * half_diagonal)
            .max(f32::MIN_POSITIVE);
        let to_p = (p - centre).normalize_or_zero();
        let mut cos_w = self.axis.dot(to_p);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = sin_of(cos_w);
        // The cone of directions from `p` that the box fills.
        let inside = p.distance_squared(centre) <= half_diagonal * half_diagonal;
        let (sin_b, cos_b) = if inside || to_p == Vec3::ZERO {
            (0.0, -1.0)
        } else {
            let sin2 = half_diagonal * half_diagonal / p.distance_squared(centre);
            (sin2.sqrt(), (1.0 - sin2).max(0.0).sqrt())
        };
        // The angle from the normals' cone to `p`, less the box's spread.
        let sin_o = sin_of(self.cos_normals);
        let (sin_x, cos_x) = angle_less((sin_w, cos_w), (sin_o, self.cos_normals));
        let (_, cos_p) = angle_less((sin_x, cos_x), (sin_b, cos_b));
        if cos_p <= self.cos_emission {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if n != Vec3::ZERO {
            let cos_i = n.dot(-to_p).abs();
            let (_, cos_ip) = angle_less((sin_of(cos_i), cos_i), (sin_b, cos_b));
            importance *= cos_ip.max(0.0);
        }
        importance.max(0.0)
    }
}

fn sin_of(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}

/// (sin, cos) of the angle a − b, clamped at 0 (cos 1) where b exceeds a.
fn angle_less((sin_a, cos_a): (f32, f32), (sin_b, cos_b): (f32, f32)) -> (f32, f32) {
    if cos_a > cos_b {
        return (0.0, 1.0);
    }
    (sin_a * cos_b - cos_a * sin_b, cos_a * cos_b + sin_a * sin_b)
}

/// The narrowest cone (axis, cosine of half-angle) holding both cones.
fn cone_union(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let everything = (Vec3::Z, -1.0);
    if a.1 <= -1.0 || b.1 <= -1.0 {
        return everything;
    }
    let (theta_a, theta_b) = (a.1.clamp(-1.0, 1.0).acos(), b.1.clamp(-1.0, 1.0).acos());
    let theta_d = a.0.dot(b.0).clamp(-1.0, 1.0).acos();
    if (theta_d + theta_b).min(PI) <= theta_a {
        return a;
    }
    if (theta_d + theta_a).min(PI) <= theta_b {
        return b;
    }
    let theta_o = 0.5 * (theta_a + theta_d + theta_b);
    if theta_o >= PI {
        return everything;
    }
    // Turn a's axis towards b's by θo − θa.
    let turn = theta_o - theta_a;
    let about = a.0.cross(b.0);
    if about.length_squared() < 1e-12 {
        return everything;
    }
    let axis = glam::Quat::from_axis_angle(about.normalize(), turn) * a.0;
    (axis.normalize(), theta_o.cos())
}

/// The orientation measure of a group's cones: the solid angle its emission can reach,
/// weighted by the cosine (Conty Estevez and Kulla's M_Ω), which the build keeps small.
fn orientation_measure(b: &LightBounds) -> f32 {
    let theta_o = b.cos_normals.clamp(-1.0, 1.0).acos();
    let theta_e = b.cos_emission.clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(PI);
    let (sin_o, cos_o) = theta_o.sin_cos();
    2.0 * PI * (1.0 - cos_o)
        + PI / 2.0
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + cos_o)
}

/// Buckets per axis the build tries splits between.
const BUCKETS: usize = 12;

#[derive(Clone, Copy, Debug)]
enum Node {
    Leaf(u32),
    Inner([u32; 2]),
}

/// The tree: nodes with their bounds, the root first; each leaf names an entry of the list
/// it was built from.
#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<(LightBounds, Node)>,
    /// Each node's parent (the root's is itself).
    parents: Vec<u32>,
    /// The leaf node of each entry of the list (`u32::MAX` for an entry without power).
    leaf_of: Vec<u32>,
}

impl LightTree {
    /// The tree over `entries` (those without power are left out); `None` if none has power.
    pub fn build(entries: &[LightBounds]) -> Option<Self> {
        let mut order: Vec<u32> = (0..entries.len() as u32)
            .filter(|&i| entries[i as usize].phi > 0.0 && entries[i as usize].phi.is_finite())
            .collect();
        if order.is_empty() {
            return None;
        }
        let mut tree = Self {
            nodes: Vec::with_capacity(2 * order.len()),
            parents: Vec::with_capacity(2 * order.len()),
            leaf_of: vec![u32::MAX; entries.len()],
        };
        tree.build_node(entries, &mut order, 0);
        Some(tree)
    }

    fn build_node(&mut self, entries: &[LightBounds], items: &mut [u32], parent: u32) -> u32 {
        let at = self.nodes.len() as u32;
        self.parents.push(if at == 0 { 0 } else { parent });
        if let [only] = items {
            self.nodes
                .push((entries[*only as usize], Node::Leaf(*only)));
            self.leaf_of[*only as usize] = at;
            return at;
        }
        let bounds = (items.iter())
            .map(|&i| entries[i as usize])
            .reduce(|a, b| a.union(&b))
            .expect("a group has entries");
        self.nodes.push((bounds, Node::Inner([0, 0])));
        let middle = split(entries, items, &bounds);
        let (left, right) = items.split_at_mut(middle);
        let l = self.build_node(entries, left, at);
        let r = self.build_node(entries, right, at);
        self.nodes[at as usize].1 = Node::Inner([l, r]);
        at
    }

    /// One entry drawn for the point `p` (unit normal `n`, or zero in a medium) with `u` in
    /// [0, 1), and the probability it was drawn with; `None` when no light can reach `p`.
    pub fn sample(&self, p: Vec3, n: Vec3, mut u: f32) -> Option<(usize, f32)> {
        let mut node = 0usize;
        let mut pmf = 1.0f32;
        if self.nodes[0].0.importance(p, n) <= 0.0 {
            return None;
        }
        loop {
            match self.nodes[node].1 {
                Node::Leaf(entry) => return Some((entry as usize, pmf)),
                Node::Inner([l, r]) => {
                    let left = self.nodes[l as usize].0.importance(p, n);
                    let right = self.nodes[r as usize].0.importance(p, n);
                    let total = left + right;
                    if total <= 0.0 || !total.is_finite() {
                        return None;
                    }
                    let p_left = left / total;
                    if u < p_left {
                        u = (u / p_left).min(ONE_BELOW);
                        pmf *= p_left;
                        node = l as usize;
                    } else {
                        u = ((u - p_left) / (1.0 - p_left)).min(ONE_BELOW);
                        pmf *= 1.0 - p_left;
                        node = r as usize;
                    }
                }
            }
        }
    }

    /// The probability [`Self::sample`] at `p` (normal `n`) draws `entry`.
    pub fn pmf(&self, p: Vec3, n: Vec3, entry: usize) -> f32 {
        let Some(&leaf) = self.leaf_of.get(entry) else {
            return 0.0;
        };
        if leaf == u32::MAX || self.nodes[0].0.importance(p, n) <= 0.0 {
            return 0.0;
        }
        let mut pmf = 1.0f32;
        let mut node = leaf as usize;
        while node != 0 {
            let parent = self.parents[node] as usize;
            let Node::Inner([l, r]) = self.nodes[parent].1 else {
                unreachable!("a parent is an inner node")
            };
            let left = self.nodes[l as usize].0.importance(p, n);
            let right = self.nodes[r as usize].0.importance(p, n);
            let total = left + right;
            if total <= 0.0 || !total.is_finite() {
                return 0.0;
            }
            pmf *= if node == l as usize { left } else { right } / total;
            node = parent;
        }
        pmf
    }

    /// Nodes in the tree.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }
}

/// The largest f32 below 1.
const ONE_BELOW: f32 = 1.0 - f32::EPSILON / 2.0;

/// Reorders `items` and says where to split them: between the buckets of the centres along
/// one axis where power × orientation × surface area, summed over both sides, is least
/// (the build cost of Conty Estevez and Kulla); in the middle of the list where the centres
/// coincide.
fn split(entries: &[LightBounds], items: &mut [u32], bounds: &LightBounds) -> usize {
    let centre = |i: u32| entries[i as usize].centre();
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &i in items.iter() {
        (lo, hi) = (lo.min(centre(i)), hi.max(centre(i)));
    }
    let extent = bounds.hi - bounds.lo;
    let cost = |b: &LightBounds| {
        let d = b.hi - b.lo;
        let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
        b.phi * orientation_measure(b) * area.max(f32::MIN_POSITIVE)
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for axis in 0..3 {
        if hi[axis] <= lo[axis] {
            continue;
        }
        let bucket = |i: u32| {
            let t = (centre(i)[axis] - lo[axis]) / (hi[axis] - lo[axis]);
            ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
        };
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for &i in items.iter() {
            let b = &mut buckets[bucket(i)];
            let e = entries[i as usize];
            *b = Some(b.map_or(e, |b| b.union(&e)));
        }
        // A long, thin box should split across its length.
        let stretch = extent.max_element() / extent[axis].max(f32::MIN_POSITIVE);
        for cut in 1..BUCKETS {
            let side = |range: std::ops::Range<usize>| {
                buckets[range]
                    .iter()
                    .flatten()
                    .copied()
                    .reduce(|a, b| a.union(&b))
            };
            let (Some(below), Some(above)) = (side(0..cut), side(cut..BUCKETS)) else {
                continue;
            };
            let c = stretch * (cost(&below) + cost(&above));
            if best.is_none_or(|(b, _, _)| c < b) {
                best = Some((c, axis, cut));
            }
        }
    }
    let Some((_, axis, cut)) = best else {
        return items.len() / 2;
    };
    let key = |i: u32| {
        let t = (centre(i)[axis] - lo[axis]) / (hi[axis] - lo[axis]);
        ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };
    items.sort_by_key(|&i| (key(i) >= cut, i));
    items.partition_point(|&i| key(i) < cut)
}

#[cfg(test)]
mod tests;
