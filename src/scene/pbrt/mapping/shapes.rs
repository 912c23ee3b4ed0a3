//! pbrt's shapes as dpm's: `trianglemesh`, `plymesh` (through [`crate::scene::ply`]) and
//! planar `bilinearmesh` patches become world-space triangle meshes wound so that their
//! geometric normal is pbrt's (the side a glass is entered from, an area light emits to);
//! full `sphere`s become spheres; the quadrics, partial spheres, `loopsubdiv` and
//! `heightfield` are tessellated ([`super::tessellated`]) and placed here like a mesh; a
//! shape's `alpha`/`shadowalpha` becomes its mesh's [`Cutout`] (a cut sphere is tessellated);
//! `curve`s become Bézier curves ([`super::curves`]). NURBS are refused. Owns placing
//! shapes; must not choose materials.

use super::super::parser::{Item, ShapeItem};
use super::tessellated::SphereCut;
use super::textures::TextureType;
use super::{Mapper, param_error, require, value_error};
use crate::scene::tessellate::quadrics::Quadric;
use crate::scene::{Curves, Cutout, SceneError, Shape, Texture, TriangleMesh, ply, rules};
use glam::{Mat3, Vec2, Vec3};
use rayon::prelude::*;

/// A bilinear patch whose fourth corner is further than this (relative to its size) from
/// the plane of the other three is not flat, and two triangles would not be the patch.
const FLAT_PATCH: f32 = 1e-4;

/// A mesh in its object space, as a shape gives it.
pub(super) struct MeshData {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    /// Per vertex, as many as `positions`.
    pub uvs: Option<Vec<Vec2>>,
    pub triangles: Vec<[u32; 3]>,
}

/// A shape's geometry in world space, before it is given a material or made a light.
pub(in super::super) enum Geometry {
    Sphere {
        center: Vec3,
        radius: f32,
        /// From the world's axes to the sphere's own, its transform's rotation undone.
        to_object: Mat3,
    },
    Triangles(TriangleMesh),
    Curves(Curves),
}

impl Mapper<'_> {
    pub(super) fn shape(
        &mut self,
        shape: &ShapeItem,
        material: u32,
    ) -> Result<Vec<Shape>, SceneError> {
        Ok(match self.geometry(shape)? {
            Geometry::Sphere {
                center,
                radius,
                to_object,
            } => vec![Shape::Sphere {
                center,
                radius,
                material,
                to_object,
            }],
            Geometry::Triangles(mut mesh) => {
                mesh.material = material;
                vec![Shape::Triangles(mesh.into())]
            }
            Geometry::Curves(mut curves) => {
                curves.material = material;
                vec![Shape::Curves(curves)]
            }
        })
    }

    pub(in super::super) fn geometry(&mut self, shape: &ShapeItem) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let cutout = self.cutout(item)?;
        let geometry = self.uncut_geometry(shape, cutout.is_some())?;
        Ok(match (geometry, cutout) {
            (Geometry::Triangles(mut mesh), Some(cutout)) => {
                mesh.cutout = Some(cutout);
                Geometry::Triangles(mesh)
            }
            (Geometry::Curves(_), Some(_)) => {
                return Err(item.at.error(
                    "Shape",
                    "\"alpha\" on a curve is not supported: dpm cuts out triangle meshes only",
                ));
            }
            (geometry, _) => geometry,
        })
    }

    /// The shape's `alpha` and `shadowalpha` (float textures or constants), `None` when the
    /// shape is opaque throughout.
    fn cutout(&self, item: &Item) -> Result<Option<Cutout>, SceneError> {
        let read = |name: &str| -> Result<Option<Texture>, SceneError> {
            let texture =
                self.parameter_if_given(&item.params, "Shape", name, TextureType::Float)?;
            match texture.as_ref().and_then(Texture::as_constant) {
                Some(c) if !c.x.is_finite() => Err(value_error(
                    item,
                    "Shape",
                    name,
                    format!("{name} {} is not a number in [0, 1]", c.x),
                )),
                Some(c) if c.x >= 1.0 => Ok(None),
                _ => Ok(texture),
            }
        };
        let (alpha, shadow_alpha) = (read("alpha")?, read("shadowalpha")?);
        if alpha.is_none() && shadow_alpha.is_none() {
            return Ok(None);
        }
        Ok(Some(Cutout {
            alpha: alpha.unwrap_or(Texture::Constant(Vec3::ONE)),
            shadow_alpha,
        }))
    }

    /// The shape's geometry without its cut-out; a sphere that will be cut is tessellated, for
    /// its triangles' texture coordinates.
    fn uncut_geometry(&mut self, shape: &ShapeItem, cut: bool) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let p = |e| param_error("Shape", e);
        match item.kind.as_str() {
            "sphere" if cut => match self.sphere_cut(item)? {
                SphereCut::Partial(quadric) => self.placed_quadric(shape, quadric),
                SphereCut::Full => {
                    let r = f64::from(item.params.float("radius").map_err(p)?.unwrap_or(1.0));
                    let sphere = Quadric::Sphere { radius: r, z_min: -r, z_max: r, phi_max: std::f64::consts::TAU };
                    self.placed_quadric(shape, sphere)
                }
            },
            "sphere" => self.sphere(shape),
            "trianglemesh" => {
                let positions = require(item.params.vec3s("P"), item, "P", "Shape")?;
                let indices = match item.params.integers("indices").map_err(p)? {
                    Some(i) => i,
                    None if positions.len() == 3 => vec![0, 1, 2],
                    None => return Err(item.at.error("Shape", "trianglemesh needs \"integer indices\" (only a single triangle may leave them out)")),
                };
                if indices.len() % 3 != 0 {
                    return Err(value_error(item, "Shape", "indices", format!("has {} indices, not a multiple of 3", indices.len())));
                }
                let normals = item.params.vec3s("N").map_err(p)?;
                let uvs = match item.params.vec2s("uv").map_err(p)? {
                    Some(uv) => Some(("uv", uv)),
                    None => item.params.vec2s("st").map_err(p)?.map(|st| ("st", st)),
                };
                let uvs = match uvs {
                    Some((name, uv)) if uv.len() != positions.len() => {
                        return Err(value_error(item, "Shape", name, format!("has {} texture coordinates for {} points", uv.len(), positions.len())));
                    }
                    other => other.map(|(_, uv)| uv),
                };
                ignore(item, &["S", "faceIndices"]);
                let triangles = corner_triples(item, &indices, positions.len())?;
                self.mesh(shape, MeshData { positions, normals, uvs, triangles })
            }
            "plymesh" => {
                let name = require(item.params.string("filename"), item, "filename", "Shape")?;
                let path = super::super::parser::Parser::resolve(&self.folder, &name);
                if item.params.at("displacement").is_some() {
                    return Err(value_error(item, "Shape", "displacement", "displacement maps are not supported".into()));
                }
                ignore(item, &["edgelength"]);
                let read = ply::read(&path, self.files).map_err(|e| match e.line {
                    None if e.field == "file" => value_error(item, "Shape", "filename", format!("`{}`: {}", path.display(), e.message)),
                    _ => SceneError {
                        file: path.clone(),
                        line: e.line,
                        column: None,
                        field: e.field,
                        message: format!("{} (the mesh of the Shape at {})", e.message, item.at),
                    },
                })?;
                self.mesh(shape, MeshData { positions: read.positions, normals: read.normals, uvs: read.uvs, triangles: read.triangles })
            }
            "bilinearmesh" => {
                let positions = require(item.params.vec3s("P"), item, "P", "Shape")?;
                let indices = match item.params.integers("indices").map_err(p)? {
                    Some(i) => i,
                    None if positions.len() == 4 => vec![0, 1, 2, 3],
                    None => return Err(item.at.error("Shape", "bilinearmesh needs \"integer indices\" (only a single patch may leave them out)")),
                };
                if indices.len() % 4 != 0 {
                    return Err(value_error(item, "Shape", "indices", format!("has {} indices, not a multiple of 4", indices.len())));
                }
                let normals = item.params.vec3s("N").map_err(p)?;
                ignore(item, &["uv", "faceIndices"]);
                let corners = corner_indices(item, &indices, positions.len())?;
                let mut triangles = Vec::with_capacity(corners.len() / 2);
                for patch in corners.chunks_exact(4) {
                    let [a, b, c, d] = [patch[0], patch[1], patch[2], patch[3]];
                    let q = |i: u32| positions[i as usize];
                    let n = (q(b) - q(a)).cross(q(c) - q(a));
                    let size = (q(b) - q(a)).length().max((q(c) - q(a)).length()).max(1e-30);
                    if n.length() > 0.0 && (q(d) - q(a)).dot(n.normalize()).abs() > FLAT_PATCH * size {
                        return Err(item.at.error("Shape", "bilinearmesh: a patch is not flat, and dpm renders patches as two triangles"));
                    }
                    // pbrt's corners are p00, p10, p01, p11.
                    triangles.push([a, b, d]);
                    triangles.push([a, d, c]);
                }
                self.mesh(shape, MeshData { positions, normals, uvs: None, triangles })
            }
            "disk" | "cylinder" | "cone" | "paraboloid" | "hyperboloid" => self.quadric(shape),
            "loopsubdiv" => self.loop_subdivision(shape),
            "heightfield" => self.heightfield(shape),
            "curve" => self.curve(shape),
            "nurbs" => Err(item.at.error(
                "Shape",
                "shape \"nurbs\" is not supported: dpm renders triangle meshes, spheres, the quadrics and curves (convert it to a trianglemesh or plymesh)",
            )),
            other => Err(item.at.error("Shape", format!("\"{other}\" is not a pbrt shape"))),
        }
    }

    fn sphere(&mut self, shape: &ShapeItem) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let p = |e| param_error("Shape", e);
        if let SphereCut::Partial(quadric) = self.sphere_cut(item)? {
            return self.placed_quadric(shape, quadric);
        }
        // sphere_cut has checked it.
        let radius = item.params.float("radius").map_err(p)?.unwrap_or(1.0);
        let m = Mat3::from_mat4(shape.ctm);
        let scales = [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()];
        let mean = scales.iter().sum::<f32>() / 3.0;
        let orthogonal = m.x_axis.dot(m.y_axis).abs()
            + m.y_axis.dot(m.z_axis).abs()
            + m.x_axis.dot(m.z_axis).abs();
        if scales.iter().any(|s| (s - mean).abs() > 1e-5 * mean) || orthogonal > 1e-5 * mean * mean
        {
            return Err(item.at.error("Shape", "the sphere's transform is not a uniform scale with a rotation, so it is not a sphere in the world"));
        }
        let center = shape.ctm.transform_point3(Vec3::ZERO);
        let radius = radius * mean;
        if !(center.is_finite() && radius.is_finite() && radius > 0.0) {
            return Err(item
                .at
                .error("Shape", "the transformed sphere is not finite"));
        }
        // The transform is `mean` times an orthonormal matrix, whose transpose undoes it.
        let to_object = (m * (1.0 / mean)).transpose();
        Ok(Geometry::Sphere {
            center,
            radius,
            to_object,
        })
    }

    /// Places a mesh in the world, wound as pbrt orients it, without zero-area triangles.
    pub(super) fn mesh(
        &mut self,
        shape: &ShapeItem,
        mesh: MeshData,
    ) -> Result<Geometry, SceneError> {
        let MeshData {
            positions,
            normals,
            uvs,
            triangles,
        } = mesh;
        let item = &shape.item;
        if let Some(n) = &normals
            && n.len() != positions.len()
        {
            return Err(value_error(
                item,
                "Shape",
                "N",
                format!("has {} normals for {} points", n.len(), positions.len()),
            ));
        }
        // Each stage works in place and in parallel: a big mesh is never held twice.
        let ctm = shape.ctm;
        let mut world = positions;
        world
            .par_iter_mut()
            .for_each(|p| *p = ctm.transform_point3(*p));
        if !world.par_iter().all(|p| p.is_finite()) {
            return Err(item.at.error("Shape", "a transformed vertex is not finite"));
        }
        let normal_matrix = Mat3::from_mat4(ctm).inverse().transpose().as_dmat3();
        let world_normals = match normals {
            None => None,
            Some(mut n) => {
                // f64: a length squared past f32's range still has a direction.
                (n.par_iter_mut()).for_each(|n| {
                    *n = (normal_matrix * n.as_dvec3()).normalize_or_zero().as_vec3()
                });
                let bad = |w: &Vec3| *w == Vec3::ZERO || !w.is_finite();
                if let Some(i) = n.par_iter().position_first(bad) {
                    return Err(value_error(
                        item,
                        "Shape",
                        "N",
                        format!("normal {i} is zero or not finite"),
                    ));
                }
                Some(n)
            }
        };
        let swaps_handedness = Mat3::from_mat4(ctm).determinant() < 0.0;
        let flip_all = shape.reverse_orientation ^ swaps_handedness;
        let mut kept = triangles;
        let area: Vec<bool> = (kept.par_iter_mut())
            .map(|t| {
                let [a, b, c] = *t;
                if rules::has_zero_area(&world, [a, b, c]) {
                    return false;
                }
                let face = (world[b as usize] - world[a as usize])
                    .cross(world[c as usize] - world[a as usize]);
                // pbrt turns the geometric normal towards the shading normal when there is one.
                let flip = match &world_normals {
                    Some(n) => face.dot(n[a as usize] + n[b as usize] + n[c as usize]) < 0.0,
                    None => flip_all,
                };
                if flip {
                    *t = [a, c, b];
                }
                true
            })
            .collect();
        let mut has_area = area.iter();
        kept.retain(|_| *has_area.next().unwrap());
        self.report.degenerate_triangles_dropped += area.len() - kept.len();
        if kept.is_empty() {
            return Err(item
                .at
                .error("Shape", "the mesh has no triangle with an area"));
        }
        Ok(Geometry::Triangles(TriangleMesh {
            positions: world,
            normals: world_normals,
            uvs,
            triangles: kept,
            material: 0,
            cutout: None,
        }))
    }
}

/// Marks parameters dpm reads past on purpose (texture coordinates, tangents).
fn ignore(item: &Item, names: &[&str]) {
    for name in names {
        item.params.mark_used(name);
    }
}

fn corner_indices(
    item: &Item,
    indices: &[i64],
    vertex_count: usize,
) -> Result<Vec<u32>, SceneError> {
    indices
        .iter()
        .enumerate()
        .map(|(k, &i)| {
            if i >= 0 && (i as usize) < vertex_count {
                Ok(i as u32)
            } else {
                Err(value_error(
                    item,
                    "Shape",
                    "indices",
                    format!("index {k} is {i}, not one of the {vertex_count} points"),
                ))
            }
        })
        .collect()
}

pub(super) fn corner_triples(
    item: &Item,
    indices: &[i64],
    vertex_count: usize,
) -> Result<Vec<[u32; 3]>, SceneError> {
    let corners = corner_indices(item, indices, vertex_count)?;
    Ok(corners
        .chunks_exact(3)
        .map(|c| [c[0], c[1], c[2]])
        .collect())
}
