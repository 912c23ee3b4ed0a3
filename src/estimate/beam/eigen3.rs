//! The symmetric 3×3 tensor of the volume kernel's structure analysis and its
//! eigen-decomposition by cyclic Jacobi rotations (exact to rounding for any symmetric input,
//! no special cases for repeated eigenvalues). Pure numerics in f64; must not know photons.

use glam::{DMat3, DVec3};

/// A symmetric 3×3 tensor, `[xx, yy, zz, xy, xz, yz]`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SymmetricTensor3(pub [f64; 6]);

/// Eigenvalues in decreasing order with their unit eigenvectors (signs arbitrary).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Eigen3 {
    pub values: [f64; 3],
    pub vectors: [DVec3; 3],
}

impl SymmetricTensor3 {
    /// `g gᵀ`.
    pub fn outer(g: DVec3) -> Self {
        Self([
            g.x * g.x,
            g.y * g.y,
            g.z * g.z,
            g.x * g.y,
            g.x * g.z,
            g.y * g.z,
        ])
    }

    /// `self + w·other`.
    pub fn add_scaled(&mut self, other: &Self, w: f64) {
        for (a, b) in self.0.iter_mut().zip(other.0) {
            *a += w * b;
        }
    }

    pub fn scaled(&self, w: f64) -> Self {
        Self(self.0.map(|v| v * w))
    }

    pub fn matrix(&self) -> DMat3 {
        let [xx, yy, zz, xy, xz, yz] = self.0;
        DMat3::from_cols(
            DVec3::new(xx, xy, xz),
            DVec3::new(xy, yy, yz),
            DVec3::new(xz, yz, zz),
        )
    }

    /// The eigen-decomposition. A tensor with a non-finite entry reports zeros on the axes.
    pub fn eigen(&self) -> Eigen3 {
        if self.0.iter().any(|v| !v.is_finite()) {
            return Eigen3 {
                values: [0.0; 3],
                vectors: [DVec3::X, DVec3::Y, DVec3::Z],
            };
        }
        let mut a = [[0.0f64; 3]; 3];
        let m = self.matrix();
        for (c, col) in [m.x_axis, m.y_axis, m.z_axis].iter().enumerate() {
            for r in 0..3 {
                a[r][c] = col[r];
            }
        }
        let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        for _sweep in 0..32 {
            let off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
            let diag = a[0][0] * a[0][0] + a[1][1] * a[1][1] + a[2][2] * a[2][2];
            if off <= 1e-30 * diag || off == 0.0 {
                break;
            }
            for (p, q) in [(0, 1), (0, 2), (1, 2)] {
                if a[p][q] == 0.0 {
                    continue;
                }
                // The rotation that zeroes a[p][q] (Golub and Van Loan, 8.4).
                let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                // A ← Jᵀ A J: the columns p and q, then the rows.
                for row in a.iter_mut() {
                    let (akp, akq) = (row[p], row[q]);
                    row[p] = c * akp - s * akq;
                    row[q] = s * akp + c * akq;
                }
                let (row_p, row_q) = (a[p], a[q]);
                for k in 0..3 {
                    a[p][k] = c * row_p[k] - s * row_q[k];
                    a[q][k] = s * row_p[k] + c * row_q[k];
                }
                for row in v.iter_mut() {
                    let (vp, vq) = (row[p], row[q]);
                    row[p] = c * vp - s * vq;
                    row[q] = s * vp + c * vq;
                }
            }
        }
        let mut order = [0usize, 1, 2];
        order.sort_by(|&i, &j| a[j][j].total_cmp(&a[i][i]));
        Eigen3 {
            values: order.map(|i| a[i][i]),
            vectors: order.map(|i| DVec3::new(v[0][i], v[1][i], v[2][i])),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rebuilt(e: &Eigen3) -> SymmetricTensor3 {
        let mut t = SymmetricTensor3::default();
        for (value, vector) in e.values.iter().zip(e.vectors) {
            t.add_scaled(&SymmetricTensor3::outer(vector), *value);
        }
        t
    }

    #[test]
    fn eigenvectors_are_orthonormal_and_rebuild_the_tensor_for_random_and_degenerate_inputs() {
        let mut cases = vec![
            SymmetricTensor3([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]),
            SymmetricTensor3([0.0; 6]),
            SymmetricTensor3([2.0, 2.0, 5.0, 0.0, 0.0, 0.0]),
            SymmetricTensor3::outer(DVec3::new(1.0, 2.0, -3.0)),
            SymmetricTensor3([1e-12, 3e8, 1.0, 1e-3, 7.0, -2e4]),
        ];
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..500 {
            cases.push(SymmetricTensor3([0; 6].map(|_| next() * 10.0)));
        }
        for t in cases {
            let e = t.eigen();
            assert!(
                e.values[0] >= e.values[1] && e.values[1] >= e.values[2],
                "{e:?}"
            );
            for i in 0..3 {
                for j in 0..3 {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (e.vectors[i].dot(e.vectors[j]) - want).abs() < 1e-12,
                        "{t:?}"
                    );
                }
                // A v = λ v.
                let av = t.matrix() * e.vectors[i];
                let scale = t.0.iter().fold(1e-300f64, |m, v| m.max(v.abs()));
                assert!(
                    (av - e.values[i] * e.vectors[i]).length() < 1e-12 * scale,
                    "{t:?}"
                );
            }
            let back = rebuilt(&e);
            let scale = t.0.iter().fold(1e-300f64, |m, v| m.max(v.abs()));
            for (a, b) in back.0.iter().zip(t.0) {
                assert!((a - b).abs() <= 1e-12 * scale, "{t:?} vs {back:?}");
            }
        }
    }

    #[test]
    fn a_non_finite_tensor_reports_zeros() {
        let e = SymmetricTensor3([f64::NAN, 0.0, 0.0, 0.0, 0.0, 0.0]).eigen();
        assert_eq!(e.values, [0.0; 3]);
    }
}
