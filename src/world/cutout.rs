//! Alpha cut-outs as Embree sees them: one [`CutoutFilter`] per cut mesh, which Embree asks,
//! hit by hit and for every kind of ray (eye rays, photons, shadow rays), whether the mesh is
//! there. Owns reading a hit's texture coordinates for its mask and the hash that turns a
//! fractional alpha into the same answer for the same ray; must not shade or trace rays.

use crate::embree::{Candidate, HitFilter};
use crate::scene::{Cutout, TriangleMesh};
use glam::Vec3;
use std::sync::Arc;

/// A cut mesh's answer to Embree: the mesh, for its corners' (u, v), and its masks.
pub(super) struct CutoutFilter {
    mesh: Arc<TriangleMesh>,
    cutout: Cutout,
}

impl CutoutFilter {
    pub(super) fn new(mesh: Arc<TriangleMesh>, cutout: &Cutout) -> Self {
        Self {
            mesh,
            cutout: cutout.clone(),
        }
    }
}

impl HitFilter for CutoutFilter {
    fn accept(&self, c: &Candidate) -> bool {
        if c.primitive as usize >= self.mesh.triangles.len() {
            return true;
        }
        let [t0, t1, t2] = self.mesh.corner_uvs(c.primitive as usize);
        let uv = (1.0 - c.u - c.v) * t0 + c.u * t1 + c.v * t2;
        let coverage = self.cutout.coverage(uv, c.is_occlusion());
        if coverage >= 1.0 {
            true
        } else if coverage > 0.0 {
            ray_fraction(c.origin(), c.dir(), c.primitive) < coverage
        } else {
            // Zero, negative or NaN: not there.
            false
        }
    }
}

/// A number in [0, 1) fixed by the ray and the primitive, so the same ray meets a
/// half-transparent surface the same way on any thread and in any pass order.
fn ray_fraction(origin: Vec3, dir: Vec3, primitive: u32) -> f32 {
    let mut h = 0x9e37_79b9_7f4a_7c15u64 ^ u64::from(primitive);
    for x in origin.to_array().into_iter().chain(dir.to_array()) {
        h = mix(h ^ u64::from(x.to_bits()));
    }
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// splitmix64's finaliser: every input bit reaches every output bit.
fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Texture;
    use glam::Vec2;

    fn quad(cutout: &Cutout) -> CutoutFilter {
        let mesh = TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]),
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            ..Default::default()
        };
        CutoutFilter::new(Arc::new(mesh), cutout)
    }

    #[test]
    fn a_half_alpha_lets_half_the_rays_through_and_answers_a_ray_the_same_way_twice() {
        let filter = quad(&Cutout {
            alpha: Texture::Constant(Vec3::splat(0.3)),
            shadow_alpha: None,
        });
        let n = 100_000;
        let mut met = 0;
        for i in 0..n {
            let origin = Vec3::new(i as f32 * 1e-3, 0.5, -1.0);
            let c = Candidate::new(i % 2, 0.2, 0.3, origin, Vec3::Z, false);
            let first = filter.accept(&c);
            assert_eq!(first, filter.accept(&c));
            met += u32::from(first);
        }
        let fraction = f64::from(met) / f64::from(n);
        // 0.3 ± 4.5 standard deviations of a binomial at 1e5 rays.
        assert!((fraction - 0.3).abs() < 0.0066, "{fraction}");
    }

    #[test]
    fn the_mask_is_read_at_the_hits_texture_coordinates_and_shadow_rays_see_both_masks() {
        // Alpha 1 for u < 0.5, 0 beyond; the shadow mask cuts v > 0.5 as well.
        let half = |axis: Vec2| Texture::Checkerboard {
            mapping: crate::scene::texture::UvMapping {
                scale: Vec2::new(2.0, 2.0) * axis + (Vec2::ONE - axis) * 1e-3,
                delta: Vec2::ZERO,
            },
            even: Box::new(Texture::Constant(Vec3::ONE)),
            odd: Box::new(Texture::Constant(Vec3::ZERO)),
        };
        let filter = quad(&Cutout {
            alpha: half(Vec2::X),
            shadow_alpha: Some(half(Vec2::Y)),
        });
        // Triangle 0 has corners (0,0), (1,0), (1,1): barycentrics (u, v) give (u + v, v).
        let at = |u: f32, v: f32, shadow| {
            filter.accept(&Candidate::new(0, u, v, Vec3::ZERO, Vec3::Z, shadow))
        };
        assert!(at(0.2, 0.1, false)); // (0.3, 0.1)
        assert!(!at(0.6, 0.1, false)); // (0.7, 0.1)
        assert!(at(0.2, 0.1, true));
        // Triangle 1 has corners (0,0), (1,1), (0,1): (0.2, 0.7) is cut for shadow rays only.
        let on_second =
            |shadow| filter.accept(&Candidate::new(1, 0.2, 0.5, Vec3::ZERO, Vec3::Z, shadow));
        assert!(on_second(false));
        assert!(!on_second(true));
        assert!(!at(0.6, 0.1, true));
        // (0.45, 0.4): alpha keeps it, the shadow mask keeps it.
        assert!(at(0.05, 0.4, true));
    }
}
