//! dpm's kd-tree against kiddo's `ImmutableKdTree` (f32, 3-D, squared Euclidean) on the same
//! photon-like data: 1M points on two surfaces with caustic-like clusters, queried at points on
//! those surfaces. Both sides run the same batch of queries the same way (rayon over chunks,
//! one reusable scratch per chunk, unsorted results), and must agree on every query's k-th
//! distance before anything is timed. `ImmutableKdTree` is kiddo's recommended type for a tree
//! built once and then queried; its other layouts (flat leaves, Donnelly stems, leaves of 16 or
//! 64) measured within 10% of it on this data.
//!
//! `cargo bench --bench kdtree`. Samples are few and short so that the whole run takes a few
//! minutes on two cores; on a shared machine compare medians across runs, not single runs.

mod support;

use support::Rng;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use dpm::photon::{KdTree, Neighbours};
use glam::Vec3;
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use std::hint::black_box;
use std::num::NonZeroUsize;
use std::time::Duration;

const PHOTONS: usize = 1_000_000;
const QUERIES: usize = 1 << 14;
const QUERY_CHUNK: usize = 64;
const KS: [usize; 3] = [50, 200, 400];

/// A point on one of two surfaces: a tilted floor and an axis-aligned wall.
fn on_surface(u: f32, v: f32, wall: bool) -> Vec3 {
    if wall {
        Vec3::new(u, 0.95, v)
    } else {
        Vec3::new(u, v, 0.3 * u + 0.2 * v + 0.1)
    }
}

/// Photon-like positions: a fifth on the wall, the rest on the floor, of which half gathered
/// in caustic-like blobs (sums of uniforms: roughly Gaussian, strongly non-uniform density).
fn photons(n: usize) -> Vec<Vec3> {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let centres = [(0.3, 0.4, 0.05), (0.7, 0.6, 0.02), (0.5, 0.2, 0.1)];
    (0..n)
        .map(|i| {
            if i % 5 == 4 {
                return on_surface(rng.unit(), rng.unit(), true);
            }
            if i % 2 == 0 {
                return on_surface(rng.unit(), rng.unit(), false);
            }
            let (cu, cv, spread) = centres[i % 3];
            let mut blob = || (rng.unit() + rng.unit() + rng.unit() - 1.5) * spread;
            let (u, v) = (cu + blob(), cv + blob());
            on_surface(u, v, false)
        })
        .collect()
}

/// Query points spread uniformly over both surfaces, like camera-ray hits.
fn queries(n: usize) -> Vec<Vec3> {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    (0..n)
        .map(|i| on_surface(rng.unit(), rng.unit(), i % 5 == 4))
        .collect()
}

fn dpm_queries(tree: &KdTree, queries: &[Vec3], k: usize) -> f64 {
    queries
        .par_chunks(QUERY_CHUNK)
        .map_init(
            || Neighbours::with_capacity(k),
            |out, chunk| {
                let mut sum = 0.0f64;
                for &q in chunk {
                    tree.k_nearest(q, k, f32::INFINITY, out);
                    sum += out.farthest().map_or(0.0, |n| n.dist2 as f64);
                }
                sum
            },
        )
        .sum()
}

type Kiddo = ImmutableKdTree<f32, 3>;

fn kiddo_queries(tree: &Kiddo, queries: &[[f32; 3]], k: usize) -> f64 {
    let k = NonZeroUsize::new(k).unwrap();
    queries
        .par_chunks(QUERY_CHUNK)
        .map_init(
            || tree.create_scratch::<SquaredEuclidean<f32>>(),
            |scratch, chunk| {
                let mut sum = 0.0f64;
                for q in chunk {
                    let found = tree
                        .query(q)
                        .nearest_n::<SquaredEuclidean<f32>>(k)
                        .unsorted()
                        .with_scratch(scratch)
                        .execute();
                    sum += found.iter().map(|n| n.distance).fold(0.0f32, f32::max) as f64;
                }
                sum
            },
        )
        .sum()
}

fn kdtree(c: &mut Criterion) {
    let points = photons(PHOTONS);
    let points_arr: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    let queries = queries(QUERIES);
    let queries_arr: Vec<[f32; 3]> = queries.iter().map(|p| p.to_array()).collect();

    let mut build = c.benchmark_group("kdtree_build_1M");
    build
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(5));
    build.throughput(Throughput::Elements(PHOTONS as u64));
    build.bench_function("dpm", |b| b.iter(|| KdTree::build(black_box(&points))));
    build.bench_function("kiddo", |b| {
        b.iter(|| Kiddo::new_from_slice_parallel(black_box(&points_arr)).unwrap())
    });
    build.finish();

    let dpm_tree = KdTree::build(&points);
    let kiddo_tree = Kiddo::new_from_slice_parallel(&points_arr).unwrap();
    // Same answers (k-th distance of every query) before timing anything.
    for k in KS {
        let (a, b) = (
            dpm_queries(&dpm_tree, &queries, k),
            kiddo_queries(&kiddo_tree, &queries_arr, k),
        );
        assert!(
            (a - b).abs() <= 1e-9 * a.abs(),
            "k = {k}: dpm {a} vs kiddo {b}"
        );
    }

    let mut knn = c.benchmark_group("kdtree_k_nearest_1M_16k_queries");
    knn.sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8));
    knn.throughput(Throughput::Elements(QUERIES as u64));
    for k in KS {
        knn.bench_with_input(BenchmarkId::new("dpm", k), &k, |b, &k| {
            b.iter(|| dpm_queries(&dpm_tree, black_box(&queries), k))
        });
        knn.bench_with_input(BenchmarkId::new("kiddo", k), &k, |b, &k| {
            b.iter(|| kiddo_queries(&kiddo_tree, black_box(&queries_arr), k))
        });
    }
    knn.finish();
}

criterion_group!(benches, kdtree);
criterion_main!(benches);
