//! Construction of [`KdTree`]: median splits, the axis of largest spread, subtrees built in
//! parallel. Every step is a pure function of the input slice (selection is deterministic and
//! min/max are exact), so the tree does not depend on how rayon schedules the work.

use super::{KdTree, LEAF_SIZE};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU8, AtomicU32, Ordering};

/// Subtrees with more points than this are built on two rayon tasks; smaller ones on one, as
/// the fork would cost more than it saves.
const PARALLEL_MIN_POINTS: usize = 1 << 15;

/// A point and where it came from, moved together while partitioning.
#[derive(Clone, Copy)]
struct Item {
    position: Vec3,
    source: u32,
}

/// Split values and axes, written once per inner node by whichever task builds it.
/// Atomics (relaxed) let sibling subtrees write the shared arrays without `unsafe`.
struct Nodes {
    splits: Vec<AtomicU32>,
    axes: Vec<AtomicU8>,
}

/// Where the leaves lie: `leaf_start(j) = j·n >> depth`.
#[derive(Clone, Copy)]
struct Shape {
    n: u64,
    depth: u32,
}

impl Shape {
    fn leaf_start(self, leaf: u64) -> usize {
        ((leaf * self.n) >> self.depth) as usize
    }
}

pub(super) fn build(points: &[Vec3]) -> KdTree {
    let n = points.len();
    assert!(
        n <= u32::MAX as usize,
        "a kd-tree holds at most u32::MAX points"
    );
    if n == 0 {
        return KdTree::default();
    }
    let mut depth = 0;
    while n.div_ceil(1 << depth) > LEAF_SIZE {
        depth += 1;
    }
    let shape = Shape { n: n as u64, depth };
    let leaf_base = 1usize << depth;

    let mut items: Vec<Item> = if n > PARALLEL_MIN_POINTS {
        points
            .par_iter()
            .enumerate()
            .map(|(i, &position)| Item {
                position,
                source: i as u32,
            })
            .collect()
    } else {
        points
            .iter()
            .enumerate()
            .map(|(i, &position)| Item {
                position,
                source: i as u32,
            })
            .collect()
    };
    let nodes = Nodes {
        splits: (0..leaf_base).map(|_| AtomicU32::new(0)).collect(),
        axes: (0..leaf_base).map(|_| AtomicU8::new(0)).collect(),
    };
    let (lower, upper) = bounds_maybe_parallel(&items);
    if depth > 0 {
        build_node(&nodes, shape, 1, 0, &mut items, (lower, upper));
    }

    let (xs, ys, zs, source) = split_columns(&items);
    KdTree {
        xs,
        ys,
        zs,
        source,
        splits: nodes
            .splits
            .into_iter()
            .map(|s| f32::from_bits(s.into_inner()))
            .collect(),
        axes: nodes.axes.into_iter().map(AtomicU8::into_inner).collect(),
        depth,
        lower,
        upper,
    }
}

/// Partitions `items` (the points of inner node `node`, at tree level `level`) around the
/// median of the axis where they spread most, records the split, and recurses.
fn build_node(
    nodes: &Nodes,
    shape: Shape,
    node: usize,
    level: u32,
    items: &mut [Item],
    bounds: (Vec3, Vec3),
) {
    let (lower, upper) = bounds;
    let leaves_below = shape.depth - level;
    let first_leaf = ((node - (1 << level)) as u64) << leaves_below;
    let middle_leaf = first_leaf + (1u64 << (leaves_below - 1));
    let mid = shape.leaf_start(middle_leaf) - shape.leaf_start(first_leaf);
    debug_assert!(0 < mid && mid < items.len());

    // Largest extent of the tight box: photons on a plane never split across it.
    let extent = upper - lower;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    // One comparator per axis, so the selection's inner loop does not dispatch on `axis`.
    let split = match axis {
        0 => {
            items
                .select_nth_unstable_by(mid, |a, b| a.position.x.total_cmp(&b.position.x))
                .1
                .position
                .x
        }
        1 => {
            items
                .select_nth_unstable_by(mid, |a, b| a.position.y.total_cmp(&b.position.y))
                .1
                .position
                .y
        }
        _ => {
            items
                .select_nth_unstable_by(mid, |a, b| a.position.z.total_cmp(&b.position.z))
                .1
                .position
                .z
        }
    };
    nodes.splits[node].store(split.to_bits(), Ordering::Relaxed);
    nodes.axes[node].store(axis as u8, Ordering::Relaxed);

    if leaves_below == 1 {
        return;
    }
    let parallel = items.len() > PARALLEL_MIN_POINTS;
    let (left, right) = items.split_at_mut(mid);
    let build_left = |left: &mut [Item]| {
        let b = bounds_maybe_parallel(left);
        build_node(nodes, shape, 2 * node, level + 1, left, b)
    };
    let build_right = |right: &mut [Item]| {
        let b = bounds_maybe_parallel(right);
        build_node(nodes, shape, 2 * node + 1, level + 1, right, b)
    };
    if parallel {
        rayon::join(|| build_left(left), || build_right(right));
    } else {
        build_left(left);
        build_right(right);
    }
}

fn bounds_maybe_parallel(items: &[Item]) -> (Vec3, Vec3) {
    if items.len() > 4 * PARALLEL_MIN_POINTS {
        items.par_chunks(PARALLEL_MIN_POINTS).map(bounds).reduce(
            || (Vec3::INFINITY, Vec3::NEG_INFINITY),
            |a, b| (a.0.min(b.0), a.1.max(b.1)),
        )
    } else {
        bounds(items)
    }
}

/// Tight bounding box (min and max are exact, so the order of reduction does not matter).
fn bounds(items: &[Item]) -> (Vec3, Vec3) {
    items
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), it| {
            (lo.min(it.position), hi.max(it.position))
        })
}

/// The items' coordinates and source indices as four arrays, in one pass (chunks in parallel
/// for large inputs; each chunk writes only its own part of each array).
fn split_columns(items: &[Item]) -> (Vec<f32>, Vec<f32>, Vec<f32>, Vec<u32>) {
    let n = items.len();
    let (mut xs, mut ys, mut zs, mut source) =
        (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0; n]);
    let write =
        |items: &[Item], xs: &mut [f32], ys: &mut [f32], zs: &mut [f32], source: &mut [u32]| {
            for (i, it) in items.iter().enumerate() {
                (xs[i], ys[i], zs[i], source[i]) =
                    (it.position.x, it.position.y, it.position.z, it.source);
            }
        };
    if n > PARALLEL_MIN_POINTS {
        let chunk = PARALLEL_MIN_POINTS;
        items
            .par_chunks(chunk)
            .zip(xs.par_chunks_mut(chunk))
            .zip(ys.par_chunks_mut(chunk))
            .zip(zs.par_chunks_mut(chunk))
            .zip(source.par_chunks_mut(chunk))
            .for_each(|((((items, xs), ys), zs), source)| write(items, xs, ys, zs, source));
    } else {
        write(items, &mut xs, &mut ys, &mut zs, &mut source);
    }
    (xs, ys, zs, source)
}
