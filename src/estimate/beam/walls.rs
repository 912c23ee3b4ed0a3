//! The beam estimate beside the walls of a medium. A camera segment that ends on a surface
//! (or starts on one) runs close to it for a while, most of all at a grazing angle, and there
//! the kernel around the ray reaches past the wall where no photon of the medium can be: the
//! estimate reads dark by the share of the kernel cut off, down to half. Each photon's weight
//! is divided by the share of its kernel, centred on the ray where the photon lies along it,
//! that the wall leaves inside, taking the wall as the plane of the surface where the segment
//! meets it: exact for an even density beside a flat wall. Pure numerics; must not gather
//! photons or trace rays.

use crate::estimate::kernel::{epanechnikov_share_below, projected_ball_share_below};
use crate::photon::volume::KernelEllipsoid;
use glam::{DVec3, Vec3};

/// The surfaces at the ends of a camera segment in a medium, as the segment's ray sees them:
/// `None` where the segment starts at the camera, runs on into the same medium, or leaves
/// the scene.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SegmentWalls {
    start: Option<Wall>,
    end: Option<Wall>,
}

/// A wall seen from a ray: how it slants to the ray, and the way to it across the ray. The
/// same for every photon along the segment, so worked out once.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Wall {
    /// |cos| and sin of the angle between the wall's normal and the ray.
    cos: f32,
    sin: f32,
    /// The unit way to the wall within the kernel's plane (across the ray).
    toward: Vec3,
}

impl SegmentWalls {
    /// The walls of unit normals (either side) `start` and `end` for the ray `dir` (unit).
    pub fn new(start: Option<Vec3>, end: Option<Vec3>, dir: Vec3) -> Self {
        let wall = |n: Vec3| {
            let cos = n.dot(dir);
            let across = n - cos * dir;
            let sin = across.length();
            Wall {
                cos: cos.abs(),
                sin,
                toward: across / sin,
            }
        };
        Self {
            start: start.map(wall),
            end: end.map(wall),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.start.is_none() && self.end.is_none()
    }
}

/// The share of a photon's kernel that the walls leave inside, the kernel centred on the
/// segment's ray at `t` of `t0..t1`: `radius` for a round disc, or its ellipsoid.
pub fn kept_share(
    walls: &SegmentWalls,
    (t0, t, t1): (f32, f32, f32),
    radius: f32,
    shape: Option<&KernelEllipsoid>,
) -> f32 {
    let mut share = 1.0f32;
    for (wall, distance) in [(walls.start, t - t0), (walls.end, t1 - t)] {
        let Some(wall) = wall else { continue };
        let gap = distance.max(0.0) * wall.cos;
        // The kernel lies within its sphere: a wall past that leaves all of it (and one the
        // ray meets head on, sin 0, always does).
        if gap >= radius * wall.sin {
            continue;
        }
        let gap = (gap / wall.sin) as f64;
        share *= match shape {
            None => epanechnikov_share_below(gap / radius as f64),
            Some(shape) => projected_ball_share_below(gap / reach(shape, wall.toward.as_dvec3())),
        } as f32;
    }
    share
}

/// How far the ellipsoid reaches along the unit `m`: √(mᵀ M⁻¹ m).
fn reach(shape: &KernelEllipsoid, m: DVec3) -> f64 {
    let [xx, yy, zz, xy, xz, yz] = shape.metric.map(f64::from);
    // M⁻¹ = adj(M) / det M, det M = root_det².
    let adjugate = [
        yy * zz - yz * yz,
        xx * zz - xz * xz,
        xx * yy - xy * xy,
        xz * yz - xy * zz,
        xy * yz - xz * yy,
        xy * xz - xx * yz,
    ];
    let [a, b, c, d, e, f] = adjugate;
    let quadratic = a * m.x * m.x
        + b * m.y * m.y
        + c * m.z * m.z
        + 2.0 * (d * m.x * m.y + e * m.x * m.z + f * m.y * m.z);
    let det = (shape.root_det as f64).powi(2);
    (quadratic / det).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::beam::disc_kernel;
    use crate::estimate::beam::ellipsoid::{ellipsoid, line_integral};

    /// An even spread of kernels beside a flat wall, read along a ray that meets the wall at
    /// a grazing angle: with each weight divided by its kept share, every stretch of the ray
    /// reads what it would far from any wall.
    #[test]
    fn beside_a_wall_the_kept_share_restores_an_even_density() {
        let wall = Vec3::new(1.0, 0.0, 0.0);
        // The ray runs towards the wall x = 0 from x = -1 at 17° to it.
        let dir = Vec3::new(0.3, 0.0, -1.0).normalize();
        let t1 = 1.0 / dir.x;
        let origin = Vec3::new(-1.0, 0.0, 0.0);
        let walls = SegmentWalls::new(None, Some(wall), dir);
        let shape = ellipsoid(
            [
                DVec3::X,
                DVec3::new(0.0, 0.6, 0.8),
                DVec3::new(0.0, -0.8, 0.6),
            ],
            [0.3, 1.0, 0.5],
            0.2,
        );
        for shaped in [false, true] {
            // Kernels centred on a fine grid filling x < 0 (the medium), unit density.
            let h = 0.01f32;
            let (mut read, mut naive) = (0.0f64, 0.0f64);
            for i in 0..60 {
                for j in -40..=40 {
                    for k in -360..=-170 {
                        let p = Vec3::new(-(i as f32 + 0.5) * h, j as f32 * h, k as f32 * h);
                        let to = p - origin;
                        let t = to.dot(dir);
                        if !(0.0..t1).contains(&t) {
                            continue;
                        }
                        let kernel = match shaped {
                            false => {
                                let d2 = (to - t * dir).length_squared();
                                disc_kernel(d2 / 0.04) / 0.04
                            }
                            true => line_integral(&shape, origin - p, dir),
                        };
                        if kernel <= 0.0 {
                            continue;
                        }
                        let s = shaped.then_some(&shape);
                        let kept = kept_share(&walls, (0.0, t, t1), 0.2, s);
                        // Only the last stretch, where the wall cuts the kernels, and away
                        // from the segment's start (no photons before it).
                        if t > t1 - 1.2 {
                            read += (kernel / kept) as f64 * (h as f64).powi(3);
                            naive += kernel as f64 * (h as f64).powi(3);
                        }
                    }
                }
            }
            // Unit density along a stretch of length 1.2 reads 1.2.
            let want = 1.2;
            assert!(
                (read - want).abs() < 0.005 * want,
                "shaped {shaped}: {read} against {want} ({naive} uncorrected)"
            );
            assert!(naive < 0.95 * want, "the wall cut {naive}");
        }
    }

    #[test]
    fn no_wall_or_a_wall_the_ray_meets_head_on_keeps_everything() {
        let walls = SegmentWalls::new(None, Some(Vec3::Z), Vec3::Z);
        assert_eq!(kept_share(&walls, (0.0, 0.99, 1.0), 0.1, None), 1.0);
        let none = SegmentWalls::default();
        assert_eq!(kept_share(&none, (0.0, 0.99, 1.0), 0.1, None), 1.0);
    }
}
