//! Textured materials at a hit: each geometry's texture coordinates, laid out for resolving a
//! hit's (u, v), and the textured materials by material id. Owns turning a hit into (u, v) —
//! barycentric interpolation of a triangle's corners, pbrt's parametric (φ/2π, 1 − θ/π) on
//! a sphere, pbrt's (along, across) on a curve — a material's values there, and which of a
//! mix's materials a point shows ([`mix_choice`]). Built only for geometries whose material
//! has textures (or is a mix reaching one), so a scene without textures carries nothing here
//! and takes no extra work. Must not trace rays.

use crate::scene::{
    CurveKind, MAX_MIX_DEPTH, Material, SceneDescription, Shape, TexturedMaterial, TriangleMesh,
};
use glam::{Mat3, Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// How one geometry's hits find their (u, v).
enum GeometryUv {
    /// Not textured: never asked.
    Untextured,
    /// A mesh: its triangles' corners' (u, v), read from the mesh (pbrt's default without).
    Triangles(std::sync::Arc<TriangleMesh>),
    /// A sphere's parametric (u, v) about its centre, measured along its own axes.
    Sphere { center: Vec3, to_object: Mat3 },
    /// A flat curve or a ribbon: u is Embree's parameter along the segment (pbrt's u, 0 to 1
    /// on each segment of a pbrt curve), v across it is pbrt's 0 to 1 (Embree's −1 to 1 on a
    /// flat curve mapped here; on a ribbon, whose band is narrowed, `resolve` puts it in
    /// place, except through an instance).
    Band(CurveKind),
    /// A cylinder curve: u as on a band; Embree's hits on a tube carry no v, so the hit's v
    /// is pbrt's, worked out when the hit is resolved ([`Texturing::tube_v`]) from each
    /// segment's control points.
    Tube(Vec<[Vec3; 4]>),
}

/// Everything evaluating textures at a hit reads.
#[derive(Default)]
pub(super) struct Texturing {
    /// By material id; empty when the scene has no textures.
    by_material: Vec<Option<TexturedMaterial>>,
    /// By Embree geometry id, for the shapes (lights come after them and are never
    /// textured).
    uv: Vec<GeometryUv>,
    /// By prototype, then by the geometry id in the prototype's own scene.
    prototype_uv: Vec<Vec<GeometryUv>>,
    /// Whether any textured geometry is a tube, whose hits need [`Texturing::tube_v`].
    pub(super) has_tubes: bool,
}

impl Texturing {
    pub(super) fn new(description: &SceneDescription) -> Self {
        if description.textured_materials.is_empty() {
            return Self::default();
        }
        let mut by_material = vec![None; description.materials.len()];
        for t in &description.textured_materials {
            by_material[t.material as usize] = Some(t.clone());
        }
        // A geometry needs its (u, v) where its material, or one a mix of it shows, has
        // textures.
        let needs_uv: Vec<bool> = (0..description.materials.len())
            .map(|id| reaches_texture(description, &by_material, id as u32, 0))
            .collect();
        let uvs = |shapes: &[Shape]| -> Vec<GeometryUv> {
            (shapes.iter())
                .map(|shape| match shape {
                    Shape::Sphere {
                        center,
                        material,
                        to_object,
                        ..
                    } if needs_uv[*material as usize] => GeometryUv::Sphere {
                        center: *center,
                        to_object: *to_object,
                    },
                    Shape::Triangles(mesh) if needs_uv[mesh.material as usize] => {
                        GeometryUv::Triangles(mesh.clone())
                    }
                    Shape::Curves(curves) if needs_uv[curves.material as usize] => {
                        match curves.kind {
                            CurveKind::Cylinder => GeometryUv::Tube(
                                (curves.points.chunks_exact(4))
                                    .map(|c| [c[0], c[1], c[2], c[3]])
                                    .collect(),
                            ),
                            kind => GeometryUv::Band(kind),
                        }
                    }
                    _ => GeometryUv::Untextured,
                })
                .collect()
        };
        let uv = uvs(&description.shapes);
        let prototype_uv = (description.prototypes.iter())
            .map(|p| uvs(&p.shapes))
            .collect();
        let has_tubes = uv.iter().any(|g| matches!(g, GeometryUv::Tube(_)));
        Self {
            by_material,
            uv,
            prototype_uv,
            has_tubes,
        }
    }

    /// pbrt's v on a textured tube, for a hit at `u` along segment `primitive` of `geometry`
    /// with unit normal `normal` by a ray along `dir` (`None` on anything else). pbrt draws a
    /// cylinder curve on a band facing the ray, v running from 0 to 1 across it; a ray that
    /// far across meets the tube where the normal's part across (along tangent × `dir`) is
    /// 2v − 1.
    pub(super) fn tube_v(
        &self,
        geometry: u32,
        primitive: u32,
        u: f32,
        normal: Vec3,
        dir: Vec3,
    ) -> Option<f32> {
        let Some(GeometryUv::Tube(segments)) = self.uv.get(geometry as usize) else {
            return None;
        };
        let across = super::hit_normals::tube_across(&segments[primitive as usize], u, dir);
        Some((0.5 + 0.5 * normal.dot(across)).clamp(0.0, 1.0))
    }

    /// The textured material of id `material`, if it has textures.
    #[inline(always)]
    pub(super) fn textured(&self, material: u32) -> Option<&TexturedMaterial> {
        self.by_material.get(material as usize)?.as_ref()
    }

    /// The (u, v) at a hit on `geometry`: triangle `primitive` at barycentrics
    /// `barycentric` (the weights of corners 1 and 2), Embree's (u, v) on a curve, or the
    /// point `position`.
    pub(super) fn uv(
        &self,
        geometry: u32,
        primitive: u32,
        barycentric: Vec2,
        position: Vec3,
    ) -> Vec2 {
        geometry_uv(
            self.uv.get(geometry as usize),
            primitive,
            barycentric,
            position,
        )
    }

    /// [`Self::uv`] on geometry `geometry` of prototype `prototype`, `local` in its space (a
    /// tube inside an object keeps Embree's v).
    pub(super) fn prototype_uv(
        &self,
        prototype: u32,
        geometry: u32,
        primitive: u32,
        barycentric: Vec2,
        local: Vec3,
    ) -> Vec2 {
        let uv = self.prototype_uv.get(prototype as usize);
        let geometry = uv.and_then(|g| g.get(geometry as usize));
        geometry_uv(geometry, primitive, barycentric, local)
    }
}

/// Whether material `id` has textures, or is a mix (`depth` mixes below the first) one of whose
/// materials reaches one.
fn reaches_texture(
    description: &SceneDescription,
    by_material: &[Option<TexturedMaterial>],
    id: u32,
    depth: usize,
) -> bool {
    if by_material[id as usize].is_some() {
        return true;
    }
    match description.materials[id as usize] {
        Material::Mix { materials, .. } if depth < MAX_MIX_DEPTH => {
            (materials.iter()).any(|&m| reaches_texture(description, by_material, m, depth + 1))
        }
        _ => false,
    }
}

/// Which of a mix's `materials` the surface shows at `position`: `materials[1]` with
/// probability `amount`, as pbrt-v4's `MixMaterial` chooses (at most 0: the first, at least
/// 1: the second, else the second where a uniform u is at most `amount`), u a hash of the
/// position's bits and the two ids. Every ray that meets the point, photon or camera path,
/// on any thread, in any pass, sees the same material, and neighbouring points choose apart.
#[inline]
pub fn mix_choice(materials: [u32; 2], amount: f32, position: Vec3) -> u32 {
    if amount.is_nan() || amount <= 0.0 {
        return materials[0];
    }
    if amount >= 1.0 {
        return materials[1];
    }
    let bits = position.to_array().map(f32::to_bits);
    let h = (bits.into_iter().chain(materials)).fold(0x6d69_785f_6d61_7465, |h, word| {
        crate::sampling::mix(h, u64::from(word))
    });
    let u = (h >> 40) as f32 / (1u64 << 24) as f32;
    if amount < u {
        materials[0]
    } else {
        materials[1]
    }
}

#[inline]
fn geometry_uv(uv: Option<&GeometryUv>, primitive: u32, barycentric: Vec2, position: Vec3) -> Vec2 {
    match uv {
        Some(GeometryUv::Triangles(mesh)) => {
            let [t0, t1, t2] = mesh.corner_uvs(primitive as usize);
            (1.0 - barycentric.x - barycentric.y) * t0 + barycentric.x * t1 + barycentric.y * t2
        }
        Some(GeometryUv::Sphere { center, to_object }) => {
            sphere_uv(*to_object * (position - *center))
        }
        Some(GeometryUv::Band(kind)) => {
            let v = match kind {
                CurveKind::Flat => 0.5 * (barycentric.y + 1.0),
                _ => barycentric.y,
            };
            Vec2::new(barycentric.x, v.clamp(0.0, 1.0))
        }
        // `resolve` has put pbrt's v in place of Embree's.
        Some(GeometryUv::Tube(_)) => barycentric,
        _ => Vec2::ZERO,
    }
}

/// pbrt's full sphere's (u, v) at the point `local` from its centre: u = φ/2π with φ from +x
/// towards +y, v = 1 − θ/π with θ from +z (v = 0 at the −z pole, 1 at the +z pole).
pub fn sphere_uv(local: Vec3) -> Vec2 {
    let mut phi = local.y.atan2(local.x);
    if phi < 0.0 {
        phi += TAU;
    }
    let cos_theta = (local.z / local.length().max(f32::MIN_POSITIVE)).clamp(-1.0, 1.0);
    Vec2::new(phi / TAU, 1.0 - cos_theta.acos() / PI)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mix_shows_its_second_material_with_probability_amount_and_the_same_one_twice() {
        let pair = [3, 8];
        let at = |i: u32| Vec3::new(i as f32 * 1e-3, 0.5, (i % 97) as f32 * 0.01);
        for amount in [0.1f32, 0.5, 0.85] {
            let n = 200_000;
            let second = (0..n)
                .filter(|&i| mix_choice(pair, amount, at(i)) == 8)
                .count();
            let share = second as f32 / n as f32;
            // The share's standard deviation is at most 0.0012.
            assert!((share - amount).abs() < 0.006, "{amount}: {share}");
        }
        for i in 0..1000 {
            let p = at(i);
            assert_eq!(mix_choice(pair, 0.4, p), mix_choice(pair, 0.4, p));
            // Never past its ends, and a NaN amount is the first material.
            assert_eq!(mix_choice(pair, 0.0, p), 3);
            assert_eq!(mix_choice(pair, -1.0, p), 3);
            assert_eq!(mix_choice(pair, f32::NAN, p), 3);
            assert_eq!(mix_choice(pair, 1.0, p), 8);
        }
        // The pair's ids enter the hash: two mixes over one point choose apart.
        let apart = (0..10_000)
            .filter(|&i| {
                (mix_choice([3, 8], 0.5, at(i)) == 8) != (mix_choice([4, 9], 0.5, at(i)) == 9)
            })
            .count();
        assert!((4000..6000).contains(&apart), "{apart}");
    }
}
