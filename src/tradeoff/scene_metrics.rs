//! Errors of a rendered caustic image against a reference image, and the regions they use,
//! defined from the reference alone (a scene has no exact density). Owns those definitions and
//! the arithmetic; it must not render, trace or read files.
//!
//! Values are the mean of the RGB channels of the caustic contribution (radiance).
//! - *lit*: reference ≥ [`LIT_FRACTION`] × the reference's bright level (its 99.5th
//!   percentile over the pixels it lights at all, so one firefly does not set the scale).
//! - *edge*: a pixel where the reference changes fast relative to itself: with `S` the 3×3 mean
//!   of the reference (less noisy than the reference), |∇S| by central differences (per pixel)
//!   over `S` at the pixel (floored at the lit threshold, so the dark side of an edge does not
//!   divide by zero) is at least [`EDGE_RELATIVE_GRADIENT`] (a 20% change per pixel), and the
//!   pixel or one of its 8 neighbours is lit.
//! - *edge band*: the edge pixels dilated by [`EDGE_DILATION`] pixels (a square), so both
//!   sides of every caustic edge are in it.
//! - *flat*: lit pixels outside the edge band.
//!
//! Errors: RMSE over every pixel; relative MSE ([`crate::image_metrics::relative_mse`]); RMSE over the edge band;
//! flat-region noise = the standard deviation over the flat pixels of (estimate − reference) /
//! reference, relative because a caustic's brightness spans orders of magnitude.

use super::sweep::Errors;
use crate::image_metrics::relative_mse;

pub const LIT_FRACTION: f64 = 0.02;
pub const EDGE_RELATIVE_GRADIENT: f64 = 0.2;
pub const EDGE_DILATION: usize = 2;

/// The pixel classes of a reference image (row by row, `width` × `height`).
#[derive(Clone, Debug, PartialEq)]
pub struct SceneRegions {
    pub width: usize,
    pub height: usize,
    pub lit: Vec<bool>,
    pub edge_band: Vec<bool>,
    pub flat: Vec<bool>,
}

impl SceneRegions {
    pub fn from_reference(reference: &[f64], width: usize, height: usize) -> Self {
        assert_eq!(reference.len(), width * height);
        let mut positive: Vec<f64> = reference
            .iter()
            .copied()
            .filter(|v| *v > 0.0 && v.is_finite())
            .collect();
        positive.sort_by(f64::total_cmp);
        let bright = positive
            .get(positive.len() * 995 / 1000)
            .copied()
            .unwrap_or(0.0);
        let threshold = LIT_FRACTION * bright;
        let lit: Vec<bool> = reference
            .iter()
            .map(|&v| bright > 0.0 && v >= threshold)
            .collect();
        let at = |x: isize, y: isize| {
            let x = x.clamp(0, width as isize - 1) as usize;
            let y = y.clamp(0, height as isize - 1) as usize;
            y * width + x
        };
        // The 3×3 mean: the local value, and what the gradient is taken of (less noise).
        let mut smooth = vec![0.0; reference.len()];
        let mut near_lit = vec![false; reference.len()];
        for y in 0..height as isize {
            for x in 0..width as isize {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        smooth[at(x, y)] += reference[at(x + dx, y + dy)] / 9.0;
                        near_lit[at(x, y)] |= lit[at(x + dx, y + dy)];
                    }
                }
            }
        }
        let mut edge = vec![false; reference.len()];
        for y in 0..height as isize {
            for x in 0..width as isize {
                let local = smooth[at(x, y)].max(threshold);
                let gx = 0.5 * (smooth[at(x + 1, y)] - smooth[at(x - 1, y)]);
                let gy = 0.5 * (smooth[at(x, y + 1)] - smooth[at(x, y - 1)]);
                let relative = gx.hypot(gy) / local;
                edge[at(x, y)] =
                    near_lit[at(x, y)] && local > 0.0 && relative >= EDGE_RELATIVE_GRADIENT;
            }
        }
        let edge_band = dilate(&edge, width, height, EDGE_DILATION);
        let flat = lit.iter().zip(&edge_band).map(|(l, e)| *l && !*e).collect();
        Self {
            width,
            height,
            lit,
            edge_band,
            flat,
        }
    }

    /// Counts of (lit, edge band, flat) pixels.
    pub fn counts(&self) -> (usize, usize, usize) {
        let n = |m: &[bool]| m.iter().filter(|b| **b).count();
        (n(&self.lit), n(&self.edge_band), n(&self.flat))
    }
}

/// `mask` grown by `radius` pixels in every direction (a square structuring element).
fn dilate(mask: &[bool], width: usize, height: usize, radius: usize) -> Vec<bool> {
    let mut out = vec![false; mask.len()];
    for y in 0..height {
        for x in 0..width {
            if !mask[y * width + x] {
                continue;
            }
            for yy in y.saturating_sub(radius)..(y + radius + 1).min(height) {
                for xx in x.saturating_sub(radius)..(x + radius + 1).min(width) {
                    out[yy * width + xx] = true;
                }
            }
        }
    }
    out
}

/// The errors of `estimate` against `reference` (see the module notes).
pub fn scene_errors(estimate: &[f64], reference: &[f64], regions: &SceneRegions) -> Errors {
    assert_eq!(estimate.len(), reference.len());
    let rms = |mask: Option<&[bool]>| {
        let (mut n, mut sum) = (0usize, 0.0);
        for (i, (e, r)) in estimate.iter().zip(reference).enumerate() {
            if mask.is_none_or(|m| m[i]) {
                n += 1;
                sum += (e - r).powi(2);
            }
        }
        (sum / n.max(1) as f64).sqrt()
    };
    // Two passes: a uniform bias must give exactly no noise, not a rounding residue.
    let relative: Vec<f64> = estimate
        .iter()
        .zip(reference)
        .zip(&regions.flat)
        .filter(|((_, r), flat)| **flat && **r > 0.0)
        .map(|((e, r), _)| (e - r) / r)
        .collect();
    let n = relative.len().max(1) as f64;
    let mean = relative.iter().sum::<f64>() / n;
    let variance = relative.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n;
    Errors {
        rmse: rms(None),
        relative_mse: relative_mse(estimate, reference),
        edge_band_rmse: rms(Some(&regions.edge_band)),
        flat_noise: variance.sqrt(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bright square on black: its border is edge band, its inside flat, the rest neither.
    #[test]
    fn a_lit_square_has_an_edge_band_round_a_flat_inside() {
        let (w, h) = (40, 40);
        let image: Vec<f64> = (0..w * h)
            .map(|i| {
                let (x, y) = (i % w, i / w);
                if (10..30).contains(&x) && (10..30).contains(&y) {
                    1.0
                } else {
                    0.0
                }
            })
            .collect();
        let r = SceneRegions::from_reference(&image, w, h);
        let at = |x: usize, y: usize| y * w + x;
        assert!(r.edge_band[at(10, 20)] && r.edge_band[at(8, 20)] && r.edge_band[at(12, 20)]);
        assert!(r.flat[at(20, 20)] && !r.edge_band[at(20, 20)]);
        assert!(!r.lit[at(2, 2)] && !r.edge_band[at(2, 2)] && !r.flat[at(2, 2)]);
        let e = scene_errors(&image, &image, &r);
        assert_eq!((e.rmse, e.edge_band_rmse, e.flat_noise), (0.0, 0.0, 0.0));
        let brighter: Vec<f64> = image.iter().map(|v| v * 1.1).collect();
        let e = scene_errors(&brighter, &image, &r);
        assert!(e.flat_noise < 1e-12, "a uniform 10% bias is not noise");
        assert!(e.rmse > 0.0 && e.relative_mse > 0.0);
    }
}
