//! A volume photon's kernel as an ellipsoid: the 3-D Epanechnikov kernel
//! `(15/8π)(1 − u²)` over the unit ball, mapped onto the ellipsoid of axes `r√λᵢ` along
//! orthonormal `eᵢ` and multiplied by `√det M` so that its integral stays 1 whatever its shape,
//! and its integral along a line in closed form (what the beam estimate needs: a camera ray
//! through the ellipsoid collects `(5/2π)(1 − u²ₘᵢₙ)^{3/2} √det M / √(wᵀMw)`, `u²ₘᵢₙ` the
//! line's least squared distance from the centre in the ellipsoid's metric). Pure numerics;
//! must not gather photons.

use crate::photon::volume::KernelEllipsoid;
use glam::{DVec3, Vec3};

/// The ellipsoid with semi-axes `radius·√lambdas[i]` along the orthonormal `axes[i]`.
pub fn ellipsoid(axes: [DVec3; 3], lambdas: [f64; 3], radius: f64) -> KernelEllipsoid {
    let r2 = radius * radius;
    let mut m = [0.0f64; 6];
    for (e, &lambda) in axes.iter().zip(&lambdas) {
        let w = 1.0 / (lambda * r2);
        m[0] += w * e.x * e.x;
        m[1] += w * e.y * e.y;
        m[2] += w * e.z * e.z;
        m[3] += w * e.x * e.y;
        m[4] += w * e.x * e.z;
        m[5] += w * e.y * e.z;
    }
    let root_det = 1.0 / (r2 * radius * (lambdas[0] * lambdas[1] * lambdas[2]).sqrt());
    KernelEllipsoid {
        metric: m.map(|v| v as f32),
        root_det: root_det as f32,
    }
}

/// The round kernel of `radius`.
pub fn ball(radius: f64) -> KernelEllipsoid {
    ellipsoid([DVec3::X, DVec3::Y, DVec3::Z], [1.0; 3], radius)
}

#[inline]
fn apply(m: &[f32; 6], v: Vec3) -> Vec3 {
    let [xx, yy, zz, xy, xz, yz] = *m;
    Vec3::new(
        xx * v.x + xy * v.y + xz * v.z,
        xy * v.x + yy * v.y + yz * v.z,
        xz * v.x + yz * v.y + zz * v.z,
    )
}

/// The kernel's integral along the line `q + s·w` (unit `w`, `q` the line's point relative
/// to the photon): zero where the line misses the ellipsoid.
#[inline]
pub fn line_integral(shape: &KernelEllipsoid, q: Vec3, w: Vec3) -> f32 {
    // From the line's point nearest the centre: `c` and `b²/a` stay small, so their
    // difference keeps its digits however far `q` was.
    let q = q - q.dot(w) * w;
    let mw = apply(&shape.metric, w);
    let a = w.dot(mw);
    let b = q.dot(mw);
    let c = q.dot(apply(&shape.metric, q));
    let u2 = c - b * b / a;
    // Also a NaN (a degenerate metric): no contribution.
    if u2.is_nan() || u2 >= 1.0 {
        return 0.0;
    }
    let inside = 1.0 - u2.max(0.0);
    const FIVE_OVER_TWO_PI: f32 = 5.0 / (2.0 * std::f32::consts::PI);
    FIVE_OVER_TWO_PI * inside * inside.sqrt() * shape.root_det / a.sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::beam::eigen3::SymmetricTensor3;

    use crate::sampling::{Rng, Stream};

    /// Test draws: uniform numbers, unit vectors, orthonormal frames.
    struct Draws(Rng);
    impl Draws {
        fn new(seed: u64) -> Self {
            Self(Rng::for_index(seed, Stream::Pixels, 0))
        }
        fn next(&mut self) -> f64 {
            self.0.next_f32() as f64
        }
        fn unit(&mut self) -> DVec3 {
            loop {
                let v = DVec3::new(self.next(), self.next(), self.next()) * 2.0 - 1.0;
                if v.length_squared() > 0.01 && v.length_squared() <= 1.0 {
                    return v.normalize();
                }
            }
        }
        /// A random orthonormal frame, from a random symmetric tensor's eigenvectors.
        fn frame(&mut self) -> [DVec3; 3] {
            SymmetricTensor3([0; 6].map(|_| self.next()))
                .eigen()
                .vectors
        }
    }

    /// The kernel at offset `d` from the photon, straight from its definition.
    fn kernel(shape: &KernelEllipsoid, d: DVec3) -> f64 {
        let u2 = d.as_vec3().dot(apply(&shape.metric, d.as_vec3())) as f64;
        match u2 < 1.0 {
            true => 15.0 / (8.0 * std::f64::consts::PI) * (1.0 - u2) * shape.root_det as f64,
            false => 0.0,
        }
    }

    #[test]
    fn the_closed_form_matches_quadrature_along_random_lines_through_random_ellipsoids() {
        let mut rng = Draws::new(7);
        for case in 0..300 {
            let lambdas = [0.02 + rng.next(), 0.02 + rng.next(), 1.0];
            let radius = 0.1 + rng.next();
            let shape = ellipsoid(rng.frame(), lambdas, radius);
            let w = rng.unit();
            let q = rng.unit() * radius * rng.next() - w * 3.0 * radius;
            let steps = 200_000;
            let h = 6.0 * radius / steps as f64;
            let brute: f64 = (0..steps)
                .map(|i| kernel(&shape, q + w * (i as f64 + 0.5) * h) * h)
                .sum();
            let closed = line_integral(&shape, q.as_vec3(), w.as_vec3()) as f64;
            let scale = brute.abs().max(closed.abs()).max(1e-6 / (radius * radius));
            assert!(
                (brute - closed).abs() < 2e-3 * scale,
                "case {case}: {brute} vs {closed}"
            );
        }
    }

    #[test]
    fn summed_over_a_plane_of_parallel_rays_every_ellipsoid_gives_one() {
        // Energy: a photon's power reaches the rays crossing it exactly once, however thin.
        let mut rng = Draws::new(11);
        for case in 0..40 {
            let lambdas = [
                0.005 + 0.3 * rng.next(),
                0.01 + rng.next(),
                0.5 + 0.5 * rng.next(),
            ];
            let shape = ellipsoid(rng.frame(), lambdas, 0.3);
            let w = rng.unit();
            let u = w.any_orthonormal_vector();
            let v = w.cross(u);
            let (n, half) = (1200, 0.31);
            let h = 2.0 * half / n as f64;
            let mut sum = 0.0f64;
            for i in 0..n {
                for j in 0..n {
                    let q = u * (-half + (i as f64 + 0.5) * h) + v * (-half + (j as f64 + 0.5) * h);
                    sum += line_integral(&shape, q.as_vec3(), w.as_vec3()) as f64 * h * h;
                }
            }
            assert!(
                (sum - 1.0).abs() < 5e-3,
                "case {case}: {sum} for λ {lambdas:?}"
            );
        }
    }

    #[test]
    fn a_round_kernel_integrates_to_the_projected_epanechnikov_profile() {
        let r = 0.4f64;
        let shape = ball(r);
        for b in [0.0, 0.1, 0.25, 0.39, 0.41] {
            let q = Vec3::new(b as f32, 0.0, -1.0);
            let got = line_integral(&shape, q, Vec3::Z) as f64;
            let x2 = (b / r) * (b / r);
            let want = match x2 < 1.0 {
                true => 5.0 / (2.0 * std::f64::consts::PI) * (1.0 - x2).powf(1.5) / (r * r),
                false => 0.0,
            };
            assert!(
                (got - want).abs() < 1e-5 * want.max(1.0),
                "b {b}: {got} vs {want}"
            );
        }
    }

    #[test]
    fn a_needle_thin_ellipsoid_stays_finite() {
        let shape = ellipsoid([DVec3::X, DVec3::Y, DVec3::Z], [1e-6, 1e-6, 1.0], 1.0);
        for w in [Vec3::X, Vec3::Z, Vec3::new(1.0, 1.0, 1.0).normalize()] {
            let value = line_integral(&shape, Vec3::ZERO - 2.0 * w, w);
            assert!(value.is_finite() && value > 0.0, "{w}: {value}");
        }
    }
}
