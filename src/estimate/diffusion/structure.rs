//! The structure tensor at a query (Eq. 7): the outer products `∇M ∇Mᵀ` of the photon
//! gradients near the query, averaged with a kernel weight, projected onto the tangent plane
//! of the query normal. Owns the tangent frame and the accumulation; must not gather photons
//! (the caller feeds it) nor decide the kernel shape.
//!
//! Projecting each gradient onto the tangent plane before the outer product gives the 2×2
//! tensor `P J Pᵀ` of the paper's 3×3 tensor `J`; on a flat surface the gradients already lie
//! in the plane and the two agree, and the 2×2 form has a closed-form eigen-decomposition.
//! Sums are in f64: `μ1` scales with the square of the light power and would overflow f32 for
//! powers near 1e20.

use super::tensor::SymmetricTensor2;
use glam::{DVec2, DVec3, Vec3};

/// An orthonormal frame `(t1, t2, n)` at a query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TangentFrame {
    pub t1: DVec3,
    pub t2: DVec3,
    pub normal: DVec3,
}

impl TangentFrame {
    /// From a normal of any nonzero length (a zero normal falls back to +z).
    pub fn new(normal: Vec3) -> Self {
        let normal = normal.as_dvec3().try_normalize().unwrap_or(DVec3::Z);
        let (t1, t2) = normal.any_orthonormal_pair();
        Self { t1, t2, normal }
    }

    /// Tangent-plane coordinates of `v` (its normal component is dropped).
    #[inline]
    pub fn project(&self, v: DVec3) -> DVec2 {
        DVec2::new(v.dot(self.t1), v.dot(self.t2))
    }

    /// The world vector with tangent-plane coordinates `p`.
    #[inline]
    pub fn to_world(&self, p: DVec2) -> DVec3 {
        self.t1 * p.x + self.t2 * p.y
    }
}

/// Kernel-weighted average of projected gradient outer products.
#[derive(Clone, Copy, Debug)]
pub struct StructureTensor {
    frame: TangentFrame,
    sum: SymmetricTensor2,
    weight: f64,
}

impl StructureTensor {
    pub fn new(frame: TangentFrame) -> Self {
        Self {
            frame,
            sum: SymmetricTensor2::default(),
            weight: 0.0,
        }
    }

    /// Adds the gradient stored at one photon with smoothing weight `weight ≥ 0`.
    #[inline]
    pub fn add(&mut self, gradient: Vec3, weight: f64) {
        let g = self.frame.project(gradient.as_dvec3());
        self.sum += SymmetricTensor2::outer(g) * weight;
        self.weight += weight;
    }

    /// Adds a weighted sum of world-space outer products `Σ w g gᵀ` (`sum`: xx, xy, xz, yy,
    /// yz, zz) whose weights sum to `weight`: projecting the sum equals summing the
    /// projections, so a scan may add a whole run of photons at once.
    #[inline]
    pub fn add_world_sum(&mut self, sum: [f64; 6], weight: f64) {
        let [xx, xy, xz, yy, yz, zz] = sum;
        let apply = |v: DVec3| {
            DVec3::new(
                xx * v.x + xy * v.y + xz * v.z,
                xy * v.x + yy * v.y + yz * v.z,
                xz * v.x + yz * v.y + zz * v.z,
            )
        };
        let (t1, t2) = (self.frame.t1, self.frame.t2);
        let s1 = apply(t1);
        self.sum += SymmetricTensor2 {
            xx: t1.dot(s1),
            xy: t2.dot(s1),
            yy: t2.dot(apply(t2)),
        };
        self.weight += weight;
    }

    /// The averaged tensor in tangent-plane coordinates (zero when nothing was added).
    pub fn average(&self) -> SymmetricTensor2 {
        if self.weight > 0.0 {
            self.sum * (1.0 / self.weight)
        } else {
            SymmetricTensor2::default()
        }
    }

    pub fn frame(&self) -> &TangentFrame {
        &self.frame
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_is_orthonormal_for_awkward_normals() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(1e-9, 0.0, -1.0),
            Vec3::new(3.0, -4.0, 1e-3),
        ] {
            let f = TangentFrame::new(n);
            for (a, b) in [(f.t1, f.t2), (f.t1, f.normal), (f.t2, f.normal)] {
                assert!(a.dot(b).abs() < 1e-12, "{n}");
            }
            for v in [f.t1, f.t2, f.normal] {
                assert!((v.length() - 1.0).abs() < 1e-12, "{n}");
            }
        }
        assert_eq!(TangentFrame::new(Vec3::ZERO).normal, DVec3::Z);
    }

    #[test]
    fn flat_gradients_give_their_direction_and_squared_length() {
        let mut s = StructureTensor::new(TangentFrame::new(Vec3::Z));
        let g = Vec3::new(3.0, 4.0, 0.0);
        s.add(g, 0.5);
        s.add(-g, 1.5); // the sign of a gradient does not matter to the tensor
        let e = s.average().eigen();
        assert!((e.major - 25.0).abs() < 1e-9);
        assert!(e.minor.abs() < 1e-9);
        let dir = s.frame().to_world(e.major_vector);
        assert!(dir.dot(g.as_dvec3().normalize()).abs() > 1.0 - 1e-12);
    }

    #[test]
    fn normal_components_are_dropped_and_huge_gradients_do_not_overflow() {
        let mut s = StructureTensor::new(TangentFrame::new(Vec3::Z));
        s.add(Vec3::new(0.0, 1e30, 1e38), 1.0);
        let e = s.average().eigen();
        assert!((e.major / 1e60 - 1.0).abs() < 1e-6);
        assert!(s.frame().to_world(e.major_vector).dot(DVec3::Y).abs() > 1.0 - 1e-12);
        assert_eq!(
            StructureTensor::new(TangentFrame::new(Vec3::Z)).average(),
            SymmetricTensor2::default()
        );
    }
}
