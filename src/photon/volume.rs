//! The volume photon map: photons left where a path scattered in a medium, each with the
//! radius of its k nearest neighbours (the beam radiance estimate gives every photon its own
//! disc), held in a bounding-volume hierarchy of their spheres so that a camera ray finds
//! every photon whose sphere it passes through. A map may also hold a kernel ellipsoid per
//! photon inside its sphere (the estimate shapes them). Points here; a beam or plane kind would
//! sit beside them. Owns storage and the ray query; must not weigh photons (the estimate does).

use super::kdtree::{KdTree, Neighbours};
use glam::Vec3;
use rayon::prelude::*;

/// A photon at a scattering event in a medium.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VolumePhoton {
    pub position: Vec3,
    /// Power, already divided by the paths emitted.
    pub power: Vec3,
    /// Unit direction the photon travelled in when it scattered.
    pub direction: Vec3,
}

/// The kernel of a photon shaped to its neighbourhood: the ellipsoid `dᵀ M d < 1` around
/// the photon (`d` its offset), always inside the photon's sphere.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KernelEllipsoid {
    /// `M` as `[xx, yy, zz, xy, xz, yz]`, in inverse squared world units.
    pub metric: [f32; 6],
    /// `√det M`: a kernel over the unit ball, mapped onto the ellipsoid, is multiplied by it
    /// to keep its integral.
    pub root_det: f32,
}

/// The volume photon maps a pass reads along camera segments in media.
#[derive(Clone, Copy, Default)]
pub struct VolumeMaps<'a> {
    /// Photons whose first scattering event came after mirrors and glass alone.
    pub caustic: Option<&'a VolumeMap>,
    /// Photons that scattered or bounced off a diffuse surface before.
    pub global: Option<&'a VolumeMap>,
}

/// Photons a leaf holds at most.
const LEAF: usize = 8;

#[derive(Clone, Copy, Debug)]
struct Node {
    lo: Vec3,
    hi: Vec3,
    /// A leaf: its photons `first..first + count`; an inner node (count 0): its second child
    /// at `first`, the first right after it.
    first: u32,
    count: u32,
}

/// A volume photon map.
#[derive(Clone, Debug, Default)]
pub struct VolumeMap {
    photons: Vec<VolumePhoton>,
    /// Each photon's radius, in the photons' order.
    radii: Vec<f32>,
    /// Each photon's kernel ellipsoid, in the photons' order; empty: round kernels.
    shapes: Vec<KernelEllipsoid>,
    nodes: Vec<Node>,
}

/// A photon whose sphere a ray passes through.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotonOnRay<'a> {
    pub photon: &'a VolumePhoton,
    pub radius: f32,
    /// Where along the ray the photon is closest to it.
    pub t: f32,
    /// Squared distance from the photon to the ray.
    pub distance2: f32,
    /// The photon's kernel ellipsoid, if the map's kernels are shaped.
    pub shape: Option<&'a KernelEllipsoid>,
}

impl VolumeMap {
    /// The map of `photons`, each photon's radius the distance to its `k`-th nearest
    /// neighbour (itself counted), at most `max_radius`, times `scale`.
    pub fn build(photons: Vec<VolumePhoton>, k: usize, max_radius: f32, scale: f32) -> Self {
        let positions: Vec<Vec3> = photons.iter().map(|p| p.position).collect();
        let tree = KdTree::build(&positions);
        let radii = (positions.par_iter())
            .map_init(
                || Neighbours::with_capacity(k.max(1)),
                |found, &p| {
                    tree.k_nearest(p, k.max(1), max_radius * max_radius, found);
                    let r2 = match found.len() < k.max(1) {
                        true => max_radius * max_radius,
                        false => found.farthest().map_or(0.0, |n| n.dist2),
                    };
                    r2.sqrt().clamp(1e-30, max_radius) * scale
                },
            )
            .collect();
        Self::with_radii(photons, radii)
    }

    /// The map of `photons` with the given radii.
    pub fn with_radii(photons: Vec<VolumePhoton>, radii: Vec<f32>) -> Self {
        assert_eq!(photons.len(), radii.len());
        let mut order: Vec<u32> = (0..photons.len() as u32).collect();
        let mut nodes = Vec::new();
        if !photons.is_empty() {
            build_node(&photons, &radii, &mut order, 0, &mut nodes);
        }
        Self {
            photons: order.iter().map(|&i| photons[i as usize]).collect(),
            radii: order.iter().map(|&i| radii[i as usize]).collect(),
            shapes: Vec::new(),
            nodes,
        }
    }

    /// The photons, in the map's order.
    pub fn photons(&self) -> &[VolumePhoton] {
        &self.photons
    }

    /// Each photon's radius, in the map's order.
    pub fn radii(&self) -> &[f32] {
        &self.radii
    }

    /// Gives every photon (in the map's order) its kernel ellipsoid, each inside its sphere.
    pub fn set_shapes(&mut self, shapes: Vec<KernelEllipsoid>) {
        assert_eq!(shapes.len(), self.photons.len());
        self.shapes = shapes;
    }

    pub fn len(&self) -> usize {
        self.photons.len()
    }

    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }

    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.photons.capacity() * std::mem::size_of::<VolumePhoton>()
            + self.radii.capacity() * 4
            + self.shapes.capacity() * std::mem::size_of::<KernelEllipsoid>()
            + self.nodes.capacity() * std::mem::size_of::<Node>()
    }

    /// Every photon whose sphere the ray `origin + t·dir` (unit `dir`) passes through, its
    /// closest point within t in [`t0`, `t1`).
    pub fn along(
        &self,
        origin: Vec3,
        dir: Vec3,
        t0: f32,
        t1: f32,
        mut found: impl FnMut(PhotonOnRay),
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inverse = dir.recip();
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let index = stack[top];
            let node = self.nodes[index as usize];
            if !slab_hit(node.lo, node.hi, origin, inverse, t0, t1) {
                continue;
            }
            if node.count == 0 {
                // Depth first: the first child follows its parent.
                stack[top] = node.first;
                stack[top + 1] = index + 1;
                top += 2;
                continue;
            }
            let range = node.first as usize..(node.first + node.count) as usize;
            for i in range {
                let (photon, radius) = (&self.photons[i], self.radii[i]);
                let to = photon.position - origin;
                let t = to.dot(dir);
                if t < t0 || t >= t1 {
                    continue;
                }
                let distance2 = (to - t * dir).length_squared();
                if distance2 < radius * radius {
                    found(PhotonOnRay {
                        photon,
                        radius,
                        t,
                        distance2,
                        shape: self.shapes.get(i),
                    });
                }
            }
        }
    }
}

/// Whether the box `lo`..`hi` meets the ray within [`t0`, `t1`].
#[inline]
fn slab_hit(lo: Vec3, hi: Vec3, origin: Vec3, inverse: Vec3, t0: f32, t1: f32) -> bool {
    let a = (lo - origin) * inverse;
    let b = (hi - origin) * inverse;
    let near = a.min(b).max_element().max(t0);
    let far = a.max(b).min_element().min(t1);
    near <= far
}

/// Builds the subtree over `order` (indices into `photons`) at `offset` into the final
/// order, pushing its nodes depth first; returns the subtree root's index.
fn build_node(
    photons: &[VolumePhoton],
    radii: &[f32],
    order: &mut [u32],
    offset: u32,
    nodes: &mut Vec<Node>,
) -> u32 {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let (mut c_lo, mut c_hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for &i in order.iter() {
        let (p, r) = (photons[i as usize].position, radii[i as usize]);
        (lo, hi) = (lo.min(p - r), hi.max(p + r));
        (c_lo, c_hi) = (c_lo.min(p), c_hi.max(p));
    }
    let index = nodes.len() as u32;
    nodes.push(Node {
        lo,
        hi,
        first: offset,
        count: order.len() as u32,
    });
    if order.len() <= LEAF {
        return index;
    }
    let extent = c_hi - c_lo;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let half = order.len() / 2;
    order.select_nth_unstable_by(half, |a, b| {
        let (pa, pb) = (photons[*a as usize].position, photons[*b as usize].position);
        pa[axis].total_cmp(&pb[axis])
    });
    let (left, right) = order.split_at_mut(half);
    build_node(photons, radii, left, offset, nodes);
    let second = build_node(photons, radii, right, offset + half as u32, nodes);
    nodes[index as usize].count = 0;
    nodes[index as usize].first = second;
    index
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Stream, StreamSeed};

    #[test]
    fn a_ray_finds_every_photon_whose_sphere_it_passes_through_as_brute_force_does() {
        let mut rng = StreamSeed::new(9, Stream::GlobalPhotons).rng(0);
        let mut point = |scale: f32| {
            Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * scale - scale / 2.0
        };
        let photons: Vec<VolumePhoton> = (0..3000)
            .map(|i| VolumePhoton {
                position: point(2.0),
                // Its index, to name it by.
                power: Vec3::splat(i as f32),
                direction: Vec3::X,
            })
            .collect();
        let radii: Vec<f32> = (0..photons.len())
            .map(|i| 0.01 + 0.002 * (i % 50) as f32)
            .collect();
        let map = VolumeMap::with_radii(photons, radii);
        for case in 0..200 {
            let origin = point(4.0);
            let dir = (point(2.0) - origin).normalize();
            let (t0, t1) = (0.3, 0.3 + 3.0 * (case % 4 + 1) as f32 / 4.0);
            let mut found: Vec<(u32, f32)> = Vec::new();
            map.along(origin, dir, t0, t1, |on| {
                found.push((on.photon.power.x as u32, on.distance2));
            });
            let mut want: Vec<(u32, f32)> = Vec::new();
            for (p, r) in map.photons.iter().zip(&map.radii) {
                let to = p.position - origin;
                let t = to.dot(dir);
                let d2 = (to - t * dir).length_squared();
                if (t0..t1).contains(&t) && d2 < r * r {
                    want.push((p.power.x as u32, d2));
                }
            }
            found.sort_by_key(|f| f.0);
            want.sort_by_key(|f| f.0);
            assert_eq!(found, want, "ray {case}");
        }
    }
}
