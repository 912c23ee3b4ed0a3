//! Object instancing in the world: each prototype built once into an Embree scene of its own,
//! each instance one Embree instance geometry that places it, so memory is the prototypes' plus
//! a transform an instance. Owns the link from a hit through an instance (its instance id and
//! the prototype's geometry id) to the surface and the world-space normals; must not trace.
//!
//! Normals of a hit through an instance are the prototype's, at the hit's point in the
//! prototype's space, carried to the world by the inverse transpose of the instance's linear
//! part (as pbrt carries an instance's normals; a mirroring instance keeps its prototype's
//! outside, where flattened triangles would turn with their winding).

use super::hit_normals::{HitNormals, normals_at, tube_offset};
use super::{BoundingSphere, Surface, add_shape, aim};
use crate::embree::{self, EmbreeError, SceneBuilder};
use crate::scene::SceneDescription;
use glam::{Mat3, Mat4, Vec3};
use std::sync::Arc;

/// A prototype's geometries, as a hit through any of its instances reads them.
struct PrototypeParts {
    surfaces: Vec<Surface>,
    normals: Vec<HitNormals>,
}

/// One instance's transforms.
struct Placed {
    prototype: u32,
    to_object: Mat4,
    normal_to_world: Mat3,
    /// The most a ray leaving a hit through it starts off the surface: [`OBJECT_EPSILON`] of
    /// its box's diagonal.
    epsilon: f32,
}

/// Largest ray offset off an instance, in its box's diagonals: the scene-wide offset of a
/// big scene can jump clean through a small instance's thin parts (25,250 statues 0.2 units
/// tall on a 300-unit floor let 5% more sky through than pbrt). Never below
/// [`super::ROUNDING_MARGIN`] of the hit's distance from the origin.
pub const OBJECT_EPSILON: f32 = 1e-3;

/// Every prototype and instance of a world; empty for a scene without instances.
#[derive(Default)]
pub(super) struct Instancing {
    prototypes: Vec<PrototypeParts>,
    placed: Vec<Placed>,
    /// The top-level geometry id of the first instance; the others follow it in order.
    first: u32,
}

/// What the world's bounds and aim need of the instances, in world space.
#[derive(Default)]
pub(super) struct InstanceExtent {
    /// Around each instance's shapes.
    pub boxes: Vec<(Vec3, Vec3)>,
    /// Around each instance's mirror and glass shapes, for those that have any.
    pub specular_boxes: Vec<(Vec3, Vec3)>,
    /// Mirror and glass shapes placed, counting each placement.
    pub specular_shapes: usize,
    /// Where to aim caustic photons at them: each prototype's targets, placed.
    pub targets: Vec<BoundingSphere>,
}

impl Instancing {
    /// Builds `description`'s prototypes on `device` and adds its instances to `top`; a
    /// material makes caustics as [`crate::scene::Material::makes_caustics`] says at `glossy_min_alpha`.
    pub(super) fn build(
        device: &embree::Device,
        description: &SceneDescription,
        glossy_min_alpha: f32,
        top: &mut SceneBuilder,
    ) -> Result<(Self, InstanceExtent), EmbreeError> {
        let mut instancing = Self::default();
        let mut extent = InstanceExtent::default();
        if description.instances.is_empty() {
            return Ok((instancing, extent));
        }
        // Per prototype: its Embree scene, its box and its specular parts' box.
        let mut built = Vec::with_capacity(description.prototypes.len());
        for prototype in &description.prototypes {
            let mut builder = device.scene_builder()?;
            let mut parts = PrototypeParts {
                surfaces: Vec::new(),
                normals: Vec::new(),
            };
            let (mut lo, mut hi) = (Vec3::MAX, Vec3::MIN);
            let (mut spec_lo, mut spec_hi) = (Vec3::MAX, Vec3::MIN);
            let mut specular = Vec::new();
            for shape in &prototype.shapes {
                let (normals, (a, b), material) = add_shape(&mut builder, shape)?;
                parts.surfaces.push(Surface::Material(material));
                parts.normals.push(normals);
                (lo, hi) = (lo.min(a), hi.max(b));
                let table = &description.materials;
                if table[material as usize].makes_caustics(table, glossy_min_alpha) {
                    (spec_lo, spec_hi) = (spec_lo.min(a), spec_hi.max(b));
                    specular.push(shape);
                }
            }
            // The same targets the prototype's shapes would get standing alone.
            let targets = match specular.len() {
                0 => Vec::new(),
                n if n > aim::MAX_TARGETS => vec![BoundingSphere::around_box(spec_lo, spec_hi)],
                _ => aim::targets(&specular),
            };
            let scene = if prototype.shapes.is_empty() {
                None
            } else {
                Some(Arc::new(builder.commit()?))
            };
            built.push((scene, (lo, hi), (spec_lo, spec_hi), targets, specular.len()));
            instancing.prototypes.push(parts);
        }
        for instance in &description.instances {
            let (scene, bounds, specular, targets, specular_shapes) =
                &built[instance.prototype as usize];
            let Some(scene) = scene else { continue };
            let m = instance.object_to_world;
            let id = top.add_instance(scene, m)?;
            if instancing.placed.is_empty() {
                instancing.first = id;
            }
            debug_assert_eq!(id, instancing.first + instancing.placed.len() as u32);
            let placed = placed_box(m, *bounds);
            instancing.placed.push(Placed {
                prototype: instance.prototype,
                to_object: m.inverse(),
                normal_to_world: Mat3::from_mat4(m).inverse().transpose(),
                epsilon: OBJECT_EPSILON * (placed.1 - placed.0).length(),
            });
            extent.boxes.push(placed);
            if specular.0.x <= specular.1.x {
                extent.specular_boxes.push(placed_box(m, *specular));
            }
            extent.specular_shapes += specular_shapes;
            if extent.targets.len() <= aim::MAX_TARGETS {
                let stretch = (0..3)
                    .map(|c| m.col(c).truncate().length())
                    .fold(0.0, f32::max);
                extent
                    .targets
                    .extend(targets.iter().map(|t| BoundingSphere {
                        center: m.transform_point3(t.center),
                        radius: t.radius * stretch,
                    }));
            }
        }
        Ok((instancing, extent))
    }

    fn placed(&self, instance: u32) -> &Placed {
        &self.placed[(instance - self.first) as usize]
    }

    /// What a hit on the prototype's geometry `geometry` through `instance` shows.
    #[inline]
    pub(super) fn surface(&self, instance: u32, geometry: u32) -> Surface {
        let placed = self.placed(instance);
        self.prototypes[placed.prototype as usize].surfaces[geometry as usize]
    }

    /// The largest offset a ray leaving a hit through `instance` may start at.
    #[inline]
    pub(super) fn epsilon(&self, instance: u32) -> f32 {
        self.placed(instance).epsilon
    }

    /// The prototype `instance` places, and the world point `position` in its space.
    #[inline]
    pub(super) fn in_prototype(&self, instance: u32, position: Vec3) -> (u32, Vec3) {
        let placed = self.placed(instance);
        (
            placed.prototype,
            placed.to_object.transform_point3(position),
        )
    }

    /// World-space geometric and shading normals of `hit` (through `instance`) at the world
    /// point `position` of a ray along `dir`.
    #[inline]
    pub(super) fn normals(
        &self,
        instance: u32,
        hit: &embree::Hit,
        position: Vec3,
        dir: Vec3,
    ) -> (Vec3, Vec3) {
        let placed = self.placed(instance);
        let parts = &self.prototypes[placed.prototype as usize];
        let local = placed.to_object.transform_point3(position);
        let local_dir = placed.to_object.transform_vector3(dir);
        let (ng, ns) = normals_at(&parts.normals[hit.geometry as usize], hit, local, local_dir);
        let ng = (placed.normal_to_world * ng).normalize_or(Vec3::Z);
        let ns = (placed.normal_to_world * ns).normalize_or(ng);
        (ng, if ns.dot(ng) < 0.0 { -ns } else { ns })
    }

    /// How far a ray leaving a hit on a placed tube starts off it, in world units
    /// ([`super::hit_normals::tube_offset`] in the object, scaled by the placement's largest
    /// stretch); `None` off tubes.
    pub(super) fn tube_offset(
        &self,
        instance: u32,
        geometry: u32,
        primitive: u32,
        u: f32,
        n: Vec3,
    ) -> Option<f32> {
        let placed = self.placed(instance);
        let parts = &self.prototypes[placed.prototype as usize];
        let m = Mat3::from_mat4(placed.to_object);
        // Normals go back to the object by the transpose of the placement's linear part.
        let local_n = (m.inverse().transpose() * n).normalize_or(n);
        let offset = tube_offset(&parts.normals[geometry as usize], primitive, u, local_n)?;
        let shrink = [m.x_axis, m.y_axis, m.z_axis].map(Vec3::length);
        Some(
            offset
                / shrink
                    .into_iter()
                    .fold(f32::INFINITY, f32::min)
                    .max(f32::MIN_POSITIVE),
        )
    }

    /// The surfaces of every prototype that is placed at least once.
    pub(super) fn placed_surfaces(&self) -> impl Iterator<Item = Surface> + '_ {
        let mut used = vec![false; self.prototypes.len()];
        for placed in &self.placed {
            used[placed.prototype as usize] = true;
        }
        (self.prototypes.iter().zip(used))
            .filter(|(_, used)| *used)
            .flat_map(|(parts, _)| parts.surfaces.iter().copied())
    }
}

/// The world box around the object box `lo`..`hi` placed by `m`.
fn placed_box(m: Mat4, (lo, hi): (Vec3, Vec3)) -> (Vec3, Vec3) {
    let mut out = (Vec3::MAX, Vec3::MIN);
    for corner in 0..8 {
        let p = Vec3::new(
            if corner & 1 == 0 { lo.x } else { hi.x },
            if corner & 2 == 0 { lo.y } else { hi.y },
            if corner & 4 == 0 { lo.z } else { hi.z },
        );
        let q = m.transform_point3(p);
        out = (out.0.min(q), out.1.max(q));
    }
    out
}
