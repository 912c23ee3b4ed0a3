use super::*;
use crate::sampling::{Rng, Stream};

fn rng(seed: u64) -> Rng {
    Rng::for_index(seed, Stream::Distribution, 0)
}

fn random_unit(rng: &mut Rng) -> Vec3 {
    let (u, v) = rng.next_2d();
    let z = 1.0 - 2.0 * u;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * v;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

fn random_point(rng: &mut Rng, size: f32) -> Vec3 {
    Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * size - Vec3::splat(size / 2.0)
}

/// Points, spheres, flat emitters one- and two-sided and spots, some without power.
fn lights(count: usize, rng: &mut Rng) -> Vec<LightBounds> {
    (0..count)
        .map(|i| {
            let p = random_point(rng, 10.0);
            let phi = if i % 17 == 5 {
                0.0
            } else {
                0.1 + rng.next_f32()
            };
            match i % 4 {
                0 => LightBounds::everywhere(p, p, phi),
                1 => LightBounds::everywhere(p - 0.2, p + 0.2, phi),
                2 => {
                    let q = p + random_point(rng, 0.5);
                    LightBounds::flat(p.min(q), p.max(q), phi, random_unit(rng), i % 8 == 2)
                }
                _ => LightBounds {
                    lo: p,
                    hi: p,
                    phi,
                    axis: random_unit(rng),
                    cos_normals: 0.9,
                    cos_emission: 0.95,
                    two_sided: false,
                },
            }
        })
        .collect()
}

#[test]
fn the_probabilities_of_all_entries_sum_to_one_and_match_the_draws() {
    let mut rng = rng(3);
    for count in [1, 2, 3, 9, 64, 300] {
        let entries = lights(count, &mut rng);
        let tree = LightTree::build(&entries).unwrap();
        for _ in 0..40 {
            let p = random_point(&mut rng, 14.0);
            let n = if rng.next_f32() < 0.2 {
                Vec3::ZERO
            } else {
                random_unit(&mut rng)
            };
            let pmfs: Vec<f32> = (0..count).map(|e| tree.pmf(p, n, e)).collect();
            let total: f32 = pmfs.iter().sum();
            // A group's bound may allow light its members do not: the draw then finds none.
            assert!(
                total <= 1.0 + 1e-4,
                "{count} lights at {p}: Σ pmf = {total}"
            );
            for (e, b) in entries.iter().enumerate() {
                if b.importance(p, n) > 0.0 {
                    assert!(pmfs[e] > 0.0, "light {e} can reach {p} but is never drawn");
                }
            }
            for (e, b) in entries.iter().enumerate() {
                if b.phi == 0.0 {
                    assert_eq!(pmfs[e], 0.0, "an entry without power is drawn");
                }
            }
            for k in 0..16 {
                let u = (k as f32 + rng.next_f32()) / 16.0;
                if let Some((e, pmf)) = tree.sample(p, n, u) {
                    let again = pmfs[e];
                    assert!(
                        (pmf - again).abs() <= 1e-5 * again.max(1e-3),
                        "{pmf} vs {again}"
                    );
                }
            }
        }
    }
}

#[test]
fn draws_land_as_often_as_their_probabilities_say() {
    let mut rng = rng(11);
    let entries = lights(40, &mut rng);
    let tree = LightTree::build(&entries).unwrap();
    let (p, n) = (Vec3::new(0.3, -1.0, 0.2), Vec3::Y);
    let draws = 200_000;
    let mut counts = vec![0u32; entries.len() + 1];
    for k in 0..draws {
        let u = (k as f32 + 0.5) / draws as f32;
        counts[tree.sample(p, n, u).map_or(entries.len(), |(e, _)| e)] += 1;
    }
    let none = f64::from(counts.pop().unwrap()) / draws as f64;
    let total: f64 = (0..entries.len())
        .map(|e| f64::from(tree.pmf(p, n, e)))
        .sum();
    assert!(
        (none - (1.0 - total)).abs() < 2e-3,
        "no light drawn {none}, 1 − Σ pmf {}",
        1.0 - total
    );
    // Chi-square over the entries expecting at least 5 draws.
    let (mut chi2, mut cells) = (0.0f64, 0);
    for (e, &c) in counts.iter().enumerate() {
        let expected = f64::from(tree.pmf(p, n, e)) * draws as f64;
        if expected >= 5.0 {
            chi2 += (f64::from(c) - expected).powi(2) / expected;
            cells += 1;
        } else {
            assert!(
                f64::from(c) <= expected + 12.0,
                "entry {e}: {c} draws, {expected} due"
            );
        }
    }
    // Stratified u: far below the 0.1% tail of χ² (≈ cells + 3.1√(2 cells)).
    assert!(
        chi2 < cells as f64 + 3.1 * (2.0 * cells as f64).sqrt(),
        "χ² {chi2} over {cells}"
    );
}

#[test]
fn a_point_lights_importance_is_its_power_over_the_squared_distance_times_the_cosine() {
    let light = LightBounds::everywhere(Vec3::new(0.0, 4.0, 0.0), Vec3::new(0.0, 4.0, 0.0), 3.0);
    let p = Vec3::new(3.0, 0.0, 0.0);
    let n = Vec3::Y;
    let d = Vec3::new(-3.0, 4.0, 0.0);
    let expected = 3.0 / d.length_squared() * n.dot(d.normalize());
    assert!((light.importance(p, n) - expected).abs() < 1e-6);
    // In a medium every side counts.
    assert!((light.importance(p, Vec3::ZERO) - 3.0 / 25.0).abs() < 1e-6);
}

#[test]
fn a_one_sided_emitter_gives_nothing_behind_it_and_a_spot_nothing_outside_its_cone() {
    let quad = LightBounds::flat(
        Vec3::new(-1.0, 2.0, -1.0),
        Vec3::new(1.0, 2.0, 1.0),
        1.0,
        Vec3::NEG_Y,
        false,
    );
    assert!(quad.importance(Vec3::ZERO, Vec3::Y) > 0.0);
    assert_eq!(quad.importance(Vec3::new(0.0, 6.0, 0.0), Vec3::Y), 0.0);
    let both = LightBounds {
        two_sided: true,
        ..quad
    };
    assert!(both.importance(Vec3::new(0.0, 6.0, 0.0), Vec3::Y) > 0.0);
    let spot = LightBounds {
        lo: Vec3::ZERO,
        hi: Vec3::ZERO,
        phi: 1.0,
        axis: Vec3::NEG_Y,
        cos_normals: 30f32.to_radians().cos(),
        cos_emission: 5f32.to_radians().cos(),
        two_sided: false,
    };
    assert!(spot.importance(Vec3::new(0.0, -3.0, 1.0), Vec3::Y) > 0.0);
    assert_eq!(spot.importance(Vec3::new(0.0, -3.0, 3.0), Vec3::Y), 0.0);
    let tree = LightTree::build(&[spot, quad]).unwrap();
    assert_eq!(tree.pmf(Vec3::new(0.0, -3.0, 3.0), Vec3::Y, 0), 0.0);
    assert_eq!(tree.pmf(Vec3::new(0.0, -3.0, 3.0), Vec3::Y, 1), 1.0);
}

#[test]
fn the_union_of_two_cones_holds_every_direction_of_both() {
    let mut rng = rng(5);
    for _ in 0..500 {
        let a = (random_unit(&mut rng), rng.next_f32() * 2.0 - 1.0);
        let b = (random_unit(&mut rng), rng.next_f32() * 2.0 - 1.0);
        let (axis, cos) = cone_union(a, b);
        for (w, c) in [a, b] {
            // The cone's rim: directions at its half-angle all round.
            let t = w.any_orthonormal_vector();
            let s = sin_of(c);
            for k in 0..8 {
                let turn = glam::Quat::from_axis_angle(w, k as f32 * PI / 4.0);
                let d = (w * c + turn * t * s).normalize();
                assert!(
                    axis.dot(d) >= cos - 1e-3,
                    "{d} outside the union of {a:?} and {b:?}"
                );
            }
        }
    }
}

#[test]
fn the_tree_over_many_point_lights_prefers_the_near_ones() {
    // A row of equal lights: a point under one end draws that end far more often.
    let entries: Vec<LightBounds> = (0..64)
        .map(|i| {
            let p = Vec3::new(i as f32, 1.0, 0.0);
            LightBounds::everywhere(p, p, 1.0)
        })
        .collect();
    let tree = LightTree::build(&entries).unwrap();
    let p = Vec3::ZERO;
    assert!(tree.pmf(p, Vec3::Y, 0) > 20.0 * tree.pmf(p, Vec3::Y, 63));
}
