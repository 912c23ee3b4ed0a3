//! Where caustic photons are aimed: the bounding spheres of the mirror and glass objects, and
//! the union of the cones towards them from a point, from which an aimed photon draws its
//! direction. Owns those cones and their sampling density; must not know lights, trace rays or
//! store photons.
//!
//! One sphere per object, not one around them all: two small spheres far apart (the Cornell
//! box's) subtend a far smaller solid angle than the sphere that holds both, and every photon
//! aimed into the gap between them is traced for nothing. For the same reason a mesh is split
//! into up to [`MAX_TARGETS`] clusters of triangles, each in its own sphere: the torus knot's
//! tube fills little of the one sphere around it.

use super::BoundingSphere;
use crate::sampling::{ConeFrame, Rng, cone_solid_angle};
use crate::scene::{Shape, TriangleMesh};
use glam::Vec3;

/// Scenes with more mirror and glass objects than this are aimed at one sphere around them all:
/// every aimed photon tests every cone.
pub const MAX_TARGETS: usize = 8;

/// The spheres to aim caustic photons at, for at most [`MAX_TARGETS`] mirror and glass shapes:
/// a sphere is its own target, curves are aimed at the sphere around their box, a mesh is
/// split into clusters sharing what is left of the budget (a power of two each).
pub fn targets(specular: &[&Shape]) -> Vec<BoundingSphere> {
    assert!(specular.len() <= MAX_TARGETS, "too many shapes to aim at");
    let meshes = specular
        .iter()
        .filter(|s| matches!(s, Shape::Triangles(_)))
        .count();
    let spare = MAX_TARGETS - (specular.len() - meshes);
    // Clusters per mesh: the largest power of two that the meshes can all have.
    let clusters = spare
        .checked_div(meshes)
        .map_or(1, |each| 1 << each.max(1).ilog2());
    let mut targets = Vec::new();
    for shape in specular {
        match shape {
            Shape::Sphere { center, radius, .. } => targets.push(BoundingSphere {
                center: *center,
                radius: radius * 1.001,
            }),
            Shape::Triangles(mesh) => {
                let all: Vec<u32> = (0..mesh.triangles.len() as u32).collect();
                split_mesh(mesh, all, clusters, &mut targets);
            }
            Shape::Curves(curves) => {
                let (lo, hi) = curves.bounds();
                targets.push(BoundingSphere::around_box(lo, hi));
            }
        }
    }
    targets
}

/// Splits `triangles` of `mesh` at the median of their centroids along the widest axis until
/// there are `clusters` groups, and appends a sphere around each.
fn split_mesh(
    mesh: &TriangleMesh,
    mut triangles: Vec<u32>,
    clusters: usize,
    out: &mut Vec<BoundingSphere>,
) {
    let vertices = |t: u32| mesh.triangles[t as usize].map(|i| mesh.positions[i as usize]);
    if clusters <= 1 || triangles.len() < 2 {
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for &t in &triangles {
            for p in vertices(t) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        let center = 0.5 * (lo + hi);
        let reach = (triangles.iter())
            .flat_map(|&t| vertices(t))
            .map(|p| p.distance(center))
            .fold(0.0f32, f32::max);
        // Relative margin, as for boxes; a lone degenerate cluster still gets a radius.
        let box_sphere = BoundingSphere::around_box(lo, hi);
        out.push(BoundingSphere {
            center,
            radius: (reach * 1.001).max(box_sphere.radius * 1e-3),
        });
        return;
    }
    let centroid = |t: u32| {
        let [a, b, c] = vertices(t);
        (a + b + c) / 3.0
    };
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for &t in &triangles {
        lo = lo.min(centroid(t));
        hi = hi.max(centroid(t));
    }
    let axis = (hi - lo).max_position();
    let half = triangles.len() / 2;
    triangles.select_nth_unstable_by(half, |&a, &b| {
        centroid(a)[axis].total_cmp(&centroid(b)[axis])
    });
    let upper = triangles.split_off(half);
    split_mesh(mesh, triangles, clusters / 2, out);
    split_mesh(mesh, upper, clusters / 2, out);
}

/// The cone from `origin` that just holds the sphere `target`: its unit axis and the cosine of
/// its half-angle. `None` from inside the sphere.
#[inline(always)]
pub fn cone_towards(target: &BoundingSphere, origin: Vec3) -> Option<(Vec3, f32)> {
    let to = target.center - origin;
    let d2 = to.length_squared();
    if d2 <= target.radius * target.radius {
        return None;
    }
    let inverse_distance = 1.0 / d2.sqrt();
    let sin_max = target.radius * inverse_distance;
    Some((
        to * inverse_distance,
        (1.0 - sin_max * sin_max).max(0.0).sqrt(),
    ))
}

/// Cones of directions, drawn from as one set: a cone is picked in proportion to its solid
/// angle, a direction drawn uniformly in it, and its density is the number of cones that hold
/// it over their total solid angle. That is uniform over the union, overlaps included.
#[derive(Clone, Copy, Debug)]
pub struct UnionOfCones {
    /// Unit axis and cosine of the half-angle of each cone.
    cones: [(Vec3, f32); MAX_TARGETS],
    /// Solid angles summed up to and including each cone.
    cumulative: [f32; MAX_TARGETS],
    len: usize,
}

/// A union of cones drawn from many times (a light's cones towards fixed targets), with every
/// cone's frame built once; a union drawn from once builds only the frame of the cone it picks.
#[derive(Clone, Copy, Debug)]
pub struct PreparedUnion {
    union: UnionOfCones,
    frames: [ConeFrame; MAX_TARGETS],
}

impl UnionOfCones {
    pub fn empty() -> Self {
        Self {
            cones: [(Vec3::Z, 1.0); MAX_TARGETS],
            cumulative: [0.0; MAX_TARGETS],
            len: 0,
        }
    }

    #[inline(always)]
    fn push(&mut self, cone: (Vec3, f32)) {
        assert!(self.len < MAX_TARGETS, "more than {MAX_TARGETS} cones");
        let before = if self.len == 0 {
            0.0
        } else {
            self.cumulative[self.len - 1]
        };
        self.cones[self.len] = cone;
        self.cumulative[self.len] = before + cone_solid_angle(cone.1);
        self.len += 1;
    }

    /// The union of `cones` (unit axis, cosine of the half-angle). `None` for no cones; cones
    /// past [`MAX_TARGETS`] are a caller's error.
    pub fn new(cones: impl IntoIterator<Item = (Vec3, f32)>) -> Option<Self> {
        let mut union = Self::empty();
        for cone in cones {
            union.push(cone);
        }
        (union.len > 0).then_some(union)
    }

    /// The cones from `origin` towards every target; `None` without targets, or when `origin`
    /// lies inside one (no cone holds all the directions to it).
    #[inline(always)]
    pub fn towards(targets: &[BoundingSphere], origin: Vec3) -> Option<Self> {
        let mut union = Self::empty();
        union.aim(targets, origin).then_some(union)
    }

    /// The cones from `origin` towards the targets that do not hold it; `None` when every
    /// target holds it. The set depends on `origin` alone, so drawing from it and its
    /// density agree at every point.
    #[inline(always)]
    pub fn towards_those_outside(targets: &[BoundingSphere], origin: Vec3) -> Option<Self> {
        let mut union = Self::empty();
        for target in targets {
            if let Some(cone) = cone_towards(target, origin) {
                union.push(cone);
            }
        }
        (union.len > 0).then_some(union)
    }

    /// Makes this the union of the cones from `origin` towards every target, in place (a
    /// light drawing a union per photon does not copy it around); false, and no union, where
    /// [`UnionOfCones::towards`] gives `None`.
    #[inline(always)]
    pub fn aim(&mut self, targets: &[BoundingSphere], origin: Vec3) -> bool {
        self.len = 0;
        for target in targets {
            let Some(cone) = cone_towards(target, origin) else {
                self.len = 0;
                return false;
            };
            self.push(cone);
        }
        self.len > 0
    }

    /// The same union with every cone's frame built once, for drawing from it many times.
    pub fn prepared(self) -> PreparedUnion {
        PreparedUnion {
            union: self,
            frames: self
                .cones
                .map(|(axis, cos_max)| ConeFrame::new(axis, cos_max)),
        }
    }

    /// Cone `k`: its unit axis and the cosine of its half-angle.
    pub fn cone(&self, k: usize) -> (Vec3, f32) {
        self.cones[..self.len][k]
    }

    /// The solid angles of cones `0..=k` summed.
    pub fn cumulative(&self, k: usize) -> f32 {
        self.cumulative[..self.len][k]
    }

    /// Total solid angle of the cones (their union where they do not overlap).
    pub fn solid_angle(&self) -> f32 {
        self.cumulative[self.len - 1]
    }

    /// A direction drawn uniformly from the union, and the reciprocal of its density (the
    /// solid angle a photon sent that way stands for).
    #[inline(always)]
    pub fn sample(&self, rng: &mut Rng) -> (Vec3, f32) {
        self.sample_with(rng, |k| ConeFrame::new(self.cones[k].0, self.cones[k].1))
    }

    #[inline(always)]
    fn sample_with(&self, rng: &mut Rng, frame: impl Fn(usize) -> ConeFrame) -> (Vec3, f32) {
        draw_from_cones(&self.cumulative[..self.len], |j| self.cones[j], frame, rng)
    }

    /// The density over solid angle with which [`UnionOfCones::sample`] draws the unit
    /// `direction`: the cones holding it over their total solid angle.
    #[inline(always)]
    pub fn density(&self, direction: Vec3) -> f32 {
        let holding = (self.cones[..self.len].iter())
            .filter(|&&(axis, cos_max)| direction.dot(axis) >= cos_max)
            .count();
        holding as f32 / self.solid_angle()
    }

    /// Whether every cone lies wholly behind a surface with unit `normal`, so that a surface
    /// there sends no light into any: n·axis < −(sin_max + δ) with δ = 1e-3, squared to spare a
    /// square root ((sin + δ)² < sin² + 3δ), so no cone that could take light is left out.
    #[inline(always)]
    pub fn behind(&self, normal: Vec3) -> bool {
        self.cones[..self.len].iter().all(|&(axis, cos_max)| {
            let along = normal.dot(axis);
            along < 0.0 && along * along > 1.0 - cos_max * cos_max + 3e-3
        })
    }
}

/// A direction drawn uniformly from a union of cones, and the reciprocal of its density: a cone
/// picked in proportion to its solid angle (`cumulative`, summed up to and including each),
/// a direction drawn in it from its `frame`, and the density counted over the cones (`cone`:
/// unit axis and cosine of the half-angle) that hold it.
#[inline(always)]
pub(crate) fn draw_from_cones(
    cumulative: &[f32],
    cone: impl Fn(usize) -> (Vec3, f32),
    frame: impl Fn(usize) -> ConeFrame,
    rng: &mut Rng,
) -> (Vec3, f32) {
    let len = cumulative.len();
    let total = cumulative[len - 1];
    if len == 1 {
        return (frame(0).sample(rng.next_2d()), total);
    }
    let pick = rng.next_f32() * total;
    let k = cumulative.iter().position(|&c| pick < c).unwrap_or(len - 1);
    let direction = frame(k).sample(rng.next_2d());
    // The cone it was drawn from counts whatever rounding says of it.
    let holding = 1
        + (0..len)
            .filter(|&j| {
                let (axis, cos_max) = cone(j);
                j != k && direction.dot(axis) >= cos_max
            })
            .count();
    (direction, total / holding as f32)
}

impl PreparedUnion {
    /// As [`UnionOfCones::sample`], on the same numbers, with the frames already built.
    #[inline(always)]
    pub fn sample(&self, rng: &mut Rng) -> (Vec3, f32) {
        self.union.sample_with(rng, |k| self.frames[k])
    }

    /// Number of cones.
    pub fn len(&self) -> usize {
        self.union.len
    }

    /// Always false: a union has at least one cone.
    pub fn is_empty(&self) -> bool {
        self.union.len == 0
    }

    /// The frame of cone `k`.
    #[inline(always)]
    pub fn frame(&self, k: usize) -> &ConeFrame {
        &self.frames[..self.union.len][k]
    }

    /// Whether cone `k` holds the unit `direction`.
    #[inline(always)]
    pub fn holds(&self, k: usize, direction: Vec3) -> bool {
        let (axis, cos_max) = self.union.cone(k);
        direction.dot(axis) >= cos_max
    }

    /// Solid angle of cone `k`.
    pub fn solid_angle_of(&self, k: usize) -> f32 {
        cone_solid_angle(self.union.cone(k).1)
    }

    /// The cones' solid angles summed (the reciprocal of the union's density where no two
    /// overlap).
    pub fn solid_angle_of_all(&self) -> f32 {
        self.union.solid_angle()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Stream, uniform_sphere};

    fn target(center: Vec3, radius: f32) -> BoundingSphere {
        BoundingSphere { center, radius }
    }

    /// Overlapping and separate targets: the weighted average of a function over the union's
    /// samples matches its integral over the union, found by sampling the whole sphere.
    #[test]
    fn union_sampling_integrates_over_the_union() {
        let sets = [
            vec![target(Vec3::new(0.0, 0.0, 3.0), 1.0)],
            vec![
                target(Vec3::new(-1.0, 0.0, 3.0), 0.8),
                target(Vec3::new(1.5, 0.5, 2.0), 0.6),
            ],
            // The second overlaps the first, seen from the origin.
            vec![
                target(Vec3::new(0.0, 0.0, 3.0), 1.2),
                target(Vec3::new(0.4, 0.0, 3.0), 0.9),
                target(Vec3::new(0.0, -2.0, -1.0), 0.5),
            ],
        ];
        let f = |d: Vec3| 1.0 + d.x * d.x + 0.5 * d.y;
        for targets in sets {
            let union = UnionOfCones::towards(&targets, Vec3::ZERO).expect("outside all");
            let inside = |d: Vec3| {
                targets.iter().any(|t| {
                    let (axis, cos) = cone_towards(t, Vec3::ZERO).unwrap();
                    d.dot(axis) >= cos
                })
            };
            let n = 400_000;
            let mut aimed = 0.0f64;
            let mut rng = Rng::for_index(1, Stream::CausticPhotons, 0);
            for _ in 0..n {
                let (d, weight) = union.sample(&mut rng);
                assert!(inside(d), "{d} outside every cone");
                // The density a sample is drawn with is the one `density` reports.
                assert!((union.density(d) * weight - 1.0).abs() < 1e-5);
                aimed += (f(d) * weight) as f64;
            }
            assert_eq!(
                union.density(-union.cone(0).0),
                0.0,
                "a direction no cone holds"
            );
            let mut plain = 0.0f64;
            for _ in 0..n {
                let d = uniform_sphere(rng.next_2d());
                if inside(d) {
                    plain += (f(d) * 4.0 * std::f32::consts::PI) as f64;
                }
            }
            let (aimed, plain) = (aimed / n as f64, plain / n as f64);
            assert!(
                (aimed - plain).abs() < 0.02 * plain,
                "{} targets: aimed {aimed} vs plain {plain}",
                targets.len()
            );
        }
    }

    /// Every vertex of a mesh lies in one of its clusters' spheres, and the clusters are as many
    /// as the budget allows.
    #[test]
    fn mesh_clusters_hold_every_vertex() {
        let mut rng = Rng::for_index(3, Stream::CausticPhotons, 0);
        // A wiggly strip of triangles along a helix, like a knot's tube.
        let positions: Vec<Vec3> = (0..600)
            .map(|i| {
                let t = i as f32 * 0.05;
                Vec3::new(t.cos(), t.sin(), 0.1 * t) + 0.05 * uniform_sphere(rng.next_2d())
            })
            .collect();
        let triangles: Vec<[u32; 3]> = (0..598).map(|i| [i, i + 1, i + 2]).collect();
        let mesh = Shape::Triangles(std::sync::Arc::new(TriangleMesh {
            positions: positions.clone(),
            normals: None,
            uvs: None,
            triangles: triangles.clone(),
            material: 0,
            cutout: None,
        }));
        let ball = Shape::Sphere {
            center: Vec3::new(5.0, 0.0, 0.0),
            radius: 0.5,
            material: 0,
            to_object: glam::Mat3::IDENTITY,
        };
        for (shapes, expected) in [
            (vec![&mesh], MAX_TARGETS),
            (vec![&mesh, &ball], 1 + 4),
            (vec![&ball, &mesh, &mesh], 1 + 2 * 2),
        ] {
            let spheres = targets(&shapes);
            assert_eq!(spheres.len(), expected);
            let mesh_spheres = if matches!(shapes[0], Shape::Sphere { .. }) {
                &spheres[1..]
            } else {
                &spheres[..]
            };
            for t in &triangles {
                // The whole triangle lies in one sphere: its three corners do.
                let held = mesh_spheres.iter().any(|s| {
                    t.iter()
                        .all(|&i| positions[i as usize].distance(s.center) <= s.radius)
                });
                assert!(held, "triangle {t:?} is in no sphere");
            }
        }
        // Clusters are smaller than one sphere around the whole mesh.
        let one = BoundingSphere::around_box(
            positions.iter().fold(Vec3::MAX, |a, &p| a.min(p)),
            positions.iter().fold(Vec3::MIN, |a, &p| a.max(p)),
        );
        assert!(
            targets(&[&mesh])
                .iter()
                .all(|s| s.radius < 0.5 * one.radius)
        );
    }

    /// One cone: the sample is the cone's own, with its solid angle as the weight.
    #[test]
    fn a_union_of_one_cone_is_that_cone() {
        let t = target(Vec3::new(0.3, 1.0, 2.0), 0.4);
        let (axis, cos) = cone_towards(&t, Vec3::ZERO).unwrap();
        let union = UnionOfCones::towards(&[t], Vec3::ZERO).unwrap();
        let prepared = union.prepared();
        let mut a = Rng::for_index(2, Stream::CausticPhotons, 0);
        let (mut b, mut c) = (a.clone(), a.clone());
        for _ in 0..1000 {
            let (d, w) = union.sample(&mut a);
            assert_eq!(d, ConeFrame::new(axis, cos).sample(b.next_2d()));
            assert_eq!(w, cone_solid_angle(cos));
            assert_eq!(prepared.sample(&mut c), (d, w));
        }
    }

    #[test]
    fn inside_a_target_there_is_no_union() {
        let targets = [
            target(Vec3::ZERO, 1.0),
            target(Vec3::new(5.0, 0.0, 0.0), 1.0),
        ];
        assert!(UnionOfCones::towards(&targets, Vec3::new(0.5, 0.0, 0.0)).is_none());
        assert!(UnionOfCones::towards(&[], Vec3::ZERO).is_none());
        assert!(UnionOfCones::towards(&targets, Vec3::new(2.5, 3.0, 0.0)).is_some());
    }

    /// A surface facing away from every target is behind them all; one facing any is not.
    #[test]
    fn behind_means_behind_every_cone() {
        let targets = [
            target(Vec3::new(0.0, 0.0, 3.0), 0.5),
            target(Vec3::new(3.0, 0.0, 0.0), 0.5),
        ];
        let union = UnionOfCones::towards(&targets, Vec3::ZERO).unwrap();
        assert!(union.behind(Vec3::new(-1.0, 0.0, -1.0).normalize()));
        assert!(!union.behind(Vec3::Z));
        assert!(!union.behind(Vec3::X));
        // Edge-on to the target along +x: not wholly behind it.
        assert!(!union.behind(-Vec3::Z));
    }
}
