//! A kd-tree over 3-D points: the spatial index of a photon map. It owns positions (copied in
//! tree order), the slot → input-index mapping and the split planes; it knows nothing of
//! photons, power, kernels or estimates, and it never reorders or touches the caller's data.
//!
//! Layout: an implicit, perfectly balanced tree. With `n` points and `2^depth` leaves, leaf `j`
//! holds the contiguous slots `[j·n >> depth, (j+1)·n >> depth)`, so every leaf has at most
//! [`LEAF_SIZE`] points and no node stores a range or a child pointer. Inner nodes are numbered
//! as in a binary heap (root 1, children `2i` and `2i+1`) and store only a split value (4 bytes)
//! and a split axis (1 byte): about 0.3 bytes per point on top of the 12-byte position and the
//! 4-byte source index. Construction lives in [`build`].
//!
//! Queries walk the tree near-child first and prune a far child by the squared distance from the
//! query to its cell, kept incrementally per axis (Arya & Mount). That bound is computed with the
//! same float operations as a point's distance, so it never exceeds the distance of any point in
//! the cell: pruning is exact, not merely close. Leaves are scanned linearly. A k-nearest query
//! collects its first `k` candidates without ordering, then turns them into a max-heap keyed on
//! squared distance, so the current k-th distance (the pruning bound) and [`Neighbours::farthest`]
//! are the heap top, read in O(1). Queries allocate nothing: the heap is the caller's
//! [`Neighbours`] buffer.

mod build;
mod nearest;

use glam::Vec3;

/// Most points in one leaf. Leaves hold between about half of this and this many points.
pub const LEAF_SIZE: usize = 8;

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
    /// Candidates of a k-nearest query packed as `dist2 bits << 32 | slot` (see [`pack`]).
    keys: Vec<u64>,
    /// Index in `items` of the farthest neighbour (0 when empty; the heap top after a
    /// k-nearest query).
    farthest_at: usize,
}

impl Neighbours {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn with_capacity(k: usize) -> Self {
        Self {
            items: Vec::with_capacity(k),
            keys: Vec::new(),
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
    /// Positions in tree order: leaf `j` owns a contiguous run (see the module notes).
    points: Vec<Vec3>,
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
    /// count. Non-finite points are the caller's responsibility to reject (they do not panic
    /// but may never be found). Panics if there are more than `u32::MAX` points.
    pub fn build(points: &[Vec3]) -> Self {
        build::build(points)
    }
    pub fn len(&self) -> usize {
        self.points.len()
    }
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
    /// The index, in the slice given to [`KdTree::build`], of the point in `slot`.
    pub fn source_index(&self, slot: usize) -> u32 {
        self.source[slot]
    }
    pub fn point(&self, slot: usize) -> Vec3 {
        self.points[slot]
    }
    /// All positions in tree order (slot `s` at `[s]`).
    pub fn points(&self) -> &[Vec3] {
        &self.points
    }

    /// The `k` nearest points with squared distance `<= max_dist2` (all of them if fewer).
    /// A non-finite query, `k == 0` or a NaN `max_dist2` finds nothing. Among points at the
    /// same distance as the k-th, which ones are returned is unspecified.
    pub fn k_nearest(&self, query: Vec3, k: usize, max_dist2: f32, out: &mut Neighbours) {
        out.clear();
        if k == 0
            || !query.is_finite()
            || max_dist2.is_nan()
            || max_dist2 < 0.0
            || self.points.is_empty()
        {
            return;
        }
        let (offsets, root_dist2) = self.root_offsets(query);
        if root_dist2 > max_dist2 {
            return;
        }
        nearest::k_nearest(self, query, k, max_dist2, offsets, out);
    }

    /// Every point with squared distance `<= radius2`.
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
        if !query.is_finite() || radius2.is_nan() || radius2 < 0.0 || self.points.is_empty() {
            return;
        }
        let (mut offsets, root_dist2) = self.root_offsets(query);
        if root_dist2 > radius2 {
            return;
        }
        let mut search = WithinRadius {
            query,
            radius2,
            visit: f,
        };
        self.descend(1, &mut offsets, &mut search);
    }

    /// Per-axis offsets from `query` to the root cell and their squared length.
    fn root_offsets(&self, query: Vec3) -> ([f32; 3], f32) {
        let below = (self.lower - query).max(Vec3::ZERO);
        let above = (query - self.upper).max(Vec3::ZERO);
        let offsets = (below + above).to_array();
        (offsets, cell_dist2(&offsets))
    }

    /// Visits the subtree of `node`, near child first; `offsets` holds, per axis, the distance
    /// from the query to the node's cell (restored on return).
    fn descend<S: Search>(&self, node: usize, offsets: &mut [f32; 3], search: &mut S) {
        let leaf_base = 1usize << self.depth;
        if node >= leaf_base {
            let leaf = (node - leaf_base) as u64;
            let n = self.points.len() as u64;
            let first = ((leaf * n) >> self.depth) as usize;
            let end = (((leaf + 1) * n) >> self.depth) as usize;
            search.scan(&self.points[first..end], first as u32);
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

/// Squared distance to a cell from its per-axis offsets, summed in the same order as
/// [`dist2`] so that it is never larger than any contained point's distance.
#[inline(always)]
fn cell_dist2(o: &[f32; 3]) -> f32 {
    o[0] * o[0] + o[1] * o[1] + o[2] * o[2]
}

/// Squared distance with the same operations as glam's `distance_squared`.
#[inline(always)]
fn dist2(p: Vec3, q: Vec3) -> f32 {
    let d = p - q;
    d.x * d.x + d.y * d.y + d.z * d.z
}

/// What a traversal collects: it scans leaves and says how far a cell may be and still matter.
trait Search {
    fn query(&self) -> Vec3;
    /// Cells farther than this (squared) are skipped.
    fn bound(&self) -> f32;
    fn scan(&mut self, leaf: &[Vec3], first_slot: u32);
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
    fn scan(&mut self, leaf: &[Vec3], first_slot: u32) {
        for (slot, &p) in (first_slot..).zip(leaf) {
            let d2 = dist2(p, self.query);
            if d2 <= self.radius2 {
                (self.visit)(slot, d2);
            }
        }
    }
}
