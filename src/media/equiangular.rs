//! Where along a ray a small light's single scattering is sampled: equiangular sampling (Kulla
//! and Fajardo 2012), a distance with density ∝ 1/|x(t) − c|² about the light's centre c, which
//! cancels the inverse square of the light's falloff; and, for a spot light, the stretch of the
//! ray inside its cone, outside which it sends nothing (a narrow beam would otherwise catch few
//! of the samples drawn along the whole ray).

use glam::Vec3;

/// A distance along `origin + t·dir` (unit `dir`) in (`t0`, `t1`) drawn from `u` with density
/// ∝ 1/|x(t) − c|², and that density; `None` where the stretch is empty or passes through `c`.
pub fn equiangular(
    origin: Vec3,
    dir: Vec3,
    c: Vec3,
    (t0, t1): (f32, f32),
    u: f32,
) -> Option<(f32, f32)> {
    let delta = (c - origin).dot(dir);
    let h = (origin + delta * dir - c).length();
    let t1 = t1.min(delta + 1e7 * h.max(1e-6));
    if t1.partial_cmp(&t0) != Some(std::cmp::Ordering::Greater) || h <= 0.0 {
        return None;
    }
    let (a, b) = (((t0 - delta) / h).atan(), ((t1 - delta) / h).atan());
    let theta = a + u * (b - a);
    let t = (delta + h * theta.tan()).clamp(t0, t1);
    let density = pdf(delta, h, (a, b), t);
    (density > 0.0).then_some((t, density))
}

/// The density [`equiangular`] gives `t`.
fn pdf(delta: f32, h: f32, (a, b): (f32, f32), t: f32) -> f32 {
    let r2 = h * h + (t - delta) * (t - delta);
    let p = h / ((b - a) * r2);
    if p.is_finite() { p } else { 0.0 }
}

/// The part of (`t0`, `t1`) along `origin + t·dir` (unit `dir`) inside the cone of apex
/// `apex`, unit `axis` and half-angle cosine `cos` (a convex cone: `cos` ≥ 0; a wider one is
/// given back whole), or `None` where the ray misses it.
pub fn within_cone(
    origin: Vec3,
    dir: Vec3,
    (apex, axis, cos): (Vec3, Vec3, f32),
    (t0, t1): (f32, f32),
) -> Option<(f32, f32)> {
    if cos <= 0.0 {
        return Some((t0, t1));
    }
    // Inside: ((v + t d)·a)² ≥ cos² |v + t d|² on the front nappe, (v + t d)·a ≥ 0.
    let v = origin - apex;
    let (da, va, c2) = (dir.dot(axis), v.dot(axis), cos * cos);
    let qa = da * da - c2;
    let qb = 2.0 * (da * va - c2 * dir.dot(v));
    let qc = va * va - c2 * v.length_squared();
    // Where the quadratic is ≥ 0, as intervals.
    let mut spans: [(f32, f32); 2] = [(f32::NAN, f32::NAN); 2];
    let disc = qb * qb - 4.0 * qa * qc;
    if qa.abs() < 1e-12 {
        // Parallel to the cone's side: one root.
        if qb.abs() > 0.0 {
            let r = -qc / qb;
            spans[0] = if qb > 0.0 {
                (r, f32::INFINITY)
            } else {
                (f32::NEG_INFINITY, r)
            };
        } else if qc >= 0.0 {
            spans[0] = (f32::NEG_INFINITY, f32::INFINITY);
        }
    } else if disc < 0.0 {
        if qa > 0.0 {
            spans[0] = (f32::NEG_INFINITY, f32::INFINITY);
        }
    } else {
        let s = disc.sqrt();
        let q = -0.5 * (qb + qb.signum() * s);
        let (mut r0, mut r1) = (q / qa, if q != 0.0 { qc / q } else { -qb / (2.0 * qa) });
        if r0 > r1 {
            std::mem::swap(&mut r0, &mut r1);
        }
        if qa > 0.0 {
            spans = [(f32::NEG_INFINITY, r0), (r1, f32::INFINITY)];
        } else {
            spans[0] = (r0, r1);
        }
    }
    // The front nappe: the half-space the axis points into.
    let front = if da > 0.0 {
        (-va / da, f32::INFINITY)
    } else if da < 0.0 {
        (f32::NEG_INFINITY, -va / da)
    } else if va >= 0.0 {
        (f32::NEG_INFINITY, f32::INFINITY)
    } else {
        return None;
    };
    let mut best: Option<(f32, f32)> = None;
    for (lo, hi) in spans {
        if lo.is_nan() {
            continue;
        }
        let (lo, hi) = (lo.max(front.0).max(t0), hi.min(front.1).min(t1));
        if hi > lo && best.is_none_or(|(a, b)| hi - lo > b - a) {
            best = Some((lo, hi));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Rng, Stream, StreamSeed};

    #[test]
    fn equiangular_samples_follow_their_density_which_integrates_to_one() {
        let (o, d, c) = (Vec3::new(-2.0, 0.0, 0.0), Vec3::X, Vec3::new(0.5, 0.7, 0.0));
        let (t0, t1) = (0.3, 5.0);
        let mut rng = StreamSeed::new(3, Stream::CausticPhotons).rng(0);
        let bins = 20;
        let mut counts = vec![0usize; bins];
        let n = 200_000;
        for _ in 0..n {
            let (t, _) = equiangular(o, d, c, (t0, t1), rng.next_f32()).unwrap();
            assert!((t0..=t1).contains(&t));
            counts[(((t - t0) / (t1 - t0)) * bins as f32).min(bins as f32 - 1.0) as usize] += 1;
        }
        // The density, integrated per bin by the midpoint rule, against the counts.
        let density = |t: f32| equiangular_density(o, d, c, (t0, t1), t);
        let mut total = 0.0;
        for (k, &count) in counts.iter().enumerate() {
            let (lo, hi) = (
                t0 + (t1 - t0) * k as f32 / bins as f32,
                t0 + (t1 - t0) * (k + 1) as f32 / bins as f32,
            );
            let steps = 200;
            let p: f64 = (0..steps)
                .map(|i| f64::from(density(lo + (hi - lo) * (i as f32 + 0.5) / steps as f32)))
                .sum::<f64>()
                * f64::from(hi - lo)
                / steps as f64;
            total += p;
            let want = p * n as f64;
            assert!(
                (count as f64 - want).abs() < 5.0 * want.sqrt() + 5.0,
                "bin {k}: {count} against {want}"
            );
        }
        assert!((total - 1.0).abs() < 1e-3, "{total}");
    }

    /// The density [`equiangular`] draws `t` with.
    fn equiangular_density(o: Vec3, d: Vec3, c: Vec3, (t0, t1): (f32, f32), t: f32) -> f32 {
        let delta = (c - o).dot(d);
        let h = (o + delta * d - c).length();
        let (a, b) = (((t0 - delta) / h).atan(), ((t1 - delta) / h).atan());
        pdf(delta, h, (a, b), t)
    }

    #[test]
    fn the_stretch_inside_a_cone_is_what_brute_force_finds() {
        let mut rng: Rng = StreamSeed::new(5, Stream::CausticPhotons).rng(1);
        let unit = |rng: &mut Rng| {
            Vec3::new(
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
                rng.next_f32() - 0.5,
            )
            .normalize()
        };
        for case in 0..2000 {
            let apex = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
            let axis = unit(&mut rng);
            let cos = 0.05 + 0.94 * rng.next_f32();
            let origin = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 6.0 - 3.0;
            let dir = unit(&mut rng);
            let (t0, t1) = (0.0, 8.0);
            let inside = |t: f32| {
                let w = origin + t * dir - apex;
                w.dot(axis) >= cos * w.length()
            };
            let found = within_cone(origin, dir, (apex, axis, cos), (t0, t1));
            let steps = 4000;
            let ts = (0..steps).map(|i| t0 + (t1 - t0) * (i as f32 + 0.5) / steps as f32);
            let hits: Vec<f32> = ts.filter(|&t| inside(t)).collect();
            let dt = (t1 - t0) / steps as f32;
            match (found, hits.first(), hits.last()) {
                (None, None, None) => {}
                (Some((lo, hi)), Some(&a), Some(&b)) => {
                    assert!(
                        (lo - a).abs() <= 2.0 * dt && (hi - b).abs() <= 2.0 * dt,
                        "case {case}: {lo}..{hi} against {a}..{b}"
                    );
                }
                (found, a, b) => {
                    // A graze shorter than a step may go either way.
                    let short = found.is_none_or(|(lo, hi)| hi - lo < 2.0 * dt) && hits.len() <= 2;
                    assert!(short, "case {case}: {found:?} against {a:?}..{b:?}");
                }
            }
        }
    }
}
