//! The edge cut (`--edge-cut`): where the structure tensor sees an edge, locate it as a step in
//! the photon density and keep the estimate on the query's side of it. The step is fitted by
//! maximum likelihood to another map's photons (the tensor history, never the photons the
//! estimate sums, so the cut cannot lean on their noise) within the kernel's disc, along the
//! tensor's across-edge direction turned by up to ±0.3 rad; a second step inside the query's
//! side makes the side a strip (a thin line's other edge). The estimate is then the round
//! kernel restricted to that strip, divided by the kernel's share inside it: unbiased for a
//! density that is constant across the strip, with the photons of a round kernel rather than
//! of an ellipse squeezed across the edge, and no spill over the edge however close the query
//! lies to it. Owns the step fit, the strip and the truncated kernel's mass; must not sum the
//! estimate or touch the tensor.

use super::super::Query;
use super::super::classic::{PhotonReader, power_of};
use super::super::kernel::epanechnikov_share_below;
use crate::photon::PhotonMap;
use glam::DVec3;
use std::f64::consts::PI;

/// The squeeze below which a kernel looks for an edge: the tensor sees some structure.
pub const GATE_LAMBDA2: f32 = 0.9;
/// Least log-likelihood gain, in photon counts, of a step over a flat density for a cut.
/// A cut from independent photons leaves a flat density's estimate unbiased, so a false one
/// costs only variance; 5 (a likelihood ratio of e⁵) took the constructed distribution's edge
/// band lower than 30 did (BENCHMARKS.md).
pub const MIN_GAIN: f64 = 5.0;
/// Least gain of the second step, inside the query's side: a false one there would leave the
/// estimate a sliver of the disc (unbiased still, but noisy), so it must be clearer.
pub const MIN_SECOND_GAIN: f64 = 3.0 * MIN_GAIN;
/// Fewest photons on either side of a step.
pub const MIN_SIDE: usize = 5;
/// How far the step's normal may turn from the tensor's `X2` (radians), and in what steps:
/// late passes' tensors point up to 0.3 rad off a straight edge.
pub const MAX_TURN: f64 = 0.3;
pub const TURN_STEP: f64 = 0.05;

/// The part of the kernel's disc the estimate keeps: offsets `d` with `lo < d · across < hi`
/// (the query, at 0, inside).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Strip {
    pub across: DVec3,
    pub lo: f64,
    pub hi: f64,
}

impl Strip {
    #[inline]
    pub fn keeps(&self, d: DVec3) -> bool {
        let t = d.dot(self.across);
        t > self.lo && t < self.hi
    }

    /// The share of a round Epanechnikov kernel of radius `r` inside the strip.
    pub fn epanechnikov_share(&self, r: f64) -> f64 {
        epanechnikov_share_below(self.hi / r) - epanechnikov_share_below(self.lo / r)
    }
}

/// Per-query buffers of the fit: (offset along `X2`, along `X1`, weight) of each photon, and
/// (offset along the turned normal, weight).
#[derive(Clone, Debug, Default)]
pub struct EdgeScratch {
    points: Vec<(f64, f64, f64)>,
    samples: Vec<(f64, f64)>,
}

/// The strip of the disc of radius `√r2` round `query` on the query's side of the steps that
/// `analysis`'s photons show across `x2` (`x1` along the edge), or `None` where no step is
/// clear or the strip is the whole disc.
pub fn locate(
    analysis: &PhotonMap,
    query: &Query,
    (x1, x2): (DVec3, DVec3),
    r2: f64,
    scratch: &mut EdgeScratch,
) -> Option<Strip> {
    let r = r2.sqrt();
    let EdgeScratch { points, samples } = scratch;
    points.clear();
    let mut reader = PhotonReader::new(query.normal);
    analysis
        .tree()
        .for_each_within(query.position, r2 as f32, |slot, _| {
            let photon = analysis.attributes(slot);
            if reader.agrees(photon) {
                let d = (analysis.position(slot) - query.position).as_dvec3();
                points.push((d.dot(x2), d.dot(x1), power_of(photon).element_sum()));
            }
        });
    let turns = (MAX_TURN / TURN_STEP).round() as i32;
    let mut best: Option<(f64, f64, DVec3, (f64, f64))> = None;
    for turn in -turns..=turns {
        let (sin, cos) = (f64::from(turn) * TURN_STEP).sin_cos();
        samples.clear();
        samples.extend(points.iter().map(|&(t, u, w)| (t * cos + u * sin, w)));
        if let Some((e, gain)) = fit_step(samples, r, (-r, r), MIN_SIDE)
            && best.is_none_or(|b| gain > b.1)
        {
            best = Some((e, gain, x2 * cos + x1 * sin, (sin, cos)));
        }
    }
    let (e, gain, across, (sin, cos)) = best?;
    if gain < MIN_GAIN {
        return None;
    }
    let (mut lo, mut hi) = if e > 0.0 { (-r, e) } else { (e, r) };
    // A second step on the query's side.
    samples.clear();
    samples.extend(
        (points.iter())
            .map(|&(t, u, w)| (t * cos + u * sin, w))
            .filter(|&(t, _)| t > lo && t < hi),
    );
    if let Some((e, gain)) = fit_step(samples, r, (lo, hi), MIN_SIDE)
        && gain >= MIN_SECOND_GAIN
    {
        if e > 0.0 {
            hi = e;
        } else {
            lo = e;
        }
    }
    Some(Strip { across, lo, hi })
}

/// Area of the part `x < e` of the disc of radius `r` centred at 0.
fn area_below(e: f64, r: f64) -> f64 {
    let e = e.clamp(-r, r);
    let past = r * r * (e / r).acos() - e * (r * r - e * e).max(0.0).sqrt();
    PI * r * r - past
}

/// The step that best explains `(t, w)` (offset along a direction, weight), all within the
/// strip `lo < t < hi` of the disc of radius `r`: a density constant on either side of an
/// offset `e`, against one constant over the strip. Returns `e` and the log-likelihood gain in
/// photon counts (the weights' gain scaled by count over weight); `None` when fewer than
/// `min_side` photons would lie on either side of every candidate. Sorts `samples`.
pub fn fit_step(
    samples: &mut [(f64, f64)],
    r: f64,
    (lo, hi): (f64, f64),
    min_side: usize,
) -> Option<(f64, f64)> {
    let n = samples.len();
    if n < 2 * min_side.max(1) {
        return None;
    }
    samples.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let total: f64 = samples.iter().map(|s| s.1).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let base = area_below(lo, r);
    let area = area_below(hi, r) - base;
    // W ln(W/A): the Poisson log-likelihood of weight W on area A at its best density, up to
    // terms that do not depend on the split.
    let xlogx = |w: f64, a: f64| {
        if w > 0.0 && a > 0.0 {
            w * (w / a).ln()
        } else {
            0.0
        }
    };
    let flat = xlogx(total, area);
    let mut below = 0.0;
    let mut best: Option<(f64, f64)> = None;
    for k in 0..n - 1 {
        below += samples[k].1;
        if k + 1 < min_side || n - k - 1 < min_side {
            continue;
        }
        let e = 0.5 * (samples[k].0 + samples[k + 1].0);
        let a1 = area_below(e, r) - base;
        let gain = xlogx(below, a1) + xlogx(total - below, area - a1) - flat;
        if best.is_none_or(|(_, g)| gain > g) {
            best = Some((e, gain));
        }
    }
    best.map(|(e, g)| (e, g * n as f64 / total))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segment_areas_add_up_to_the_disc() {
        assert!((area_below(0.0, 2.0) - 2.0 * PI).abs() < 1e-12);
        assert!((area_below(2.0, 2.0) - 4.0 * PI).abs() < 1e-12);
        assert!((area_below(0.7, 2.0) + area_below(-0.7, 2.0) - 4.0 * PI).abs() < 1e-12);
    }

    /// `n` points uniform in the unit disc, the part with `x > edge` kept with probability
    /// `dim`: their x offsets.
    fn step_samples(n: usize, edge: f64, dim: f64, seed: u64) -> Vec<(f64, f64)> {
        let mut i = 0u64;
        let mut uniform = || {
            i += 1;
            (crate::sampling::mix(i, seed) >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut out = Vec::new();
        while out.len() < n {
            let (x, y) = (2.0 * uniform() - 1.0, 2.0 * uniform() - 1.0);
            if x * x + y * y < 1.0 && (x < edge || uniform() < dim) {
                out.push((x, 1.0));
            }
        }
        out
    }

    #[test]
    fn a_step_is_found_where_it_is_and_a_flat_density_shows_little_gain() {
        for (seed, edge) in [(1, 0.03), (2, -0.4), (3, 0.3)] {
            let mut s = step_samples(400, edge, 0.1, seed);
            let (e, gain) = fit_step(&mut s, 1.0, (-1.0, 1.0), MIN_SIDE).unwrap();
            // The photons nearest the edge on the bright side are about 1/(ρ chord) apart.
            assert!((e - edge).abs() < 0.02, "edge {edge}: fitted {e}");
            assert!(gain > 10.0 * MIN_GAIN, "gain {gain}");
        }
        let mut flat_gains: Vec<f64> = (0..40)
            .map(|seed| {
                let mut s = step_samples(400, 2.0, 1.0, 100 + seed);
                fit_step(&mut s, 1.0, (-1.0, 1.0), MIN_SIDE).unwrap().1
            })
            .collect();
        flat_gains.sort_by(f64::total_cmp);
        // The largest of ~400 split points' likelihood ratios: a few units, rarely past 5.
        assert!(flat_gains[20] < MIN_GAIN, "{flat_gains:?}");
        // Within a strip the areas are the strip's: a flat strip gains little too.
        let mut strip: Vec<(f64, f64)> = step_samples(2000, 2.0, 1.0, 7)
            .into_iter()
            .filter(|&(t, _)| t > -0.2 && t < 0.5)
            .collect();
        let (_, gain) = fit_step(&mut strip, 1.0, (-0.2, 0.5), MIN_SIDE).unwrap();
        assert!(gain < 3.0 * MIN_GAIN, "strip gain {gain}");
        assert!(fit_step(&mut [(0.0, 1.0); 9], 1.0, (-1.0, 1.0), MIN_SIDE).is_none());
    }

    #[test]
    fn a_strip_keeps_what_lies_between_its_bounds() {
        let strip = Strip {
            across: DVec3::X,
            lo: -0.5,
            hi: 0.25,
        };
        assert!(strip.keeps(DVec3::new(0.2, 3.0, 0.0)));
        assert!(!strip.keeps(DVec3::new(0.3, 0.0, 0.0)));
        assert!(!strip.keeps(DVec3::new(-0.6, 0.0, 0.0)));
        let share = strip.epanechnikov_share(1.0);
        let expected = epanechnikov_share_below(0.25) - epanechnikov_share_below(-0.5);
        assert!((share - expected).abs() < 1e-15 && share > 0.0 && share < 1.0);
    }
}
