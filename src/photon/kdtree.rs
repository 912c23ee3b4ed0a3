//! A kd-tree over 3-D points: the spatial index of a photon map. It owns positions (copied in
//! tree order), the slot → input-index mapping and the split planes, and answers k-nearest and
//! radius queries. It knows nothing of photons, power, kernels or estimates, and it never
//! reorders or keeps the caller's slice.
//!
//! Layout: an implicit, perfectly balanced tree. With `n` points and `2^depth` leaves, leaf `j`
//! holds the contiguous slots `[j·n >> depth, (j+1)·n >> depth)`, so no node stores a range or
//! a child pointer. Inner nodes are numbered as in a binary heap (root 1, children `2i` and
//! `2i+1`) and store only a split value (4 bytes) and a split axis (1 byte): about 0.3 bytes
//! per point on top of the 12-byte position and the 4-byte source index. Positions are kept one
//! array per axis so that a leaf's distances are computed with SIMD. Construction (median
//! splits on the axis of largest spread, in parallel) lives in `build`.
//!
//! Queries walk the tree near child first and skip a far child by the squared distance from the
//! query to its cell, kept per axis as the walk goes (Arya & Mount). That bound is computed with
//! the same float operations as a point's distance, so it never exceeds the distance of any
//! point in the cell: pruning is exact in floats, not merely in reals. Leaves are scanned
//! linearly. How a k-nearest query keeps its `k` best is in `nearest`; the result's farthest
//! neighbour is known without a scan. Queries allocate nothing once the caller's
//! [`Neighbours`] has grown to the largest `k` used.

mod build;
mod nearest;

use glam::Vec3;

/// Most points in one leaf; leaves hold between about half of this and this many. Leaves of
/// 16 points measured best on photon-like data for k from 10 to 400 (8 and 32 were worse):
/// smaller leaves cost more inner nodes, larger ones more distances to points outside the
/// search radius.
pub const LEAF_SIZE: usize = 20;

/// One neighbour found by a query: the tree slot (see [`KdTree::source_index`]) and its
/// squared distance to the query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Neighbour {
    pub dist2: f32,
    pub slot: u32,
}

/// Reusable result buffer: queries write into it, so the hot loop allocates nothing.
#[derive(Clone, Debug, Default)]
pub struct Neighbours {
    items: Vec<Neighbour>,
    /// Scratch for k-nearest candidates, packed as `dist2 bits << 32 | slot`.
    keys: Vec<u64>,
    /// Index in `items` of the farthest neighbour (0 when empty).
    farthest_at: usize,
}

impl Neighbours {
    pub fn new() -> Self {
        Self::default()
    }
    /// A buffer that k-nearest queries with up to `k` neighbours fill without allocating.
    pub fn with_capacity(k: usize) -> Self {
        Self {
            items: Vec::with_capacity(k),
            keys: vec![0; nearest::scratch_len(k)],
            farthest_at: 0,
        }
    }
    /// The neighbours found, in no particular order.
    pub fn as_slice(&self) -> &[Neighbour] {
        &self.items
    }
    pub fn len(&self) -> usize {
        self.items.len()
    }
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
    /// The farthest neighbour found (the k-th of a full k-nearest query), in O(1).
    pub fn farthest(&self) -> Option<Neighbour> {
        self.items.get(self.farthest_at).copied()
    }
    pub fn clear(&mut self) {
        self.items.clear();
        self.farthest_at = 0;
    }
    /// Sorts the neighbours by increasing distance (ties by slot), for callers that want them
    /// in order. [`Neighbours::farthest`] stays valid.
    pub fn sort_by_distance(&mut self) {
        self.items
            .sort_unstable_by(|a, b| a.dist2.total_cmp(&b.dist2).then(a.slot.cmp(&b.slot)));
        self.farthest_at = self.items.len().saturating_sub(1);
    }
}

/// Balanced kd-tree. Points are stored in tree order ("slots").
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    /// Positions in tree order, one array per axis (so a leaf's distances vectorize): leaf
    /// `j` owns a contiguous run of each (see the module notes).
    xs: Vec<f32>,
    ys: Vec<f32>,
    zs: Vec<f32>,
    /// `source[slot]` is the index of that point in the slice given to [`KdTree::build`].
    source: Vec<u32>,
    /// Split value of inner node `i` at `[i]` (index 0 unused). Points left of a split are
    /// `<=` it on the split axis, points right of it `>=`.
    splits: Vec<f32>,
    /// Split axis (0, 1 or 2) of inner node `i` at `[i]`.
    axes: Vec<u8>,
    /// Leaves are `1 << depth`; the first leaf's node number is `1 << depth` too.
    depth: u32,
    /// Bounding box of all points: the root cell, so a query far outside stops at once.
    lower: Vec3,
    upper: Vec3,
}

impl KdTree {
    /// Builds the tree: median splits on the axis where the node's points spread most, in
    /// parallel for large inputs. The result depends only on `points`, not on the thread
    /// count. Non-finite points are the caller's responsibility to reject: nothing panics,
    /// but they are never found and a NaN can hide finite points from queries. Panics if there
    /// are more than `u32::MAX` points.
    pub fn build(points: &[Vec3]) -> Self {
        build::build(points)
    }
    pub fn len(&self) -> usize {
        self.source.len()
    }
    pub fn is_empty(&self) -> bool {
        self.source.is_empty()
    }
    /// The index, in the slice given to [`KdTree::build`], of the point in `slot`.
    pub fn source_index(&self, slot: usize) -> u32 {
        self.source[slot]
    }
    /// Inner nodes and leaves are numbered as in a binary heap: the root is 1, the children of
    /// `i` are `2i` and `2i + 1`, and nodes from `leaf_base()` on are leaves. For walks that
    /// keep their own data per node (see [`KdTree::node_slots`]).
    pub fn leaf_base(&self) -> usize {
        1 << self.depth
    }
    /// One past the largest node number.
    pub fn node_end(&self) -> usize {
        2 << self.depth
    }
    /// The slots under `node` (inner node or leaf): always one contiguous run.
    pub fn node_slots(&self, node: usize) -> std::ops::Range<usize> {
        debug_assert!(node >= 1 && node < self.node_end());
        let level = usize::BITS - 1 - node.leading_zeros();
        let below = self.depth - level;
        let first_leaf = ((node << below) - self.leaf_base()) as u64;
        let end_leaf = (((node + 1) << below) - self.leaf_base()) as u64;
        let n = self.len() as u64;
        ((first_leaf * n) >> self.depth) as usize..((end_leaf * n) >> self.depth) as usize
    }
    /// Positions in slot order, one slice per axis (for loops over a node's slots).
    pub fn coordinates(&self) -> (&[f32], &[f32], &[f32]) {
        (&self.xs, &self.ys, &self.zs)
    }
    /// Heap bytes held: positions, source indices and split planes.
    pub fn heap_bytes(&self) -> usize {
        (self.xs.capacity() + self.ys.capacity() + self.zs.capacity() + self.splits.capacity())
            * size_of::<f32>()
            + self.source.capacity() * size_of::<u32>()
            + self.axes.capacity()
    }
    #[inline]
    pub fn point(&self, slot: usize) -> Vec3 {
        Vec3::new(self.xs[slot], self.ys[slot], self.zs[slot])
    }

    /// The `k` nearest points with squared distance `<= max_dist2` (all of them if fewer),
    /// in no particular order; [`Neighbours::farthest`] is the k-th. A non-finite query,
    /// `k == 0`, a negative or NaN `max_dist2` or an empty tree finds nothing. Among points at
    /// the same distance as the k-th, which ones are returned is unspecified.
    pub fn k_nearest(&self, query: Vec3, k: usize, max_dist2: f32, out: &mut Neighbours) {
        out.clear();
        if k == 0 || !query.is_finite() || max_dist2.is_nan() || max_dist2 < 0.0 || self.is_empty()
        {
            return;
        }
        // Asking for more than there are is asking for all of them.
        let k = k.min(self.len());
        let (offsets, root_dist2) = self.root_offsets(query);
        if root_dist2 > max_dist2 {
            return;
        }
        nearest::k_nearest(self, query, k, max_dist2, offsets, out);
    }

    /// The nearest point with squared distance `<= max_dist2` that `accept(slot, dist2)`
    /// takes (ties by slot), or `None`. A non-finite query or a negative or NaN `max_dist2`
    /// finds nothing. One bound that shrinks with every point taken: cheaper than a
    /// k-nearest query and a scan of its result when most points are taken.
    pub fn nearest_where(
        &self,
        query: Vec3,
        max_dist2: f32,
        accept: impl FnMut(u32, f32) -> bool,
    ) -> Option<Neighbour> {
        if !query.is_finite() || max_dist2.is_nan() || max_dist2 < 0.0 || self.is_empty() {
            return None;
        }
        let (mut offsets, root_dist2) = self.root_offsets(query);
        if root_dist2 > max_dist2 {
            return None;
        }
        let mut search = nearest::NearestWhere::new(query, max_dist2, accept);
        self.descend(1, &mut offsets, &mut search);
        search.best()
    }

    /// Every point with squared distance `<= radius2`, in no particular order.
    pub fn within_radius(&self, query: Vec3, radius2: f32, out: &mut Neighbours) {
        out.clear();
        let items = &mut out.items;
        let mut farthest_at = 0;
        let mut farthest_dist2 = f32::NEG_INFINITY;
        self.for_each_within(query, radius2, |slot, dist2| {
            if dist2 > farthest_dist2 {
                farthest_dist2 = dist2;
                farthest_at = items.len();
            }
            items.push(Neighbour { dist2, slot });
        });
        out.farthest_at = farthest_at;
    }

    /// Calls `f(slot, dist2)` for every point with squared distance `<= radius2`, in no
    /// particular order. A non-finite query or a NaN radius finds nothing.
    pub fn for_each_within(&self, query: Vec3, radius2: f32, f: impl FnMut(u32, f32)) {
        let Some(mut offsets) = self.radius_search_start(query, radius2) else {
            return;
        };
        let mut search = WithinRadius {
            query,
            radius2,
            visit: f,
        };
        self.descend(1, &mut offsets, &mut search);
    }

    /// Calls `f(leaf, slots)` for every leaf whose cell is within `radius2` (squared) of
    /// `query`, `leaf` counted from the first leaf, in slot order (so neighbouring leaves can
    /// be merged into one run): a scan that streams whole leaves through its own per-slot
    /// arrays tests the distances itself. Finds nothing where [`KdTree::for_each_within`]
    /// finds nothing.
    pub fn for_each_leaf_within(
        &self,
        query: Vec3,
        radius2: f32,
        f: impl FnMut(usize, std::ops::Range<usize>),
    ) {
        let Some(mut offsets) = self.radius_search_start(query, radius2) else {
            return;
        };
        let mut search = LeavesWithin {
            query,
            radius2,
            visit: f,
        };
        self.descend_in_order(1, &mut offsets, &mut search);
    }

    /// [`KdTree::descend`] with the children in slot order instead of near first.
    fn descend_in_order<S: Search>(&self, node: usize, offsets: &mut [f32; 3], search: &mut S) {
        if node >= self.leaf_base() {
            search.scan(self.leaf(node));
            return;
        }
        let axis = usize::from(self.axes[node]);
        let diff = search.query()[axis] - self.splits[node];
        let query_left = diff < 0.0;
        for (child, left) in [(2 * node, true), (2 * node + 1, false)] {
            if left == query_left {
                self.descend_in_order(child, offsets, search);
                continue;
            }
            let saved = offsets[axis];
            offsets[axis] = diff;
            if cell_dist2(offsets) <= search.bound() {
                self.descend_in_order(child, offsets, search);
            }
            offsets[axis] = saved;
        }
    }

    /// The root cell's offsets for a radius search, or `None` where it finds nothing (a
    /// non-finite query, a NaN or negative radius, an empty tree, a query beyond the radius
    /// of the root cell).
    fn radius_search_start(&self, query: Vec3, radius2: f32) -> Option<[f32; 3]> {
        if !query.is_finite() || radius2.is_nan() || radius2 < 0.0 || self.is_empty() {
            return None;
        }
        let (offsets, root_dist2) = self.root_offsets(query);
        (root_dist2 <= radius2).then_some(offsets)
    }

    /// Per-axis offsets from `query` to the root cell and their squared length.
    fn root_offsets(&self, query: Vec3) -> ([f32; 3], f32) {
        let below = (self.lower - query).max(Vec3::ZERO);
        let above = (query - self.upper).max(Vec3::ZERO);
        let offsets = (below + above).to_array();
        (offsets, cell_dist2(&offsets))
    }

    /// The points of leaf `node` (a node number from [`KdTree::leaf_base`] on).
    #[inline(always)]
    fn leaf(&self, node: usize) -> Leaf<'_> {
        let leaf = (node - self.leaf_base()) as u64;
        let n = self.len() as u64;
        let first = ((leaf * n) >> self.depth) as usize;
        let end = (((leaf + 1) * n) >> self.depth) as usize;
        Leaf {
            xs: &self.xs[first..end],
            ys: &self.ys[first..end],
            zs: &self.zs[first..end],
            first_slot: first as u32,
            index: node - self.leaf_base(),
        }
    }

    /// Visits the subtree of `node`, near child first; `offsets` holds, per axis, the distance
    /// from the query to the node's cell (restored on return).
    fn descend<S: Search>(&self, node: usize, offsets: &mut [f32; 3], search: &mut S) {
        if node >= self.leaf_base() {
            search.scan(self.leaf(node));
            return;
        }
        let axis = usize::from(self.axes[node]);
        let diff = search.query()[axis] - self.splits[node];
        let (near, far) = if diff < 0.0 {
            (2 * node, 2 * node + 1)
        } else {
            (2 * node + 1, 2 * node)
        };
        self.descend(near, offsets, search);
        let saved = offsets[axis];
        offsets[axis] = diff;
        if cell_dist2(offsets) <= search.bound() {
            self.descend(far, offsets, search);
        }
        offsets[axis] = saved;
    }
}

/// Squared distance to a cell from its per-axis offsets, with the operations of
/// [`Leaf::dist2`] in the same order, so that it is never larger than the computed distance
/// of any point in the cell (float subtraction, squaring and addition are all monotonic).
#[inline(always)]
fn cell_dist2(o: &[f32; 3]) -> f32 {
    o[0] * o[0] + o[1] * o[1] + o[2] * o[2]
}

/// The points of one leaf, one slice per axis (all of the same length, at most
/// [`LEAF_SIZE`]), and the slot of the first.
struct Leaf<'a> {
    xs: &'a [f32],
    ys: &'a [f32],
    zs: &'a [f32],
    first_slot: u32,
    /// Which leaf, counted from the first.
    index: usize,
}

impl Leaf<'_> {
    /// Squared distances from `query` to the leaf's points, in slot order, with the same
    /// operations as glam's `distance_squared`. One straight loop over the three slices, which
    /// the compiler turns into SIMD.
    #[inline(always)]
    fn dist2<'b>(&self, query: Vec3, out: &'b mut [f32; LEAF_SIZE]) -> &'b [f32] {
        let out = &mut out[..self.xs.len()];
        for (((d2, &x), &y), &z) in out.iter_mut().zip(self.xs).zip(self.ys).zip(self.zs) {
            let (dx, dy, dz) = (x - query.x, y - query.y, z - query.z);
            *d2 = dx * dx + dy * dy + dz * dz;
        }
        out
    }
}

/// What a traversal collects: it scans leaves and says how far a cell may be and still matter.
trait Search {
    fn query(&self) -> Vec3;
    /// Cells farther than this (squared) are skipped.
    fn bound(&self) -> f32;
    fn scan(&mut self, leaf: Leaf<'_>);
}

struct WithinRadius<F> {
    query: Vec3,
    radius2: f32,
    visit: F,
}

impl<F: FnMut(u32, f32)> Search for WithinRadius<F> {
    #[inline(always)]
    fn query(&self) -> Vec3 {
        self.query
    }
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.radius2
    }
    #[inline(always)]
    fn scan(&mut self, leaf: Leaf<'_>) {
        let mut dist2 = [0.0; LEAF_SIZE];
        for (slot, &d2) in (leaf.first_slot..).zip(leaf.dist2(self.query, &mut dist2)) {
            if d2 <= self.radius2 {
                (self.visit)(slot, d2);
            }
        }
    }
}

struct LeavesWithin<F> {
    query: Vec3,
    radius2: f32,
    visit: F,
}

impl<F: FnMut(usize, std::ops::Range<usize>)> Search for LeavesWithin<F> {
    #[inline(always)]
    fn query(&self) -> Vec3 {
        self.query
    }
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.radius2
    }
    #[inline(always)]
    fn scan(&mut self, leaf: Leaf<'_>) {
        let first = leaf.first_slot as usize;
        (self.visit)(leaf.index, first..first + leaf.xs.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every leaf whose cell (the points' box cut by the splits above it) lies within the
    /// radius, in slot order, found cell by cell.
    fn leaves_within_by_brute_force(tree: &KdTree, q: Vec3, radius2: f32) -> Vec<usize> {
        (0..tree.leaf_base())
            .filter(|&leaf| {
                let (mut lower, mut upper) = (tree.lower.to_array(), tree.upper.to_array());
                let node = tree.leaf_base() + leaf;
                for level in (0..tree.depth).rev() {
                    let (parent, child) = (node >> (level + 1), node >> level);
                    let axis = usize::from(tree.axes[parent]);
                    if child == 2 * parent {
                        upper[axis] = tree.splits[parent];
                    } else {
                        lower[axis] = tree.splits[parent];
                    }
                }
                let q = q.to_array();
                let near: f32 = (0..3)
                    .map(|a| (lower[a] - q[a]).max(q[a] - upper[a]).max(0.0))
                    .map(|d| d * d)
                    .sum();
                near <= radius2
            })
            .collect()
    }

    #[test]
    fn leaves_within_a_radius_are_every_leaf_whose_cell_it_reaches_in_slot_order() {
        use crate::sampling::{Rng, Stream};
        let mut rng = Rng::for_index(1, Stream::Distribution, 0);
        let mut next = || rng.next_f32();
        // A volume, and a plane with a dense strip (photons on a floor, a caustic on it).
        let cloud: Vec<Vec3> = (0..3000)
            .map(|_| Vec3::new(next(), next(), next()))
            .collect();
        let floor: Vec<Vec3> = (0..5000)
            .map(|i| {
                let x = next();
                let z = if i % 2 == 0 {
                    0.5 + 0.02 * next()
                } else {
                    next()
                };
                Vec3::new(x, 0.0, z)
            })
            .collect();
        for points in [cloud, floor] {
            let tree = KdTree::build(&points);
            for i in 0..400 {
                let q = Vec3::new(1.4 * next() - 0.2, 0.3 * next() - 0.1, 1.4 * next() - 0.2);
                let radius = [0.01, 0.05, 0.2, 2.0][i % 4] * next();
                let mut found = Vec::new();
                tree.for_each_leaf_within(q, radius * radius, |leaf, slots| {
                    assert_eq!(slots, tree.node_slots(tree.leaf_base() + leaf));
                    found.push(leaf);
                });
                assert_eq!(
                    found,
                    leaves_within_by_brute_force(&tree, q, radius * radius)
                );
            }
        }
    }

    #[test]
    fn cell_bound_never_exceeds_a_point_distance_in_floats() {
        // A point just beyond a split plane on two axes: the cell bound uses the plane, the
        // point its own coordinate; rounding must not put the bound above the distance.
        let query = Vec3::new(0.1, 0.7, 0.3);
        let split = Vec3::new(0.1 + 1e-7, 0.7, 0.3 - 3e-8);
        let point = Vec3::new(split.x, 0.7, split.z);
        let offsets = [query.x - split.x, 0.0, query.z - split.z];
        let leaf = Leaf {
            xs: &[point.x],
            ys: &[point.y],
            zs: &[point.z],
            first_slot: 0,
            index: 0,
        };
        let mut out = [0.0; LEAF_SIZE];
        assert!(cell_dist2(&offsets) <= leaf.dist2(query, &mut out)[0]);
    }
}
