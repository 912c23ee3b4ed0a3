//! PLACEHOLDER (brute force) with the final API: the kd-tree helper replaces the body.
//! A kd-tree over 3-D points. Owns the spatial index only: it knows positions, not photons.

use glam::Vec3;

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
}

impl Neighbours {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn with_capacity(k: usize) -> Self {
        Self {
            items: Vec::with_capacity(k),
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
    /// The farthest neighbour found (the k-th of a full k-nearest query).
    pub fn farthest(&self) -> Option<Neighbour> {
        self.items
            .iter()
            .copied()
            .max_by(|a, b| a.dist2.total_cmp(&b.dist2))
    }
    pub fn clear(&mut self) {
        self.items.clear();
    }
}

/// Balanced kd-tree. Points are stored in tree order ("slots").
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    points: Vec<Vec3>,
    source: Vec<u32>,
}

impl KdTree {
    /// Builds the tree. Non-finite points are the caller's responsibility to reject.
    pub fn build(points: &[Vec3]) -> Self {
        Self {
            points: points.to_vec(),
            source: (0..points.len() as u32).collect(),
        }
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
    /// The `k` nearest points with squared distance `<= max_dist2` (all of them if fewer).
    pub fn k_nearest(&self, query: Vec3, k: usize, max_dist2: f32, out: &mut Neighbours) {
        out.clear();
        let mut all: Vec<Neighbour> = self
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| Neighbour {
                dist2: p.distance_squared(query),
                slot: i as u32,
            })
            .filter(|n| n.dist2 <= max_dist2)
            .collect();
        all.sort_by(|a, b| a.dist2.total_cmp(&b.dist2));
        all.truncate(k);
        out.items.extend(all);
    }
    /// Every point with squared distance `<= radius2`.
    pub fn within_radius(&self, query: Vec3, radius2: f32, out: &mut Neighbours) {
        out.clear();
        self.for_each_within(query, radius2, |slot, dist2| {
            out.items.push(Neighbour { dist2, slot })
        });
    }
    /// Calls `f(slot, dist2)` for every point with squared distance `<= radius2`.
    pub fn for_each_within(&self, query: Vec3, radius2: f32, mut f: impl FnMut(u32, f32)) {
        for (i, p) in self.points.iter().enumerate() {
            let d2 = p.distance_squared(query);
            if d2 <= radius2 {
                f(i as u32, d2);
            }
        }
    }
}
