//! Radial kernels of the radiance estimates, as functions of the scaled squared distance
//! `y = d²/r²` (Eq. 2) or the scaled Mahalanobis distance `dᵀD⁻¹d/r²` (Eq. 14). Owns the kernel
//! shapes and their normalisation: every kernel here integrates to exactly one over the unit
//! disc, so `Σ K(y_i) Φ_i / r²` is an unbiased density when the photons are uniform in the
//! disc. Must not gather photons or know about photon maps.

use std::f64::consts::PI;

/// Sharpness of Jensen's (Pavicic's) Gaussian filter, as in Jensen's book.
pub const GAUSSIAN_BETA: f64 = 1.953;

/// A kernel of the general radiance estimate (Eq. 2), normalised over the unit disc.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RadialKernel {
    /// `1/π`: the simple estimate of Eq. 1.
    Constant,
    /// Jensen's cone filter (Eq. 3): `(1 − √y / slope) / ((1 − 2/(3 slope)) π)`, `slope ≥ 1`.
    Cone { slope: f64 },
    /// Jensen's Gaussian shape `1 − (1 − e^{−βy/2}) / (1 − e^{−β})`, divided by its exact
    /// integral over the disc. Jensen's constant α = 0.918 is not that integral, which is why
    /// his Gaussian estimate is biased.
    Gaussian,
    /// The 2-D Epanechnikov kernel (Eq. 4): `(2/π)(1 − y)`.
    Epanechnikov,
}

impl RadialKernel {
    /// Kernel value at scaled squared distance `y`; zero for `y ≥ 1` (and for NaN). The
    /// support is open on purpose: the k-th photon of a k-NN search lies at `y = 1` and so
    /// gets no weight, which is what leaves it out of the sum.
    #[inline]
    pub fn weight(self, y: f64) -> f64 {
        if y.is_nan() || y >= 1.0 {
            return 0.0;
        }
        let y = y.max(0.0);
        match self {
            RadialKernel::Constant => 1.0 / PI,
            RadialKernel::Cone { slope } => {
                (1.0 - y.sqrt() / slope) / ((1.0 - 2.0 / (3.0 * slope)) * PI)
            }
            RadialKernel::Gaussian => gaussian_shape(y) / gaussian_shape_integral(),
            RadialKernel::Epanechnikov => 2.0 / PI * (1.0 - y),
        }
    }

    /// The kernel's value just inside the disc's rim (`y → 1⁻`): what including the k-th
    /// photon would add to a k-NN estimate, per unit power and `r²`.
    pub fn rim_weight(self) -> f64 {
        self.weight(1.0 - 1e-12)
    }
}

/// A kernel with its constants worked out once, for the estimates' inner loops: the same
/// values as [`RadialKernel::weight`] up to rounding, without its divisions per photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PreparedKernel {
    /// The constant value.
    Constant(f64),
    /// `a − b √y`.
    Cone { a: f64, b: f64 },
    /// `(a + b e^{−c y})`: Jensen's shape expanded, divided by its integral.
    Gaussian { a: f64, b: f64, c: f64 },
    /// `a (1 − y)`.
    Epanechnikov(f64),
}

impl RadialKernel {
    /// This kernel with its constants precomputed.
    pub fn prepare(self) -> PreparedKernel {
        match self {
            RadialKernel::Constant => PreparedKernel::Constant(1.0 / PI),
            RadialKernel::Cone { slope } => {
                let a = 1.0 / ((1.0 - 2.0 / (3.0 * slope)) * PI);
                PreparedKernel::Cone { a, b: a / slope }
            }
            RadialKernel::Gaussian => {
                // 1 − (1 − e^{−βy/2})/(1 − e^{−β}) = (1 − s) + s e^{−βy/2}, s = 1/(1 − e^{−β}).
                let s = 1.0 / (1.0 - (-GAUSSIAN_BETA).exp());
                let norm = 1.0 / gaussian_shape_integral();
                PreparedKernel::Gaussian {
                    a: (1.0 - s) * norm,
                    b: s * norm,
                    c: GAUSSIAN_BETA / 2.0,
                }
            }
            RadialKernel::Epanechnikov => PreparedKernel::Epanechnikov(2.0 / PI),
        }
    }
}

impl PreparedKernel {
    /// Kernel value at `y`; zero for `y ≥ 1` and NaN, like [`RadialKernel::weight`].
    #[inline(always)]
    pub fn weight(self, y: f64) -> f64 {
        if y.is_nan() || y >= 1.0 {
            return 0.0;
        }
        let y = y.max(0.0);
        match self {
            PreparedKernel::Constant(c) => c,
            PreparedKernel::Cone { a, b } => a - b * y.sqrt(),
            PreparedKernel::Gaussian { a, b, c } => a + b * (-c * y).exp(),
            PreparedKernel::Epanechnikov(a) => a * (1.0 - y),
        }
    }
}

/// A prepared kernel for one radius, taking the squared distance `d²` itself: `K(d²/r²)`
/// with `1/r²` (and for the cone `1/r`) folded into the constants, so an inner loop does no
/// division. Zero for `d² ≥ r²` and NaN.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RadiusKernel {
    kernel: PreparedKernel,
    radius2: f64,
}

impl PreparedKernel {
    /// This kernel at support radius `√radius2` (positive).
    pub fn for_radius2(self, radius2: f64) -> RadiusKernel {
        let kernel = match self {
            PreparedKernel::Constant(c) => PreparedKernel::Constant(c),
            PreparedKernel::Cone { a, b } => PreparedKernel::Cone {
                a,
                b: b / radius2.sqrt(),
            },
            PreparedKernel::Gaussian { a, b, c } => PreparedKernel::Gaussian {
                a,
                b,
                c: c / radius2,
            },
            PreparedKernel::Epanechnikov(a) => PreparedKernel::Epanechnikov(a / radius2),
        };
        RadiusKernel { kernel, radius2 }
    }
}

impl RadiusKernel {
    #[inline(always)]
    pub fn weight(self, d2: f64) -> f64 {
        if d2.is_nan() || d2 >= self.radius2 {
            return 0.0;
        }
        let d2 = d2.max(0.0);
        match self.kernel {
            PreparedKernel::Constant(c) => c,
            PreparedKernel::Cone { a, b } => a - b * d2.sqrt(),
            PreparedKernel::Gaussian { a, b, c } => a + b * (-c * d2).exp(),
            // a (1 − d²/r²) with a/r² folded: a − (a/r²) d².
            PreparedKernel::Epanechnikov(a_r2) => a_r2 * (self.radius2 - d2),
        }
    }
}

fn gaussian_shape(y: f64) -> f64 {
    let b = GAUSSIAN_BETA;
    1.0 - (1.0 - (-b * y / 2.0).exp()) / (1.0 - (-b).exp())
}

/// `∫_disc shape = π ∫_0^1 shape(y) dy` (the disc's area element is `π dy` in `y = ρ²`).
fn gaussian_shape_integral() -> f64 {
    let b = GAUSSIAN_BETA;
    let mean_one_minus_exp = 1.0 - 2.0 / b * (1.0 - (-b / 2.0).exp());
    PI * (1.0 - mean_one_minus_exp / (1.0 - (-b).exp()))
}

/// The share of the unit-disc Epanechnikov kernel `(2/π)(1 − x² − y²)` with `x < h`: its
/// marginal is `(8/(3π))(1 − x²)^{3/2}`, whose primitive is
/// `(x(5 − 2x²)√(1 − x²) + 3 asin x)/8`.
pub fn epanechnikov_share_below(h: f64) -> f64 {
    let h = h.clamp(-1.0, 1.0);
    let primitive =
        |x: f64| (x * (5.0 - 2.0 * x * x) * (1.0 - x * x).max(0.0).sqrt() + 3.0 * x.asin()) / 8.0;
    (8.0 / (3.0 * PI)) * (primitive(h) - primitive(-1.0))
}

/// The share of the line integral of the 3-D Epanechnikov kernel, `(5/2π)(1 − x² − y²)^{3/2}`
/// over the unit disc (what a ball, or an ellipsoid up to an affine map, projects to along a
/// ray), with `x < h`: its marginal is `(15/16)(1 − x²)²`.
pub fn projected_ball_share_below(h: f64) -> f64 {
    let h = h.clamp(-1.0, 1.0);
    let primitive = |x: f64| x - 2.0 / 3.0 * x.powi(3) + x.powi(5) / 5.0;
    15.0 / 16.0 * (primitive(h) - primitive(-1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The share of `profile(x² + y²)` over the unit disc with x < h, by the midpoint rule.
    fn share_by_grid(profile: impl Fn(f64) -> f64, h: f64) -> f64 {
        let n = 800;
        let (mut below, mut all) = (0.0, 0.0);
        for i in 0..n {
            for j in 0..n {
                let x = -1.0 + (i as f64 + 0.5) * 2.0 / n as f64;
                let y = -1.0 + (j as f64 + 0.5) * 2.0 / n as f64;
                let w = profile((x * x + y * y).min(1.0));
                all += w;
                if x < h {
                    below += w;
                }
            }
        }
        below / all
    }

    #[test]
    fn the_shares_below_a_line_run_from_nothing_to_all_as_the_disc_does() {
        for share in [epanechnikov_share_below, projected_ball_share_below] {
            assert!(share(-1.0).abs() < 1e-12);
            assert!((share(0.0) - 0.5).abs() < 1e-12);
            assert!((share(1.0) - 1.0).abs() < 1e-12);
        }
        for h in [-0.9, -0.4, 0.25, 0.5, 0.8, 0.97] {
            let disc = share_by_grid(|r2| 1.0 - r2, h);
            assert!(
                (epanechnikov_share_below(h) - disc).abs() < 1e-4,
                "disc at {h}"
            );
            let ball = share_by_grid(|r2| (1.0 - r2).powf(1.5), h);
            assert!(
                (projected_ball_share_below(h) - ball).abs() < 1e-4,
                "ball at {h}"
            );
        }
    }

    /// Midpoint rule in polar coordinates: ∫_disc K(ρ²) dA = 2π ∫_0^1 K(ρ²) ρ dρ.
    fn disc_integral(k: RadialKernel) -> f64 {
        let n = 200_000;
        let h = 1.0 / n as f64;
        (0..n)
            .map(|i| {
                let rho = (i as f64 + 0.5) * h;
                k.weight(rho * rho) * rho * h
            })
            .sum::<f64>()
            * 2.0
            * PI
    }

    /// Every kernel, the cone at three slopes.
    const EVERY_KERNEL: [RadialKernel; 6] = [
        RadialKernel::Constant,
        RadialKernel::Cone { slope: 1.0 },
        RadialKernel::Cone { slope: 1.1 },
        RadialKernel::Cone { slope: 5.0 },
        RadialKernel::Gaussian,
        RadialKernel::Epanechnikov,
    ];

    #[test]
    fn every_kernel_integrates_to_one_over_the_unit_disc() {
        for k in EVERY_KERNEL {
            let s = disc_integral(k);
            assert!((s - 1.0).abs() < 1e-6, "{k:?} integrates to {s}");
        }
    }

    #[test]
    fn kernels_vanish_outside_the_disc_and_decrease_inside() {
        for k in [
            RadialKernel::Cone { slope: 1.3 },
            RadialKernel::Gaussian,
            RadialKernel::Epanechnikov,
        ] {
            assert_eq!(k.weight(1.0), 0.0);
            assert_eq!(k.weight(3.0), 0.0);
            assert_eq!(k.weight(f64::NAN), 0.0);
            let mut last = f64::INFINITY;
            for i in 0..100 {
                let w = k.weight(i as f64 / 100.0);
                assert!(w > 0.0 && w <= last, "{k:?} at {i}");
                last = w;
            }
        }
    }

    #[test]
    fn prepared_kernels_match_the_definitions() {
        for k in EVERY_KERNEL {
            let p = k.prepare();
            for i in 0..=1000 {
                let y = i as f64 / 1000.0;
                let (a, b) = (k.weight(y), p.weight(y));
                assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "{k:?} at {y}");
            }
            for y in [1.0, 1.5, f64::NAN, f64::INFINITY] {
                assert_eq!(p.weight(y), 0.0, "{k:?} at {y}");
            }
            for radius2 in [1e-6, 0.37, 4.0, 1e8] {
                let r = p.for_radius2(radius2);
                for i in 0..=1000 {
                    let y = i as f64 / 1000.0;
                    let (a, b) = (k.weight(y), r.weight(y * radius2));
                    assert!((a - b).abs() <= 1e-12 * a.abs().max(1.0), "{k:?} at {y}");
                }
                assert_eq!(r.weight(radius2), 0.0);
                assert_eq!(r.weight(f64::NAN), 0.0);
            }
        }
    }

    #[test]
    fn cone_with_slope_one_is_zero_at_the_rim() {
        assert!(RadialKernel::Cone { slope: 1.0 }.rim_weight().abs() < 1e-5);
        assert!(RadialKernel::Cone { slope: 2.0 }.rim_weight() > 0.1);
    }
}
