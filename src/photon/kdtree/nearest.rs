//! How a k-nearest query keeps its `k` best: an unordered buffer and a selection, not a heap.
//!
//! A candidate is packed into one `u64`, `dist2 bits << 32 | slot`: a squared distance is never
//! negative or NaN, so its bits order like its value, and ties break by slot. The traversal
//! appends every point within the current bound without a branch (write always, advance if
//! near); when `k + slack` are in, a selection keeps the nearest `k` and lowers the bound to
//! just below the k-th distance. At the end one more selection leaves exactly `k`, the k-th at
//! index `k - 1`, which is [`Neighbours::farthest`] without a scan.
//!
//! Why not a binary heap: most points scanned by a large query do enter the result, and each
//! heap replacement is a chain of `log2 k` dependent loads, so at k = 400 the heap made
//! queries about twice as slow as this buffer; at k = 1 to 10 the two measured the same.

use super::{KdTree, LEAF_SIZE, Leaf, Neighbour, Neighbours, Search};
use glam::Vec3;

/// Candidates collected beyond `k` before a selection: `k/2` but at least this. Measured on
/// photon-like data (1M points on surfaces) for k from 1 to 1000: half of k balances the
/// cost of each selection against how often it runs and how stale the bound gets between.
const MIN_SLACK: usize = 8;

/// Scratch keys needed for a query of `k`: the buffer plus room to write one whole leaf.
pub(super) fn scratch_len(k: usize) -> usize {
    k + slack(k) + LEAF_SIZE
}

fn slack(k: usize) -> usize {
    (k / 2).max(MIN_SLACK)
}

/// Fills `out` with the `k` (at most the tree's size) nearest points within `max_dist2`;
/// `offsets` are the query's per-axis distances to the root cell.
pub(super) fn k_nearest(
    tree: &KdTree,
    query: Vec3,
    k: usize,
    max_dist2: f32,
    mut offsets: [f32; 3],
    out: &mut Neighbours,
) {
    let storage = scratch_len(k);
    if out.keys.len() < storage {
        // Grows once per buffer; the contents are scratch and never need clearing.
        out.keys.resize(storage, 0);
    }
    let capacity = k + slack(k);
    let mut buffer = Buffer {
        query,
        k,
        capacity,
        bound: max_dist2,
        keys: &mut out.keys,
        len: 0,
    };
    tree.descend(1, &mut offsets, &mut buffer);
    let len = buffer.len;
    let found = &mut out.keys[..len];
    let found = if len > k {
        found.select_nth_unstable(k - 1);
        out.farthest_at = k - 1;
        &found[..k]
    } else {
        out.farthest_at = position_of_max(found);
        &found[..]
    };
    out.items.extend(found.iter().map(|&key| unpack(key)));
}

/// Packs a candidate so that integer order is distance order (ties by slot).
#[inline(always)]
fn pack(dist2: f32, slot: u32) -> u64 {
    (u64::from(dist2.to_bits()) << 32) | u64::from(slot)
}

#[inline(always)]
fn key_dist2(key: u64) -> f32 {
    f32::from_bits((key >> 32) as u32)
}

fn unpack(key: u64) -> Neighbour {
    Neighbour {
        dist2: key_dist2(key),
        slot: key as u32,
    }
}

fn position_of_max(keys: &[u64]) -> usize {
    keys.iter()
        .enumerate()
        .max_by_key(|&(_, key)| key)
        .map_or(0, |(i, _)| i)
}

/// The largest float below `x` (for `x > 0`), or -1 (nothing passes) when `x` is 0: turns
/// "strictly nearer than the k-th" into the inclusive test the traversal uses.
fn just_below(x: f32) -> f32 {
    if x > 0.0 {
        f32::from_bits(x.to_bits() - 1)
    } else {
        -1.0
    }
}

/// The k-nearest collector: an unordered buffer shrunk to the nearest `k` by selection.
struct Buffer<'a> {
    query: Vec3,
    k: usize,
    /// Candidates held before a selection shrinks them back to `k`.
    capacity: usize,
    /// Points farther than this are not candidates and cells farther are skipped: first
    /// `max_dist2`, then just below the k-th distance of the last selection.
    bound: f32,
    /// `capacity + LEAF_SIZE` keys, so a whole leaf can be written before checking; the
    /// first `len` are candidates.
    keys: &'a mut [u64],
    len: usize,
}

impl Buffer<'_> {
    #[cold]
    #[inline(never)]
    fn shrink(&mut self) {
        let k = self.k;
        self.keys[..self.len].select_nth_unstable(k - 1);
        self.len = k;
        self.bound = just_below(key_dist2(self.keys[k - 1]));
    }
}

impl Search for Buffer<'_> {
    #[inline(always)]
    fn query(&self) -> Vec3 {
        self.query
    }
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.bound
    }
    #[inline(always)]
    fn scan(&mut self, leaf: Leaf<'_>) {
        if self.len >= self.capacity {
            self.shrink();
        }
        let mut dist2 = [0.0; LEAF_SIZE];
        let mut len = self.len;
        for (slot, &dist2) in (leaf.first_slot..).zip(leaf.dist2(self.query, &mut dist2)) {
            // Write always, keep if near: no branch to mispredict.
            self.keys[len] = pack(dist2, slot);
            len += usize::from(dist2 <= self.bound);
        }
        self.len = len;
    }
}

/// The nearest collector with a predicate: the best `(dist2, slot)` taken so far bounds the
/// search.
pub(super) struct NearestWhere<F> {
    query: Vec3,
    bound: f32,
    best: Option<u64>,
    accept: F,
}

impl<F: FnMut(u32, f32) -> bool> NearestWhere<F> {
    pub(super) fn new(query: Vec3, max_dist2: f32, accept: F) -> Self {
        Self {
            query,
            bound: max_dist2,
            best: None,
            accept,
        }
    }

    pub(super) fn best(&self) -> Option<Neighbour> {
        self.best.map(unpack)
    }
}

impl<F: FnMut(u32, f32) -> bool> Search for NearestWhere<F> {
    #[inline(always)]
    fn query(&self) -> Vec3 {
        self.query
    }
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.bound
    }
    #[inline(always)]
    fn scan(&mut self, leaf: Leaf<'_>) {
        let mut dist2 = [0.0; LEAF_SIZE];
        for (slot, &d2) in (leaf.first_slot..).zip(leaf.dist2(self.query, &mut dist2)) {
            // Cells at the bound are still visited, so a tie with a lower slot is found.
            if d2 > self.bound {
                continue;
            }
            let key = pack(d2, slot);
            if self.best.is_none_or(|b| key < b) && (self.accept)(slot, d2) {
                self.best = Some(key);
                self.bound = d2;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packed_keys_order_like_distances() {
        let d = [0.0f32, 1e-30, 0.5, 0.5, 1.0, 3e8];
        for w in d.windows(2) {
            assert!(pack(w[0], 7) <= pack(w[1], 3) || w[0] == w[1]);
        }
        assert!(pack(0.5, 3) < pack(0.5, 4));
        assert_eq!(
            unpack(pack(0.25, 42)),
            Neighbour {
                dist2: 0.25,
                slot: 42
            }
        );
        assert_eq!(just_below(0.0), -1.0);
        assert!(just_below(1.0) < 1.0 && just_below(1.0) > 0.9999);
    }
}
