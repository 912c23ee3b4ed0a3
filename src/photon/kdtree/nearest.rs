//! k-nearest collection: how candidates found by the traversal become the `k` nearest.
//!
//! Two collectors share one packed candidate, `dist2 bits << 32 | slot` (a squared distance
//! is never negative or NaN, so its bits order like its value, and a `u64` compares in one
//! instruction):
//! - small `k`: a max-heap. Its bound is always the exact k-th distance, and a replacement
//!   walks only `log2 k` levels.
//! - large `k`: an unordered buffer. Candidates are appended branch-free; when the buffer
//!   holds `k + slack`, a selection keeps the nearest `k` and tightens the bound. A heap
//!   replacement is a chain of dependent loads `log2 k` long and most scanned points of a
//!   large query do get in, so the heap stalls where the buffer streams.

use super::{KdTree, LEAF_SIZE, Neighbour, Neighbours, Search, dist2};
use glam::Vec3;

pub(super) fn k_nearest(
    tree: &KdTree,
    query: Vec3,
    k: usize,
    max_dist2: f32,
    mut offsets: [f32; 3],
    out: &mut Neighbours,
) {
    let cfg = dev_config();
    let keys = &mut out.keys;
    keys.clear();
    if k <= cfg.0 {
        keys.reserve(k + 1);
        let mut heap = Heap {
            query,
            k,
            max_dist2,
            bound: max_dist2,
            keys,
        };
        tree.descend(1, &mut offsets, &mut heap);
        if keys.len() > k {
            keys.pop(); // the sentinel
        } else if !keys.is_empty() {
            // Never filled, so never a heap: put the farthest on top.
            let farthest = position_of_max(keys);
            keys.swap(0, farthest);
        }
        out.farthest_at = 0;
    } else {
        let slack = (k * cfg.1 / 100).max(cfg.2);
        keys.resize(k + slack + LEAF_SIZE, 0);
        let mut buffer = Buffer {
            query,
            k,
            capacity: k + slack,
            bound: max_dist2,
            keys,
            len: 0,
        };
        tree.descend(1, &mut offsets, &mut buffer);
        let len = buffer.len;
        keys.truncate(len);
        if len > k {
            keys.select_nth_unstable(k - 1);
            keys.truncate(k);
            out.farthest_at = k - 1;
        } else {
            out.farthest_at = position_of_max(keys);
        }
    }
    out.items.extend(out.keys.iter().map(|&key| unpack(key)));
}

fn dev_config() -> (usize, usize, usize) {
    static CFG: std::sync::OnceLock<(usize, usize, usize)> = std::sync::OnceLock::new();
    *CFG.get_or_init(|| {
        let get = |n: &str, d: usize| {
            std::env::var(n)
                .ok()
                .and_then(|s| s.parse().ok())
                .unwrap_or(d)
        };
        (get("HEAPK", 32), get("PCT", 50), get("MINSLACK", 8))
    })
}

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

/// Small-k collector: unordered until it holds `k`, then a max-heap whose top is the k-th.
struct Heap<'a> {
    query: Vec3,
    k: usize,
    max_dist2: f32,
    /// `max_dist2` while filling, then the heap top's distance.
    bound: f32,
    /// The candidates; once full, a heap followed by one sentinel 0 (see [`heapify`]).
    keys: &'a mut Vec<u64>,
}

impl Search for Heap<'_> {
    #[inline(always)]
    fn query(&self) -> Vec3 {
        self.query
    }
    #[inline(always)]
    fn bound(&self) -> f32 {
        self.bound
    }
    #[inline(always)]
    fn scan(&mut self, leaf: &[Vec3], first_slot: u32) {
        let mut rest = leaf;
        let mut slot = first_slot;
        while self.keys.len() < self.k {
            let Some((&p, tail)) = rest.split_first() else {
                return;
            };
            rest = tail;
            let dist2 = dist2(p, self.query);
            if dist2 <= self.max_dist2 {
                self.keys.push(pack(dist2, slot));
                if self.keys.len() == self.k {
                    self.keys.push(0);
                    heapify(self.keys);
                    self.bound = key_dist2(self.keys[0]);
                }
            }
            slot += 1;
        }
        for (slot, &p) in (slot..).zip(rest) {
            let dist2 = dist2(p, self.query);
            if dist2 < self.bound {
                self.bound = replace_top(self.keys, pack(dist2, slot));
            }
        }
    }
}

/// Makes a max-heap of `heap[..len - 1]`. The last element is a sentinel 0, never larger
/// than a key, so that a node's right child can always be read.
fn heapify(heap: &mut [u64]) {
    let n = heap.len() - 1;
    for start in (0..n / 2).rev() {
        let item = heap[start];
        let mut hole = start;
        let mut child = 2 * hole + 1;
        while child < n {
            child += usize::from(heap[child + 1] > heap[child]);
            if heap[child] <= item {
                break;
            }
            heap[hole] = heap[child];
            hole = child;
            child = 2 * hole + 1;
        }
        heap[hole] = item;
    }
}

/// Replaces the top of a sentinel-terminated max-heap (see [`heapify`]) with `item`; returns
/// the new top distance. Bottom-up: the hole goes down along the larger children without
/// comparing against `item` (a branch-free choice per level), then `item`, which replaced
/// the largest and so is usually small, climbs back the few levels it needs.
#[inline(always)]
fn replace_top(heap: &mut [u64], item: u64) -> f32 {
    let n = heap.len() - 1;
    let mut hole = 0;
    let mut child = 1;
    while child < n {
        let (left, right) = (heap[child], heap[child + 1]);
        let take_right = right > left;
        heap[hole] = if take_right { right } else { left };
        hole = child + usize::from(take_right);
        child = 2 * hole + 1;
    }
    while hole > 0 {
        let parent = (hole - 1) / 2;
        let above = heap[parent];
        if above >= item {
            break;
        }
        heap[hole] = above;
        hole = parent;
    }
    heap[hole] = item;
    key_dist2(heap[0])
}

/// Large-k collector: an unordered buffer shrunk to the nearest `k` by selection.
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
    fn scan(&mut self, leaf: &[Vec3], first_slot: u32) {
        if self.len >= self.capacity {
            self.shrink();
        }
        let mut len = self.len;
        for (slot, &p) in (first_slot..).zip(leaf) {
            let dist2 = dist2(p, self.query);
            // Write always, keep if near: no branch to mispredict.
            self.keys[len] = pack(dist2, slot);
            len += usize::from(dist2 <= self.bound);
        }
        self.len = len;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heap_keeps_the_largest_on_top() {
        let mut heap: Vec<u64> = [3u64, 1, 4, 15, 5, 9, 2, 6]
            .iter()
            .map(|&d| d << 32)
            .collect();
        heap.push(0);
        heapify(&mut heap);
        assert_eq!(heap[0] >> 32, 15);
        for expected_top in [9, 6, 5, 4] {
            replace_top(&mut heap, 0);
            assert_eq!(heap[0] >> 32, expected_top);
        }
        assert_eq!(*heap.last().unwrap(), 0, "the sentinel stays in place");
    }

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
