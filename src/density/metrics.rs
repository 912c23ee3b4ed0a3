//! Error metrics of an estimated density image against the known one: overall and relative
//! RMSE, RMSE in a band around the discontinuities, noise in flat regions, the thin line's peak
//! and total energy. Owns the region definitions and the arithmetic; it must not sample photons,
//! evaluate estimates or write files.
//!
//! Regions (world units, so they mean the same at every resolution and for every estimate):
//! - *interior*: pixel centres at least `margin` inside the image extent and the unit square
//!   that carries the photons. Kernels reaching past the border lose photons there (boundary
//!   bias); the interior keeps that out of every metric except the whole-image RMSE.
//! - *edge band*: interior pixels whose centre lies within `band` of a discontinuity of the true
//!   density.
//! - *flat*: interior pixels farther than `band` from every discontinuity and every kink (where
//!   the density is continuous but its slope jumps: a ridge's crest and feet, a ramp's foot).
//!   There the true density is constant or linear, so a symmetric kernel has no bias and
//!   the spread of estimate − truth is noise.
//! - *thin line*: pixels within `band` of the line's centre line, farther than `band` from its
//!   ends; binned by their position along the line (bins one pixel wide), the estimate's maximum
//!   over each bin's cross-section, averaged over the bins, over the true peak.
//!
//! Energy: Σ estimate · pixel area against Σ truth · pixel area over the interior, with the truth
//! averaged over each pixel (a thin line 4.2 pixels wide covers 4 or 5 pixel centres, so summing
//! centre values would miscount its energy by up to 20%). The interior's border crosses only
//! the uniform background, where what a kernel carries out it also carries in, so a kernel that
//! preserves energy scores 0 up to noise.

use super::distribution::Truth;
use super::grid::Grid;
use glam::DVec2;

/// Where the regions are, in world units.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RegionWidths {
    pub band: f64,
    pub margin: f64,
}

/// The thin line's centre line and true peak value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineProbe {
    pub a: DVec2,
    pub b: DVec2,
    pub true_peak: f64,
}

/// Which pixels belong to which region, computed once per grid and layout.
#[derive(Clone, Debug, PartialEq)]
pub struct Regions {
    pub interior: Vec<bool>,
    pub edge_band: Vec<bool>,
    pub flat: Vec<bool>,
    /// For each pixel near the thin line (and away from its ends): its bin along the line.
    pub line_bin: Vec<Option<u32>>,
    pub line_peak: Option<f64>,
}

impl Regions {
    /// `discontinuity(p)` and `kink(p)` give the distance from `p` to the nearest such curve.
    pub fn new(
        grid: &Grid,
        widths: RegionWidths,
        discontinuity: impl Fn(DVec2) -> f64 + Sync,
        kink: impl Fn(DVec2) -> f64 + Sync,
        line: Option<LineProbe>,
    ) -> Self {
        let e = grid.extent;
        let m = widths.margin;
        let inside = |p: DVec2| {
            let lo = DVec2::new(e.x0.max(0.0), e.y0.max(0.0)) + m;
            let hi = DVec2::new(e.x1.min(1.0), e.y1.min(1.0)) - m;
            p.cmpge(lo).all() && p.cmple(hi).all()
        };
        let classes = grid.map(|p| {
            let interior = inside(p);
            let d = discontinuity(p);
            (
                interior,
                interior && d <= widths.band,
                interior && d > widths.band && kink(p) > widths.band,
            )
        });
        let bin_width = grid.pixel_size().min_element();
        let line_bin = grid.map(|p| {
            let l = line?;
            let (axis, len) = ((l.b - l.a).normalize(), l.a.distance(l.b));
            let along = (p - l.a).dot(axis);
            let across = (p - l.a).perp_dot(axis).abs();
            let keep = inside(p)
                && across <= widths.band
                && along >= widths.band
                && along <= len - widths.band;
            keep.then(|| ((along - widths.band) / bin_width) as u32)
        });
        Self {
            interior: classes.iter().map(|c| c.0).collect(),
            edge_band: classes.iter().map(|c| c.1).collect(),
            flat: classes.iter().map(|c| c.2).collect(),
            line_bin,
            line_peak: line.map(|l| l.true_peak),
        }
    }
}

/// The metrics of one estimate (values are the mean of the RGB channels, in irradiance units).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Metrics {
    /// Over every pixel.
    pub rmse: f64,
    /// `rmse` over the mean true value of every pixel.
    pub relative_rmse: f64,
    pub interior_rmse: f64,
    pub edge_band_rmse: f64,
    /// Standard deviation of estimate − truth over the flat pixels.
    pub flat_noise: f64,
    /// Mean of estimate − truth over the flat pixels.
    pub flat_bias: f64,
    /// Mean over the line of the cross-section maximum, over the true peak.
    pub line_peak: Option<f64>,
    /// (Σ estimate − Σ truth) / Σ truth over the interior.
    pub energy_error: f64,
    pub pixels: usize,
    pub interior_pixels: usize,
    pub edge_band_pixels: usize,
    pub flat_pixels: usize,
}

impl Metrics {
    pub fn new(estimate: &[f64], truth: &Truth, regions: &Regions) -> Self {
        let (centre, pixel_mean) = (&truth.centre, &truth.pixel_mean);
        assert!(estimate.len() == centre.len() && estimate.len() == pixel_mean.len());
        let all = vec![true; estimate.len()];
        let stats = |mask: &[bool]| Moments::of(estimate, centre, mask);
        let (whole, interior) = (stats(&all), stats(&regions.interior));
        let (band, flat) = (stats(&regions.edge_band), stats(&regions.flat));
        let mean_truth = centre.iter().sum::<f64>() / centre.len().max(1) as f64;
        let (energy_estimate, energy_truth) = estimate
            .iter()
            .zip(pixel_mean)
            .zip(&regions.interior)
            .filter(|(_, inside)| **inside)
            .fold((0.0, 0.0), |(e, t), ((a, b), _)| (e + a, t + b));
        Self {
            rmse: whole.rms(),
            relative_rmse: whole.rms() / mean_truth,
            interior_rmse: interior.rms(),
            edge_band_rmse: band.rms(),
            flat_noise: flat.std_dev(),
            flat_bias: flat.mean(),
            line_peak: line_peak(estimate, regions),
            energy_error: (energy_estimate - energy_truth) / energy_truth,
            pixels: whole.n,
            interior_pixels: interior.n,
            edge_band_pixels: band.n,
            flat_pixels: flat.n,
        }
    }

    /// The metrics as a table of name, value rows (for the report).
    pub fn rows(&self) -> Vec<(&'static str, String)> {
        let mut rows = vec![
            ("RMSE (whole image)", format!("{:.5}", self.rmse)),
            ("relative RMSE", format!("{:.4}", self.relative_rmse)),
            ("RMSE (interior)", format!("{:.5}", self.interior_rmse)),
            ("RMSE (edge band)", format!("{:.5}", self.edge_band_rmse)),
            ("noise (flat, std-dev)", format!("{:.5}", self.flat_noise)),
            ("bias (flat, mean)", format!("{:+.5}", self.flat_bias)),
        ];
        if let Some(p) = self.line_peak {
            rows.push(("thin line peak / true", format!("{p:.3}")));
        }
        rows.push((
            "energy error (interior)",
            format!("{:+.4}%", 100.0 * self.energy_error),
        ));
        rows.push((
            "pixels: all/interior/band/flat",
            format!(
                "{}/{}/{}/{}",
                self.pixels, self.interior_pixels, self.edge_band_pixels, self.flat_pixels
            ),
        ));
        rows
    }
}

/// Sums of estimate − truth over a set of pixels.
struct Moments {
    n: usize,
    sum: f64,
    sum_sq: f64,
}

impl Moments {
    fn of(estimate: &[f64], truth: &[f64], mask: &[bool]) -> Self {
        let mut m = Moments {
            n: 0,
            sum: 0.0,
            sum_sq: 0.0,
        };
        for ((&e, &t), _) in estimate
            .iter()
            .zip(truth)
            .zip(mask)
            .filter(|(_, keep)| **keep)
        {
            let d = e - t;
            m.n += 1;
            m.sum += d;
            m.sum_sq += d * d;
        }
        m
    }
    fn mean(&self) -> f64 {
        self.sum / self.n.max(1) as f64
    }
    fn rms(&self) -> f64 {
        (self.sum_sq / self.n.max(1) as f64).sqrt()
    }
    fn std_dev(&self) -> f64 {
        (self.sum_sq / self.n.max(1) as f64 - self.mean().powi(2))
            .max(0.0)
            .sqrt()
    }
}

fn line_peak(estimate: &[f64], regions: &Regions) -> Option<f64> {
    let true_peak = regions.line_peak?;
    let bins = regions
        .line_bin
        .iter()
        .flatten()
        .max()
        .map(|&b| b as usize + 1)?;
    let mut max = vec![f64::NEG_INFINITY; bins];
    for (&e, bin) in estimate.iter().zip(&regions.line_bin) {
        if let Some(b) = bin {
            max[*b as usize] = max[*b as usize].max(e);
        }
    }
    let filled: Vec<f64> = max.into_iter().filter(|m| m.is_finite()).collect();
    Some(filled.iter().sum::<f64>() / filled.len() as f64 / true_peak)
}

/// The metrics as an aligned two-column text table.
pub fn format_table(title: &str, rows: &[(&str, String)]) -> String {
    let width = rows
        .iter()
        .map(|(k, _)| k.len())
        .max()
        .unwrap_or(0)
        .max(title.len());
    let mut out = format!("{title}\n{}\n", "-".repeat(width + 14));
    for (k, v) in rows {
        out.push_str(&format!("{k:<width$}  {v:>12}\n"));
    }
    out
}
