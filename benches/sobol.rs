//! One Owen-scrambled Sobol point, as camera samples (four dimensions) and light samples (two)
//! draw them: `sampling::sobol` against the `sobol_burley` crate's `sample_4d`, which gives the
//! same numbers bit for bit (`sampling::sobol`'s test). A batch is 4096 points of one thread,
//! indices and seeds as a pixel's samples vary them.
//!
//! `cargo bench --bench sobol` (under a minute).

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use dpm::sampling::sobol;
use std::hint::black_box;

const BATCH: u32 = 4096;

fn seed_of(i: u32) -> u32 {
    i.wrapping_mul(0x9E37_79B9) ^ 0x5bd1_e995
}

fn points(c: &mut Criterion) {
    let mut group = c.benchmark_group("sobol point");
    group.throughput(Throughput::Elements(u64::from(BATCH)));
    group.bench_function("sobol_burley::sample_4d", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for i in 0..BATCH {
                let p = sobol_burley::sample_4d(black_box((i * 13) & 0xffff), 0, seed_of(i));
                sum += p[0] + p[1] + p[2] + p[3];
            }
            sum
        })
    });
    group.bench_function("sampling::sobol::sample_4d", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for i in 0..BATCH {
                let p = sobol::sample_4d(black_box((i * 13) & 0xffff), seed_of(i));
                sum += p[0] + p[1] + p[2] + p[3];
            }
            sum
        })
    });
    group.bench_function("sampling::sobol::sample_2d", |b| {
        b.iter(|| {
            let mut sum = 0.0f32;
            for i in 0..BATCH {
                let p = sobol::sample_2d(black_box((i * 13) & 0xffff), seed_of(i));
                sum += p[0] + p[1];
            }
            sum
        })
    });
    group.finish();
}

criterion_group!(benches, points);
criterion_main!(benches);
