//! The built-in photon distributions with a known density (the paper's constructed distribution,
//! Section 4, and a second one with other shapes), their photon sampling and their exact
//! density. Owns the layouts and the photon counts; it must not evaluate estimates or compute
//! metrics.
//!
//! A distribution is a uniform background over the unit square plus shapes whose profiles peak at
//! 1 (the same density per area inside every shape); the background's level is
//! [`BACKGROUND_LEVEL`] of a shape's. The `count` photons are split between the background and
//! the shapes in proportion to their masses (largest remainder, so the split is exact and known);
//! each photon is then drawn from its part with its own random stream, so the photons depend
//! only on the seed and not on the thread count. Every photon carries the same power, `1/count`
//! as stored by the photon record, so the image integrates to about 1.

use super::grid::Grid;
use super::rng::SplitMix64;
use super::shapes::{Curve, Frame, Shape};
use crate::photon::Photon;
use crate::photon::record::{decode_rgbe, encode_rgbe};
use glam::{DVec2, Vec3};
use rayon::prelude::*;

/// The background's density relative to a shape's.
pub const BACKGROUND_LEVEL: f64 = 0.1;

/// Width of the thin lines (world units), chosen so that the isotropic Epanechnikov estimate
/// with radius 0.02 keeps 40% of a line's true value (line plus background). That kernel's
/// marginal across the line is `m(y) = 8 (r² − y²)^{3/2} / (3π r⁴)`; its integral over the
/// line's width is 0.341 for w = 0.0082, so the estimate on the line is 0.1 + 0.341 of a shape's
/// level against a true 1.1: 0.40.
pub const THIN_LINE_WIDTH: f64 = 0.0082;

/// Sub-samples a side when averaging the truth over a pixel that a discontinuity crosses.
const TRUTH_SUBSAMPLES: usize = 16;

/// The true irradiance on a grid, row by row.
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    /// At each pixel centre: what a point estimate at the centre should return.
    pub centre: Vec<f64>,
    /// Averaged over each pixel (16×16 sub-samples where a discontinuity crosses the pixel):
    /// what the pixel holds, for energy sums.
    pub pixel_mean: Vec<f64>,
}

/// The built-in distributions.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DistributionName {
    /// Disc, rectangle, vertical thin line and tent-shaped ridge (like the paper's Figures 4-6).
    Constructed,
    /// Triangle, annulus, diagonal thin line, curved band and linear ramp.
    Second,
}

/// The thin line whose peak is measured: its centre line and its true peak density.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinLine {
    pub a: DVec2,
    pub b: DVec2,
}

/// A distribution's layout: the background covers the unit square; shapes lie on top.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    pub shapes: Vec<Shape>,
    pub thin_line: ThinLine,
}

impl Layout {
    pub fn new(name: DistributionName) -> Self {
        let p = DVec2::new;
        match name {
            DistributionName::Constructed => {
                let line = ThinLine {
                    a: p(0.5, 0.12),
                    b: p(0.5, 0.88),
                };
                Self {
                    shapes: vec![
                        Shape::Disc {
                            centre: p(0.27, 0.70),
                            radius: 0.14,
                        },
                        Shape::Rectangle(Frame::new(p(0.74, 0.70), 0.0, p(0.14, 0.12))),
                        line_shape(line),
                        Shape::Ridge(Frame::new(p(0.27, 0.27), 0.0, p(0.14, 0.05))),
                    ],
                    thin_line: line,
                }
            }
            DistributionName::Second => {
                let line = ThinLine {
                    a: p(0.10, 0.10),
                    b: p(0.40, 0.46),
                };
                Self {
                    shapes: vec![
                        Shape::Triangle([p(0.10, 0.58), p(0.42, 0.58), p(0.26, 0.90)]),
                        Shape::Annulus {
                            centre: p(0.72, 0.74),
                            inner: 0.07,
                            outer: 0.15,
                        },
                        line_shape(line),
                        Shape::ArcBand {
                            centre: p(0.74, 0.26),
                            inner: 0.165,
                            outer: 0.195,
                            start: 30.0,
                            end: 150.0,
                        },
                        Shape::Ramp(Frame::new(p(0.74, 0.16), 0.0, p(0.16, 0.06))),
                    ],
                    thin_line: line,
                }
            }
        }
    }

    /// Curves where the density jumps (the unit square's own border is not one: metrics stay
    /// inside it).
    pub fn discontinuities(&self) -> Vec<Curve> {
        self.shapes
            .iter()
            .flat_map(Shape::discontinuities)
            .collect()
    }

    pub fn kinks(&self) -> Vec<Curve> {
        self.shapes.iter().flat_map(Shape::kinks).collect()
    }
}

fn line_shape(line: ThinLine) -> Shape {
    let d = line.b - line.a;
    let angle = d.y.atan2(d.x).to_degrees();
    Shape::Rectangle(Frame::new(
        0.5 * (line.a + line.b),
        angle,
        DVec2::new(0.5 * d.length(), 0.5 * THIN_LINE_WIDTH),
    ))
}

/// A layout with a photon count: the exact density of its photons and the photons themselves.
#[derive(Clone, Debug, PartialEq)]
pub struct Distribution {
    pub name: DistributionName,
    pub layout: Layout,
    /// Photons drawn from the background (index 0) and from each shape (index i + 1).
    pub counts: Vec<u64>,
    /// The power every photon carries, as the photon record stores it.
    pub photon_power: f32,
}

impl Distribution {
    pub fn new(name: DistributionName, count: u64) -> Self {
        let layout = Layout::new(name);
        let masses: Vec<f64> = std::iter::once(BACKGROUND_LEVEL)
            .chain(layout.shapes.iter().map(Shape::mass))
            .collect();
        let counts = split_by_largest_remainder(count, &masses);
        let photon_power = decode_rgbe(encode_rgbe(Vec3::splat(1.0 / count.max(1) as f32))).x;
        Self {
            name,
            layout,
            counts,
            photon_power,
        }
    }

    pub fn count(&self) -> u64 {
        self.counts.iter().sum()
    }

    /// Expected photons per unit area at `p`.
    pub fn photon_density(&self, p: DVec2) -> f64 {
        if !(0.0..=1.0).contains(&p.x) || !(0.0..=1.0).contains(&p.y) {
            return 0.0;
        }
        let shapes: f64 = self
            .layout
            .shapes
            .iter()
            .zip(&self.counts[1..])
            .map(|(s, &n)| n as f64 * s.profile(p) / s.mass())
            .sum();
        self.counts[0] as f64 + shapes
    }

    /// The true irradiance (photon power per unit area) at `p`.
    pub fn irradiance(&self, p: DVec2) -> f64 {
        self.photon_density(p) * self.photon_power as f64
    }

    /// The true irradiance on the thin line's centre (the line plus the background).
    pub fn thin_line_peak(&self) -> f64 {
        let line = self.layout.thin_line;
        self.irradiance(0.5 * (line.a + line.b))
    }

    /// The true irradiance on `grid`, at the pixel centres and averaged over the pixels.
    pub fn truth_on(&self, grid: &Grid) -> Truth {
        let edges = self.layout.discontinuities();
        let size = grid.pixel_size();
        let (half_diagonal, n) = (0.5 * size.length(), TRUTH_SUBSAMPLES);
        let both = grid.map(|c| {
            let centre = self.irradiance(c);
            // Away from a jump the profiles are linear across a pixel, so the centre is the mean.
            if edges.iter().all(|e| e.distance(c) > half_diagonal) {
                return (centre, centre);
            }
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let offset = DVec2::new(
                        (i as f64 + 0.5) / n as f64 - 0.5,
                        (j as f64 + 0.5) / n as f64 - 0.5,
                    );
                    sum += self.irradiance(c + offset * size);
                }
            }
            (centre, sum / (n * n) as f64)
        });
        Truth {
            centre: both.iter().map(|b| b.0).collect(),
            pixel_mean: both.iter().map(|b| b.1).collect(),
        }
    }

    /// The photons, in the plane z = 0, arriving straight down onto the +z side.
    pub fn photons(&self, seed: u64) -> Vec<Photon> {
        let power = Vec3::splat(self.photon_power);
        let starts: Vec<u64> = self
            .counts
            .iter()
            .scan(0, |s, &n| {
                *s += n;
                Some(*s - n)
            })
            .collect();
        (0..self.count())
            .into_par_iter()
            .map(|i| {
                let part = starts.partition_point(|&s| s <= i) - 1;
                let mut rng = SplitMix64::for_item(seed, i);
                let p = match part {
                    0 => DVec2::new(rng.next_f64(), rng.next_f64()),
                    k => self.layout.shapes[k - 1].sample(&mut rng),
                };
                Photon::new(
                    Vec3::new(p.x as f32, p.y as f32, 0.0),
                    power,
                    Vec3::NEG_Z,
                    Vec3::Z,
                )
            })
            .collect()
    }
}

/// Splits `total` into integers proportional to `weights` that sum to `total`.
pub fn split_by_largest_remainder(total: u64, weights: &[f64]) -> Vec<u64> {
    let sum: f64 = weights.iter().sum();
    let exact: Vec<f64> = weights.iter().map(|w| total as f64 * w / sum).collect();
    let mut counts: Vec<u64> = exact.iter().map(|e| e.floor() as u64).collect();
    let mut order: Vec<usize> = (0..weights.len()).collect();
    order.sort_by(|&a, &b| {
        (exact[b] - exact[b].floor())
            .total_cmp(&(exact[a] - exact[a].floor()))
            .then(a.cmp(&b))
    });
    let short = total - counts.iter().sum::<u64>();
    for &i in order.iter().cycle().take(short as usize) {
        counts[i] += 1;
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn split_sums_to_the_total() {
        assert_eq!(
            split_by_largest_remainder(10, &[1.0, 1.0, 1.0]),
            vec![4, 3, 3]
        );
        assert_eq!(
            split_by_largest_remainder(7, &[0.5, 0.25, 0.25])
                .iter()
                .sum::<u64>(),
            7
        );
        assert_eq!(split_by_largest_remainder(0, &[1.0, 2.0]), vec![0, 0]);
    }

    #[test]
    fn shapes_are_as_dense_as_each_other_and_the_background_dimmer() {
        for name in [DistributionName::Constructed, DistributionName::Second] {
            let d = Distribution::new(name, 1_000_000);
            let bg = d.counts[0] as f64;
            for (s, &n) in d.layout.shapes.iter().zip(&d.counts[1..]) {
                let peak = n as f64 / s.mass();
                assert!((peak * BACKGROUND_LEVEL / bg - 1.0).abs() < 1e-3, "{s:?}");
            }
        }
    }

    /// Shapes stay clear of each other and of the border, so bands and windows see one shape.
    #[test]
    fn shapes_are_separated() {
        for name in [DistributionName::Constructed, DistributionName::Second] {
            let layout = Layout::new(name);
            let n = 400;
            for i in 0..n {
                for j in 0..n {
                    let p = DVec2::new((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                    let near: Vec<usize> = (0..layout.shapes.len())
                        .filter(|&k| {
                            let s = &layout.shapes[k];
                            s.profile(p) > 0.0
                                || s.discontinuities().iter().any(|c| c.distance(p) < 0.04)
                        })
                        .collect();
                    assert!(near.len() <= 1, "{name:?} {p}: shapes {near:?} within 0.04");
                    if !near.is_empty() {
                        assert!(
                            p.min_element() > 0.05 && p.max_element() < 0.95,
                            "{name:?} {p}"
                        );
                    }
                }
            }
        }
    }
}
