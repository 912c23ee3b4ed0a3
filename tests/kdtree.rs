//! The kd-tree against brute force: every query type (k nearest, within a radius, the nearest a
//! predicate takes), on random and degenerate data.
//! Distances are compared as sorted lists (ties make the set of slots ambiguous for k-nearest
//! queries); radius queries have no ties at the boundary question, so their slots are compared
//! exactly.

use dpm::photon::kdtree::Neighbour;
use dpm::photon::{KdTree, Neighbours};
use glam::Vec3;
use proptest::prelude::*;
use std::collections::HashSet;

/// PCG-XSH-RR 32: small, deterministic, good enough for test data.
struct Pcg32(u64);

impl Pcg32 {
    fn new(seed: u64) -> Self {
        let mut rng = Self(
            seed.wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407),
        );
        rng.next_u32();
        rng
    }
    fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }
    /// Uniform in [0, 1).
    fn unit(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u32 << 24) as f32
    }
    fn in_box(&mut self) -> Vec3 {
        Vec3::new(self.unit(), self.unit(), self.unit())
    }
    fn below(&mut self, n: usize) -> usize {
        ((self.next_u32() as u64 * n as u64) >> 32) as usize
    }
}

fn random_box(n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    (0..n).map(|_| rng.in_box()).collect()
}

/// Points on a tilted plane (no axis is constant) plus a few on a second, axis-aligned plane:
/// caustic photons lie on surfaces.
fn two_planes(n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|i| {
            let (u, v) = (rng.unit(), rng.unit());
            if i % 5 == 4 {
                Vec3::new(u, 0.25, v)
            } else {
                Vec3::new(u, v, 0.3 * u + 0.2 * v + 0.1)
            }
        })
        .collect()
}

fn flat_plane(n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|_| Vec3::new(rng.unit(), rng.unit(), 0.5))
        .collect()
}

fn line(n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|_| {
            let t = rng.unit();
            Vec3::new(t, 2.0 * t - 1.0, 0.25)
        })
        .collect()
}

fn duplicates(n: usize) -> Vec<Vec3> {
    vec![Vec3::new(0.3, -0.2, 0.7); n]
}

/// A few distinct values per axis: many exact ties in coordinates and in distances.
fn grid_ties(n: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    (0..n)
        .map(|_| {
            Vec3::new(
                rng.below(4) as f32,
                rng.below(3) as f32,
                rng.below(2) as f32,
            )
        })
        .collect()
}

/// Queries: random in and around the data's box, on data points, and far outside.
fn queries(points: &[Vec3], count: usize, seed: u64) -> Vec<Vec3> {
    let mut rng = Pcg32::new(seed);
    let (lo, hi) = points.iter().fold((Vec3::ZERO, Vec3::ONE), |(lo, hi), &p| {
        (lo.min(p), hi.max(p))
    });
    let size = (hi - lo).max(Vec3::splat(0.1));
    (0..count)
        .map(|i| match i % 4 {
            0 if !points.is_empty() => points[rng.below(points.len())],
            1 if !points.is_empty() => {
                points[rng.below(points.len())] + (rng.in_box() - 0.5) * 0.01
            }
            2 => lo + (rng.in_box() * 3.0 - 1.0) * size,
            _ => lo + rng.in_box() * size,
        })
        .collect()
}

fn brute_dist2(points: &[Vec3], q: Vec3, max_dist2: f32) -> Vec<f32> {
    let mut d: Vec<f32> = points
        .iter()
        .map(|p| p.distance_squared(q))
        .filter(|&d2| d2 <= max_dist2)
        .collect();
    d.sort_by(f32::total_cmp);
    d
}

fn check_layout(tree: &KdTree, points: &[Vec3]) {
    assert_eq!(tree.len(), points.len());
    assert_eq!(tree.is_empty(), points.is_empty());
    let mut seen = vec![false; points.len()];
    for slot in 0..tree.len() {
        let src = tree.source_index(slot) as usize;
        assert!(!seen[src], "source index {src} appears twice");
        seen[src] = true;
        assert_eq!(tree.point(slot), points[src]);
    }
}

/// Each neighbour is a distinct slot whose reported distance is its true distance.
fn check_neighbours_are_real(tree: &KdTree, q: Vec3, found: &[Neighbour]) {
    let mut slots = HashSet::new();
    for n in found {
        assert!(slots.insert(n.slot), "slot {} reported twice", n.slot);
        assert_eq!(n.dist2, tree.point(n.slot as usize).distance_squared(q));
    }
}

fn sorted_dist2(found: &[Neighbour]) -> Vec<f32> {
    let mut d: Vec<f32> = found.iter().map(|n| n.dist2).collect();
    d.sort_by(f32::total_cmp);
    d
}

fn check_k_nearest(
    tree: &KdTree,
    points: &[Vec3],
    q: Vec3,
    k: usize,
    max_dist2: f32,
    out: &mut Neighbours,
) {
    tree.k_nearest(q, k, max_dist2, out);
    let mut expected = brute_dist2(points, q, max_dist2);
    expected.truncate(k);
    check_neighbours_are_real(tree, q, out.as_slice());
    assert_eq!(
        sorted_dist2(out.as_slice()),
        expected,
        "k = {k}, max_dist2 = {max_dist2}, q = {q}"
    );
    assert_eq!(out.len(), expected.len());
    assert_eq!(out.is_empty(), expected.is_empty());
    assert_eq!(out.farthest().map(|n| n.dist2), expected.last().copied());
}

fn check_within(tree: &KdTree, points: &[Vec3], q: Vec3, radius2: f32, out: &mut Neighbours) {
    let expected: HashSet<u32> = (0..points.len() as u32)
        .filter(|&i| points[i as usize].distance_squared(q) <= radius2)
        .collect();

    tree.within_radius(q, radius2, out);
    check_neighbours_are_real(tree, q, out.as_slice());
    let found: HashSet<u32> = out
        .as_slice()
        .iter()
        .map(|n| tree.source_index(n.slot as usize))
        .collect();
    assert_eq!(found, expected, "radius2 = {radius2}, q = {q}");
    let farthest = sorted_dist2(out.as_slice()).last().copied();
    assert_eq!(out.farthest().map(|n| n.dist2), farthest);

    let mut visited = Vec::new();
    tree.for_each_within(q, radius2, |slot, dist2| {
        visited.push(Neighbour { dist2, slot })
    });
    check_neighbours_are_real(tree, q, &visited);
    let found: HashSet<u32> = visited
        .iter()
        .map(|n| tree.source_index(n.slot as usize))
        .collect();
    assert_eq!(found, expected);
}

/// The nearest point a predicate takes, against brute force: the least (distance, slot) among
/// the taken points within the limit. Taken: a slot-dependent half of the points (whether the
/// source index is even or odd), and a distance-dependent set (beyond a floor), so that the
/// search must pass over near points it may not take.
fn check_nearest_where(tree: &KdTree, points: &[Vec3], q: Vec3, max_dist2: f32, floor2: f32) {
    for parity in 0..2 {
        let takes =
            |slot: u32, d2: f32| tree.source_index(slot as usize) % 2 == parity && d2 >= floor2;
        let expected = (0..tree.len() as u32)
            .map(|slot| {
                let source = tree.source_index(slot as usize) as usize;
                (points[source].distance_squared(q), slot)
            })
            .filter(|&(d2, slot)| d2 <= max_dist2 && takes(slot, d2))
            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let found = tree.nearest_where(q, max_dist2, takes);
        assert_eq!(
            found.map(|n| (n.dist2, n.slot)),
            expected,
            "max_dist2 = {max_dist2}, floor2 = {floor2}, parity {parity}, q = {q}"
        );
    }
}

/// Builds the tree on `points` and checks every query type with several k and radii.
fn check_all(points: &[Vec3], query_count: usize, ks: &[usize], seed: u64) {
    let tree = KdTree::build(points);
    check_layout(&tree, points);
    let mut rng = Pcg32::new(seed ^ 0x9e37_79b9);
    let mut out = Neighbours::new();
    for q in queries(points, query_count, seed) {
        for &k in ks {
            check_k_nearest(&tree, points, q, k, f32::INFINITY, &mut out);
            let limit = 0.05 * rng.unit();
            check_k_nearest(&tree, points, q, k, limit * limit, &mut out);
        }
        let radius = 0.2 * rng.unit();
        check_within(&tree, points, q, radius * radius, &mut out);
        check_nearest_where(&tree, points, q, f32::INFINITY, 0.0);
        check_nearest_where(&tree, points, q, radius * radius, 0.0);
        check_nearest_where(&tree, points, q, f32::INFINITY, 0.01 * rng.unit());
        check_within(&tree, points, q, 0.0, &mut out);
        if !points.is_empty() {
            // Limits equal to a point's distance: both queries include the boundary.
            let exact = points[rng.below(points.len())].distance_squared(q);
            check_within(&tree, points, q, exact, &mut out);
            for &k in ks {
                check_k_nearest(&tree, points, q, k, exact, &mut out);
            }
        }
    }
}

const KS: [usize; 5] = [1, 7, 50, 400, 3000];

#[test]
fn random_points_of_every_size_match_brute_force() {
    for (n, queries) in [
        (0, 4),
        (1, 8),
        (2, 8),
        (3, 8),
        (13, 8),
        (1000, 40),
        (100_000, 12),
    ] {
        check_all(&random_box(n, n as u64 + 1), queries, &KS, n as u64);
    }
}

#[test]
fn points_on_two_planes_match_brute_force() {
    check_all(&two_planes(20_000, 7), 24, &KS, 7);
}

#[test]
fn points_on_an_axis_aligned_plane_match_brute_force() {
    check_all(&flat_plane(5_000, 8), 24, &KS, 8);
}

#[test]
fn points_on_a_line_match_brute_force() {
    check_all(&line(5_000, 9), 24, &KS, 9);
}

#[test]
fn duplicate_points_match_brute_force() {
    check_all(&duplicates(1_000), 12, &KS, 10);
    check_all(&duplicates(7), 12, &KS, 11);
}

#[test]
fn tied_coordinates_match_brute_force() {
    check_all(&grid_ties(3_000, 12), 24, &KS, 12);
}

#[test]
fn fewer_points_than_k_returns_them_all() {
    let points = random_box(30, 13);
    let tree = KdTree::build(&points);
    let mut out = Neighbours::with_capacity(100);
    tree.k_nearest(Vec3::splat(0.5), 100, f32::INFINITY, &mut out);
    assert_eq!(out.len(), 30);
    let expected = brute_dist2(&points, Vec3::splat(0.5), f32::INFINITY);
    assert_eq!(sorted_dist2(out.as_slice()), expected);
    assert_eq!(out.farthest().unwrap().dist2, *expected.last().unwrap());
}

#[test]
fn empty_tree_finds_nothing() {
    let tree = KdTree::build(&[]);
    assert!(tree.is_empty());
    assert_eq!(tree.len(), 0);
    let mut out = Neighbours::new();
    tree.k_nearest(Vec3::ZERO, 5, f32::INFINITY, &mut out);
    assert!(out.is_empty());
    assert_eq!(out.farthest(), None);
    tree.within_radius(Vec3::ZERO, 1.0, &mut out);
    assert!(out.is_empty());
    tree.for_each_within(Vec3::ZERO, 1.0, |_, _| panic!("empty tree visited a point"));
}

#[test]
fn nan_queries_k_zero_and_nan_limits_find_nothing() {
    let any = |_: u32, _: f32| true;
    let tree = KdTree::build(&random_box(100, 20));
    assert_eq!(tree.nearest_where(Vec3::NAN, f32::INFINITY, any), None);
    assert_eq!(tree.nearest_where(Vec3::ZERO, f32::NAN, any), None);
    assert_eq!(tree.nearest_where(Vec3::ZERO, -1.0, any), None);
    assert_eq!(KdTree::build(&[]).nearest_where(Vec3::ZERO, 1.0, any), None);
    let points = random_box(500, 14);
    let tree = KdTree::build(&points);
    let mut out = Neighbours::new();
    for q in [
        Vec3::NAN,
        Vec3::new(0.5, f32::NAN, 0.5),
        Vec3::new(f32::INFINITY, 0.0, 0.0),
    ] {
        tree.k_nearest(q, 10, f32::INFINITY, &mut out);
        assert!(out.is_empty());
        tree.within_radius(q, 10.0, &mut out);
        assert!(out.is_empty());
        tree.for_each_within(q, 10.0, |_, _| panic!("non-finite query found a point"));
    }
    tree.k_nearest(Vec3::splat(0.5), 0, f32::INFINITY, &mut out);
    assert!(out.is_empty());
    tree.k_nearest(Vec3::splat(0.5), 5, f32::NAN, &mut out);
    assert!(out.is_empty());
    tree.k_nearest(Vec3::splat(0.5), 5, -1.0, &mut out);
    assert!(out.is_empty());
    tree.within_radius(Vec3::splat(0.5), f32::NAN, &mut out);
    assert!(out.is_empty());
}

#[test]
fn non_finite_points_do_not_panic() {
    let mut points = random_box(3_000, 19);
    for i in (0..points.len()).step_by(97) {
        points[i] = [
            Vec3::NAN,
            Vec3::INFINITY,
            Vec3::new(0.5, f32::NEG_INFINITY, f32::NAN),
        ][i % 3];
    }
    let tree = KdTree::build(&points);
    let mut sources: Vec<u32> = (0..tree.len()).map(|s| tree.source_index(s)).collect();
    sources.sort_unstable();
    assert!(sources.iter().copied().eq(0..points.len() as u32));
    let mut out = Neighbours::new();
    for q in queries(&points[1..50], 20, 20) {
        tree.k_nearest(q, 30, f32::INFINITY, &mut out);
        assert!(out.as_slice().iter().all(|n| n.dist2.is_finite()));
        tree.within_radius(q, 0.01, &mut out);
        assert!(out.as_slice().iter().all(|n| n.dist2 <= 0.01));
    }
}

#[test]
fn reused_buffer_is_cleared_between_queries() {
    let points = random_box(2_000, 15);
    let tree = KdTree::build(&points);
    let mut out = Neighbours::new();
    tree.within_radius(Vec3::splat(0.5), 0.25, &mut out);
    assert!(out.len() > 50);
    check_k_nearest(&tree, &points, Vec3::splat(0.1), 7, f32::INFINITY, &mut out);
    out.clear();
    assert!(out.is_empty());
    assert_eq!(out.farthest(), None);
}

#[test]
fn sorted_neighbours_come_in_increasing_distance() {
    let points = two_planes(5_000, 16);
    let tree = KdTree::build(&points);
    let mut out = Neighbours::new();
    let q = Vec3::new(0.4, 0.6, 0.3);
    tree.k_nearest(q, 60, f32::INFINITY, &mut out);
    let farthest = out.farthest();
    out.sort_by_distance();
    let d: Vec<f32> = out.as_slice().iter().map(|n| n.dist2).collect();
    assert!(d.windows(2).all(|w| w[0] <= w[1]));
    assert_eq!(out.farthest().map(|n| n.dist2), farthest.map(|n| n.dist2));
    assert_eq!(d, brute_dist2(&points, q, f32::INFINITY)[..60]);
}

#[test]
fn construction_is_deterministic_across_thread_counts() {
    let points = two_planes(300_000, 17);
    let build_on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| KdTree::build(&points))
    };
    let one = build_on(1);
    let four = build_on(4);
    let slots: Vec<u32> = (0..one.len()).map(|s| one.source_index(s)).collect();
    assert!(
        (0..four.len())
            .map(|s| four.source_index(s))
            .eq(slots.iter().copied())
    );
    check_layout(&one, &points);
    let mut a = Neighbours::new();
    let mut b = Neighbours::new();
    for q in queries(&points, 20, 18) {
        one.k_nearest(q, 50, f32::INFINITY, &mut a);
        four.k_nearest(q, 50, f32::INFINITY, &mut b);
        assert_eq!(a.as_slice(), b.as_slice());
    }
}

fn small_point() -> impl Strategy<Value = Vec3> {
    // Coarse coordinates so that ties in coordinates and in distances are common.
    (-4i8..=4, -4i8..=4, -2i8..=2)
        .prop_map(|(x, y, z)| Vec3::new(x as f32, y as f32, z as f32 * 0.5))
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 128, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn any_small_point_set_matches_brute_force(
        points in prop::collection::vec(small_point(), 0..200),
        q in small_point(),
        jitter in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        k in 0usize..60,
        max_dist2 in prop_oneof![Just(f32::INFINITY), 0.0f32..20.0],
    ) {
        let tree = KdTree::build(&points);
        check_layout(&tree, &points);
        let mut out = Neighbours::new();
        for q in [q, q + Vec3::from(jitter) * 0.5] {
            check_k_nearest(&tree, &points, q, k, max_dist2, &mut out);
            check_within(&tree, &points, q, max_dist2.min(50.0), &mut out);
            check_nearest_where(&tree, &points, q, max_dist2, 0.0);
            check_nearest_where(&tree, &points, q, max_dist2, 1.0);
        }
    }
}
