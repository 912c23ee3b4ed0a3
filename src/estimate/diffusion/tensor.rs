//! Small tensors of the diffusion estimate: the symmetric 2×2 tensor with its closed-form
//! eigen-decomposition (the structure tensor in the tangent plane), the diffusivity function
//! (Eq. 9) and the diffusion tensor (Eq. 8) with the scaled Mahalanobis distance and the
//! energy-preserving normalisation of the kernel (Eq. 14). Pure numerics in f64; must not
//! gather photons or know about photon maps.

use glam::{DVec2, DVec3};

/// A symmetric 2×2 tensor `[[xx, xy], [xy, yy]]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SymmetricTensor2 {
    pub xx: f64,
    pub xy: f64,
    pub yy: f64,
}

/// Eigen-decomposition of a [`SymmetricTensor2`]: `major ≥ minor`, `major_vector` a unit
/// eigenvector of `major` (the sign is arbitrary).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eigen2 {
    pub major: f64,
    pub minor: f64,
    pub major_vector: DVec2,
}

impl SymmetricTensor2 {
    /// The outer product `g gᵀ`.
    pub fn outer(g: DVec2) -> Self {
        Self {
            xx: g.x * g.x,
            xy: g.x * g.y,
            yy: g.y * g.y,
        }
    }

    /// Closed-form eigen-decomposition. An isotropic tensor (including zero) has no preferred
    /// direction; it reports the first axis. A non-finite tensor reports zero.
    pub fn eigen(&self) -> Eigen2 {
        let Self { xx, xy, yy } = *self;
        if !(xx.is_finite() && xy.is_finite() && yy.is_finite()) {
            return Eigen2 {
                major: 0.0,
                minor: 0.0,
                major_vector: DVec2::X,
            };
        }
        let mean = 0.5 * (xx + yy);
        let half_diff = 0.5 * (xx - yy);
        let radius = half_diff.hypot(xy);
        let major_vector = if radius == 0.0 {
            DVec2::X
        } else if half_diff >= 0.0 {
            // Rows of (T − μ1 I) give two candidate eigenvectors; this one has its first
            // component ≥ radius > 0, so it never cancels.
            unit(DVec2::new(half_diff + radius, xy))
        } else {
            unit(DVec2::new(xy, radius - half_diff))
        };
        Eigen2 {
            major: mean + radius,
            minor: mean - radius,
            major_vector,
        }
    }
}

/// Normalises a vector with a nonzero component without squaring it first, so that tiny
/// (subnormal) and huge tensors keep their direction.
fn unit(v: DVec2) -> DVec2 {
    (v / v.abs().max_element()).normalize()
}

impl std::ops::AddAssign for SymmetricTensor2 {
    fn add_assign(&mut self, o: Self) {
        self.xx += o.xx;
        self.xy += o.xy;
        self.yy += o.yy;
    }
}

impl std::ops::Mul<f64> for SymmetricTensor2 {
    type Output = Self;
    fn mul(self, s: f64) -> Self {
        Self {
            xx: self.xx * s,
            xy: self.xy * s,
            yy: self.yy * s,
        }
    }
}

/// The diffusivity function of Eq. 9, `1/(1 + (contrast/K)^(1+α))`, without the floor.
/// No contrast (a flat region) gives 1; `K = ∞` gives 1 for any finite contrast; `K = 0`
/// gives 0 for any positive contrast.
pub fn diffusivity(contrast: f64, k: f64, alpha: f64) -> f64 {
    if contrast.is_nan() || contrast <= 0.0 || k == f64::INFINITY {
        return 1.0;
    }
    let ratio = contrast / k; // +inf when k = 0
    let lambda = 1.0 / (1.0 + ratio.powf(1.0 + alpha));
    if lambda.is_nan() { 1.0 } else { lambda }
}

/// The diffusion tensor `D = X diag(λ1, λ2, λ3) Xᵀ` (Eq. 8) with `X1` along the edge, `X2`
/// across it and `X3` the surface normal.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffusionTensor {
    pub x1: DVec3,
    pub x2: DVec3,
    pub x3: DVec3,
    pub lambda1: f64,
    pub lambda2: f64,
    pub lambda3: f64,
}

impl DiffusionTensor {
    /// From the structure tensor's major direction `across` (a unit vector in the tangent
    /// plane of the unit `normal`): `X2 = across`, `X3 = normal`, `X1 = X2 × X3`, `λ1 = 1`.
    pub fn new(across: DVec3, normal: DVec3, lambda2: f64, lambda3: f64) -> Self {
        Self {
            x1: across.cross(normal),
            x2: across,
            x3: normal,
            lambda1: 1.0,
            lambda2,
            lambda3,
        }
    }

    /// The same tensor with `λ1` (along the edge) set to `lambda1` (the paper keeps it 1).
    pub fn with_lambda1(self, lambda1: f64) -> Self {
        Self { lambda1, ..self }
    }

    /// `dᵀ D⁻¹ d / r²`: the kernel argument of Eq. 14.
    #[inline]
    pub fn scaled_mahalanobis(&self, d: DVec3, radius2: f64) -> f64 {
        let (a, b, c) = (d.dot(self.x1), d.dot(self.x2), d.dot(self.x3));
        (a * a / self.lambda1 + b * b / self.lambda2 + c * c / self.lambda3) / radius2
    }

    /// The kernel argument's quadratic form with `1/(λ_i r²)` worked out once, for the inner
    /// loop: [`ScaledMetric::distance`] equals [`DiffusionTensor::scaled_mahalanobis`] up to
    /// rounding, with no division per photon.
    pub fn metric(&self, radius2: f64) -> ScaledMetric {
        ScaledMetric {
            a1: self.x1 / (self.lambda1 * radius2).sqrt(),
            a2: self.x2 / (self.lambda2 * radius2).sqrt(),
            a3: self.x3 / (self.lambda3 * radius2).sqrt(),
        }
    }

    /// Energy-preserving factor for photons in the tangent plane: the kernel's support there
    /// is an ellipse of area `π r² √(λ1 λ2)`, so a kernel normalised over the unit disc
    /// integrates to `r² √(λ1 λ2)`. (The paper's `√det D` includes λ3 and would brighten
    /// every estimate by `1/√λ3`.) Multiply by `1/r²` as well.
    #[inline]
    pub fn plane_normalisation(&self) -> f64 {
        1.0 / (self.lambda1 * self.lambda2).sqrt()
    }
}

/// `dᵀD⁻¹d / r²` as `Σ (d · a_i)²` with `a_i = X_i / √(λ_i r²)` (see
/// [`DiffusionTensor::metric`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScaledMetric {
    a1: DVec3,
    a2: DVec3,
    a3: DVec3,
}

impl ScaledMetric {
    #[inline(always)]
    /// The three scaled axes `a_i`.
    pub fn axes(&self) -> [DVec3; 3] {
        [self.a1, self.a2, self.a3]
    }

    pub fn distance(&self, d: DVec3) -> f64 {
        let (a, b, c) = (d.dot(self.a1), d.dot(self.a2), d.dot(self.a3));
        a * a + b * b + c * c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Lcg(u64);
    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    fn apply(t: &SymmetricTensor2, v: DVec2) -> DVec2 {
        DVec2::new(t.xx * v.x + t.xy * v.y, t.xy * v.x + t.yy * v.y)
    }

    #[test]
    fn eigen_reconstructs_random_symmetric_tensors() {
        let mut rng = Lcg(7);
        for i in 0..20_000 {
            let scale = 10f64.powi((i % 13) - 6);
            let t = SymmetricTensor2 {
                xx: (rng.next() * 2.0 - 1.0) * scale,
                xy: (rng.next() * 2.0 - 1.0) * scale,
                yy: (rng.next() * 2.0 - 1.0) * scale,
            };
            let e = t.eigen();
            let v = e.major_vector;
            let w = DVec2::new(-v.y, v.x);
            assert!((v.length() - 1.0).abs() < 1e-12);
            assert!(e.major >= e.minor);
            // T v = μ1 v, T w = μ2 w, relative to the tensor's size.
            let tol = 1e-12 * scale * 4.0;
            assert!((apply(&t, v) - e.major * v).length() < tol, "{t:?} {e:?}");
            assert!((apply(&t, w) - e.minor * w).length() < tol, "{t:?} {e:?}");
            // Trace and determinant are preserved.
            assert!((e.major + e.minor - (t.xx + t.yy)).abs() < tol);
            let det = t.xx * t.yy - t.xy * t.xy;
            assert!((e.major * e.minor - det).abs() < tol * scale * 4.0);
        }
    }

    #[test]
    fn eigen_of_rank_one_tensor_is_the_vector() {
        let mut rng = Lcg(3);
        for _ in 0..1000 {
            let a = rng.next() * std::f64::consts::TAU;
            let m = 1e-30 + rng.next() * 1e30;
            let g = DVec2::new(a.cos(), a.sin()) * m.sqrt();
            let e = SymmetricTensor2::outer(g).eigen();
            assert!((e.major / m - 1.0).abs() < 1e-12);
            assert!(e.minor.abs() <= 1e-12 * m);
            assert!(e.major_vector.dot(g.normalize()).abs() > 1.0 - 1e-12);
        }
    }

    #[test]
    fn eigen_of_isotropic_and_degenerate_tensors_is_finite() {
        for t in [
            SymmetricTensor2::default(),
            SymmetricTensor2 {
                xx: 2.0,
                xy: 0.0,
                yy: 2.0,
            },
            SymmetricTensor2 {
                xx: 1e-300,
                xy: 0.0,
                yy: 1e-300,
            },
            SymmetricTensor2 {
                xx: 0.0,
                xy: 1e-310,
                yy: 0.0,
            },
            SymmetricTensor2 {
                xx: f64::NAN,
                xy: 0.0,
                yy: 1.0,
            },
            SymmetricTensor2 {
                xx: f64::INFINITY,
                xy: 0.0,
                yy: 1.0,
            },
        ] {
            let e = t.eigen();
            assert!(e.major.is_finite() && e.minor.is_finite(), "{t:?}");
            assert!((e.major_vector.length() - 1.0).abs() < 1e-12, "{t:?}");
        }
        let e = SymmetricTensor2 {
            xx: 2.0,
            xy: 0.0,
            yy: 2.0,
        }
        .eigen();
        assert_eq!((e.major, e.minor), (2.0, 2.0));
        // A pure off-diagonal tensor has its major axis on the diagonal.
        let e = SymmetricTensor2 {
            xx: 0.0,
            xy: 1.0,
            yy: 0.0,
        }
        .eigen();
        assert!((e.major - 1.0).abs() < 1e-15);
        assert!((e.major_vector.x.abs() - e.major_vector.y.abs()).abs() < 1e-12);
    }

    #[test]
    fn diffusivity_limits() {
        assert_eq!(diffusivity(0.0, 0.2, 1.0), 1.0);
        assert_eq!(diffusivity(0.0, 0.0, 1.0), 1.0);
        assert_eq!(diffusivity(5.0, 0.0, 1.0), 0.0);
        assert_eq!(diffusivity(1e300, f64::INFINITY, 1.0), 1.0);
        assert_eq!(diffusivity(f64::INFINITY, 1.0, 1.0), 0.0);
        assert!((diffusivity(0.2, 0.2, 1.0) - 0.5).abs() < 1e-15);
        assert!((diffusivity(0.2, 0.2, 50.0) - 0.5).abs() < 1e-15);
        // Steeper with larger α: below K it stays nearer 1, above it falls faster.
        assert!(diffusivity(0.1, 0.2, 50.0) > diffusivity(0.1, 0.2, 1.0));
        assert!(diffusivity(0.4, 0.2, 50.0) < diffusivity(0.4, 0.2, 1.0));
        assert!(diffusivity(1e10, 1e-10, 50.0) >= 0.0);
        assert!(diffusivity(1e-10, 1e10, 1e-9) <= 1.0);
        let mut last = 1.0;
        for i in 1..200 {
            let l = diffusivity(i as f64 * 0.01, 0.2, 1.0);
            assert!(l < last && l > 0.0);
            last = l;
        }
    }

    #[test]
    fn mahalanobis_distance_and_normalisation() {
        let across = DVec3::new(1.0, 1.0, 0.0).normalize();
        let d = DiffusionTensor::new(across, DVec3::Z, 0.04, 0.1);
        assert!(d.x1.dot(d.x2).abs() < 1e-15 && (d.x1.length() - 1.0).abs() < 1e-15);
        let r2 = 4.0;
        // Along the edge the support reaches r; across it r √λ2; off the plane r √λ3.
        assert!((d.scaled_mahalanobis(d.x1 * 2.0, r2) - 1.0).abs() < 1e-12);
        assert!((d.scaled_mahalanobis(d.x2 * 0.4, r2) - 1.0).abs() < 1e-12);
        assert!((d.scaled_mahalanobis(DVec3::Z * 2.0 * 0.1f64.sqrt(), r2) - 1.0).abs() < 1e-12);
        assert!((d.plane_normalisation() - 5.0).abs() < 1e-12);
        let m = d.metric(r2);
        for v in [
            d.x1 * 2.0,
            d.x2 * 0.4,
            DVec3::new(0.3, -1.1, 0.25),
            DVec3::ZERO,
        ] {
            let (slow, fast) = (d.scaled_mahalanobis(v, r2), m.distance(v));
            assert!(
                (slow - fast).abs() <= 1e-12 * slow.max(1.0),
                "{v}: {slow} {fast}"
            );
        }
    }
}
