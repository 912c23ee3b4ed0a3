//! Value checks on the typed scene file, and construction of the public scene types from it.
//! Owns the rules on values (finite numbers, positive radii and powers, albedo in [0, 1],
//! ior >= 1, usable camera and quad geometry, material names that exist) and the numbering of
//! materials. Each failure names the field path of the offending value. Must not read files
//! (meshes are `mesh`'s) or know TOML syntax (that is `format` and `document`).

use super::document::{Document, child_path};
use super::format::{CameraSpec, LightSpec, MaterialSpec, MeshSpec, QuadSpec, Scale, SphereSpec};
use super::transform::Transform;
use super::{Camera, Light, Material, SceneError, Shape, TriangleMesh};
use glam::Vec3;
use std::collections::HashMap;

/// Directions closer than this (sine of the angle between them) count as parallel.
const PARALLEL_SINE: f32 = 1e-4;

/// Materials in the order they are numbered, with the names objects refer to them by.
#[derive(Default)]
pub(crate) struct MaterialTable {
    materials: Vec<Material>,
    by_name: HashMap<String, u32>,
}

impl MaterialTable {
    pub(crate) fn add_named(&mut self, name: &str, material: Material) -> u32 {
        let index = self.add(material);
        self.by_name.insert(name.to_string(), index);
        index
    }

    /// Adds a material no scene field can name (one read from an MTL file).
    pub(crate) fn add(&mut self, material: Material) -> u32 {
        self.materials.push(material);
        (self.materials.len() - 1) as u32
    }

    /// The index of the scene material named by the string field at `path`.
    pub(crate) fn resolve(
        &self,
        doc: &Document,
        path: &str,
        name: &str,
    ) -> Result<u32, SceneError> {
        self.by_name.get(name).copied().ok_or_else(|| {
            let mut known: Vec<&str> = self.by_name.keys().map(String::as_str).collect();
            known.sort_unstable();
            let known = if known.is_empty() {
                "no [materials] are defined".to_string()
            } else {
                format!("defined: {}", known.join(", "))
            };
            doc.error(path, format!("unknown material `{name}` ({known})"))
        })
    }

    pub(crate) fn into_materials(self) -> Vec<Material> {
        self.materials
    }
}

/// How a mesh object is placed and coloured, checked.
pub(crate) struct MeshPlacement {
    pub file: String,
    pub material_override: Option<u32>,
    pub transform: Transform,
}

pub(crate) fn camera(doc: &Document, spec: &CameraSpec) -> Result<Camera, SceneError> {
    let position = finite3(doc, "camera.position", spec.position)?;
    let look_at = finite3(doc, "camera.look_at", spec.look_at)?;
    let up = finite3(doc, "camera.up", spec.up)?;
    let view = look_at - position;
    let extent = position.abs().max(look_at.abs()).max_element().max(1.0);
    if view.length() <= 1e-6 * extent {
        return Err(doc.error(
            "camera.look_at",
            "equals camera.position: no view direction",
        ));
    }
    if up.length_squared() == 0.0 {
        return Err(doc.error("camera.up", "is the zero vector"));
    }
    if view.normalize().cross(up.normalize()).length() < PARALLEL_SINE {
        return Err(doc.error(
            "camera.up",
            "is parallel to the view direction (look_at - position)",
        ));
    }
    let fov = spec.fov_y;
    if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
        return Err(doc.error("camera.fov_y", format!("{fov} is not in (0, 180) degrees")));
    }
    for (axis, &pixels) in spec.resolution.iter().enumerate() {
        if pixels == 0 {
            return Err(doc.error(
                &format!("camera.resolution[{axis}]"),
                "must be at least 1 pixel",
            ));
        }
    }
    Ok(Camera {
        position,
        look_at,
        up,
        fov_y_degrees: fov,
        handedness: match spec.handedness {
            super::format::HandednessSpec::Right => super::Handedness::Right,
            super::format::HandednessSpec::Left => super::Handedness::Left,
        },
        width: spec.resolution[0],
        height: spec.resolution[1],
    })
}

pub(crate) fn light(doc: &Document, path: &str, spec: &LightSpec) -> Result<Light, SceneError> {
    let field = |name: &str| child_path(path, name);
    Ok(match spec {
        LightSpec::Point(point) => Light::Point {
            position: finite3(doc, &field("position"), point.position)?,
            power: power(doc, &field("power"), point.power)?,
        },
        LightSpec::Sphere(sphere) => Light::Sphere {
            center: finite3(doc, &field("center"), sphere.center)?,
            radius: positive(doc, &field("radius"), sphere.radius)?,
            power: power(doc, &field("power"), sphere.power)?,
        },
        LightSpec::Quad(quad) => {
            let (corner, edge_u, edge_v) =
                parallelogram(doc, path, quad.corner, quad.edge_u, quad.edge_v)?;
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                power: power(doc, &field("power"), quad.power)?,
            }
        }
    })
}

pub(crate) fn material(
    doc: &Document,
    path: &str,
    spec: &MaterialSpec,
) -> Result<Material, SceneError> {
    Ok(match spec {
        MaterialSpec::Diffuse(diffuse) => Material::Diffuse {
            albedo: albedo(doc, &child_path(path, "albedo"), diffuse.albedo)?,
        },
        MaterialSpec::Mirror(_) => Material::Mirror,
        MaterialSpec::Glass(glass) => Material::Glass {
            ior: ior(doc, &child_path(path, "ior"), glass.ior)?,
        },
    })
}

pub(crate) fn sphere(
    doc: &Document,
    path: &str,
    spec: &SphereSpec,
    materials: &MaterialTable,
) -> Result<Shape, SceneError> {
    Ok(Shape::Sphere {
        center: finite3(doc, &child_path(path, "center"), spec.center)?,
        radius: positive(doc, &child_path(path, "radius"), spec.radius)?,
        material: materials.resolve(doc, &child_path(path, "material"), &spec.material)?,
    })
}

/// A quad object becomes two triangles wound so their normal is `edge_u × edge_v`.
pub(crate) fn quad(
    doc: &Document,
    path: &str,
    spec: &QuadSpec,
    materials: &MaterialTable,
) -> Result<Shape, SceneError> {
    let (corner, edge_u, edge_v) = parallelogram(doc, path, spec.corner, spec.edge_u, spec.edge_v)?;
    let material = materials.resolve(doc, &child_path(path, "material"), &spec.material)?;
    Ok(Shape::Triangles(TriangleMesh {
        positions: vec![
            corner,
            corner + edge_u,
            corner + edge_u + edge_v,
            corner + edge_v,
        ],
        normals: None,
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        material,
    }))
}

pub(crate) fn mesh_placement(
    doc: &Document,
    path: &str,
    spec: &MeshSpec,
    materials: &MaterialTable,
) -> Result<MeshPlacement, SceneError> {
    if spec.file.trim().is_empty() {
        return Err(doc.error(&child_path(path, "file"), "is empty; give an OBJ file path"));
    }
    let material_override = match &spec.material {
        Some(name) => Some(materials.resolve(doc, &child_path(path, "material"), name)?),
        None => None,
    };
    let translate = finite3(doc, &child_path(path, "translate"), spec.translate)?;
    let rotate = finite3(doc, &child_path(path, "rotate"), spec.rotate)?;
    let scale_path = child_path(path, "scale");
    let scale = match spec.scale {
        Scale::Uniform(factor) => Vec3::splat(positive(doc, &scale_path, factor)?),
        Scale::PerAxis(factors) => {
            for (axis, &factor) in factors.iter().enumerate() {
                positive(doc, &format!("{scale_path}[{axis}]"), factor)?;
            }
            Vec3::from_array(factors)
        }
    };
    Ok(MeshPlacement {
        file: spec.file.clone(),
        material_override,
        transform: Transform::new(translate, rotate, scale),
    })
}

/// Checks `corner`, `edge_u`, `edge_v` of the table at `path`: finite, non-zero, not parallel.
fn parallelogram(
    doc: &Document,
    path: &str,
    corner: [f32; 3],
    edge_u: [f32; 3],
    edge_v: [f32; 3],
) -> Result<(Vec3, Vec3, Vec3), SceneError> {
    let corner = finite3(doc, &child_path(path, "corner"), corner)?;
    let u_path = child_path(path, "edge_u");
    let v_path = child_path(path, "edge_v");
    let edge_u = finite3(doc, &u_path, edge_u)?;
    let edge_v = finite3(doc, &v_path, edge_v)?;
    if edge_u.length_squared() == 0.0 {
        return Err(doc.error(&u_path, "has zero length"));
    }
    if edge_v.length_squared() == 0.0 {
        return Err(doc.error(&v_path, "has zero length"));
    }
    if edge_u.normalize().cross(edge_v.normalize()).length() < PARALLEL_SINE {
        return Err(doc.error(&v_path, "is parallel to edge_u: the quad has no area"));
    }
    Ok((corner, edge_u, edge_v))
}

/// Every component finite; a bad one is reported as `path[i]`.
fn finite3(doc: &Document, path: &str, v: [f32; 3]) -> Result<Vec3, SceneError> {
    for (i, &x) in v.iter().enumerate() {
        if !x.is_finite() {
            return Err(doc.error(
                &format!("{path}[{i}]"),
                format!("{x} is not a finite number"),
            ));
        }
    }
    Ok(Vec3::from_array(v))
}

fn positive(doc: &Document, path: &str, x: f32) -> Result<f32, SceneError> {
    if x.is_finite() && x > 0.0 {
        Ok(x)
    } else {
        Err(doc.error(path, format!("{x} must be a finite number greater than 0")))
    }
}

/// Watts per channel: finite, non-negative, not all zero.
fn power(doc: &Document, path: &str, rgb: [f32; 3]) -> Result<Vec3, SceneError> {
    for (i, &x) in rgb.iter().enumerate() {
        if !(x.is_finite() && x >= 0.0) {
            return Err(doc.error(
                &format!("{path}[{i}]"),
                format!("{x} watts must be finite and >= 0"),
            ));
        }
    }
    let power = Vec3::from_array(rgb);
    if power == Vec3::ZERO {
        return Err(doc.error(path, "is zero in every channel: the light emits nothing"));
    }
    Ok(power)
}

/// The albedo rule, shared with MTL `Kd`.
pub(crate) fn is_albedo_channel(x: f32) -> bool {
    (0.0..=1.0).contains(&x)
}

/// The index of refraction rule, shared with MTL `Ni`.
pub(crate) fn is_ior(x: f32) -> bool {
    x.is_finite() && x >= 1.0
}

fn albedo(doc: &Document, path: &str, rgb: [f32; 3]) -> Result<Vec3, SceneError> {
    for (i, &x) in rgb.iter().enumerate() {
        if !is_albedo_channel(x) {
            return Err(doc.error(&format!("{path}[{i}]"), format!("{x} is not in [0, 1]")));
        }
    }
    Ok(Vec3::from_array(rgb))
}

fn ior(doc: &Document, path: &str, x: f32) -> Result<f32, SceneError> {
    if is_ior(x) {
        Ok(x)
    } else {
        Err(doc.error(
            path,
            format!("{x} must be a finite index of refraction >= 1"),
        ))
    }
}

/// Warnings (not errors) for lights sealed inside a closed opaque object that the camera is
/// outside of: such a light cannot brighten anything the camera sees. A light inside a closed
/// room with the camera, or inside glass, is fine and gives none. Closed means a sphere, or a
/// triangle mesh (one material's part of an OBJ, or a quad... which is never closed) in which
/// every edge is shared by exactly two triangles; inside is decided by ray parity.
pub(crate) fn enclosed_light_warnings(scene: &super::SceneDescription) -> Vec<String> {
    let opaque = |m: u32| !matches!(scene.materials[m as usize], Material::Glass { .. });
    let mut warnings = Vec::new();
    for (s, shape) in scene.shapes.iter().enumerate() {
        let inside: Box<dyn Fn(Vec3) -> bool> = match shape {
            Shape::Sphere {
                center,
                radius,
                material,
            } if opaque(*material) => {
                let (c, r) = (*center, *radius);
                Box::new(move |p: Vec3| p.distance_squared(c) < r * r)
            }
            Shape::Triangles(mesh) if opaque(mesh.material) && is_closed(mesh) => {
                Box::new(move |p: Vec3| inside_closed_mesh(mesh, p))
            }
            _ => continue,
        };
        if inside(scene.camera.position) {
            continue;
        }
        for (l, light) in scene.lights.iter().enumerate() {
            let at = match light {
                Light::Point { position, .. } => *position,
                Light::Sphere { center, .. } => *center,
                Light::Quad {
                    corner,
                    edge_u,
                    edge_v,
                    ..
                } => *corner + 0.5 * (*edge_u + *edge_v),
            };
            if inside(at) {
                let what = match shape {
                    Shape::Sphere { .. } => "an opaque sphere",
                    Shape::Triangles(_) => "a closed opaque mesh",
                };
                warnings.push(format!(
                    "lights[{l}] is inside {what} (shape {s}) and the camera is outside it: \
                     none of its light can reach the picture"
                ));
            }
        }
    }
    warnings
}

/// Every edge shared by exactly two triangles (vertices compared by position, since OBJ
/// faces split by normals repeat positions).
fn is_closed(mesh: &TriangleMesh) -> bool {
    let key = |i: u32| mesh.positions[i as usize].to_array().map(f32::to_bits);
    let mut edges: HashMap<([u32; 3], [u32; 3]), u32> = HashMap::new();
    for &[a, b, c] in &mesh.triangles {
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let (p, q) = (key(p), key(q));
            *edges
                .entry(if p < q { (p, q) } else { (q, p) })
                .or_default() += 1;
        }
    }
    !edges.is_empty() && edges.values().all(|&n| n == 2)
}

/// Ray parity along a fixed, axis-avoiding direction.
fn inside_closed_mesh(mesh: &TriangleMesh, p: Vec3) -> bool {
    let d = Vec3::new(0.5773, 0.5917, 0.5628).normalize();
    let mut crossings = 0;
    for &[a, b, c] in &mesh.triangles {
        let (v0, v1, v2) = (
            mesh.positions[a as usize],
            mesh.positions[b as usize],
            mesh.positions[c as usize],
        );
        // Möller–Trumbore.
        let (e1, e2) = (v1 - v0, v2 - v0);
        let h = d.cross(e2);
        let det = e1.dot(h);
        if det.abs() < 1e-12 * e1.length_squared().max(e2.length_squared()) {
            continue;
        }
        let s = p - v0;
        let u = s.dot(h) / det;
        if !(0.0..=1.0).contains(&u) {
            continue;
        }
        let q = s.cross(e1);
        let v = d.dot(q) / det;
        if v < 0.0 || u + v > 1.0 {
            continue;
        }
        if e2.dot(q) / det > 0.0 {
            crossings += 1;
        }
    }
    crossings % 2 == 1
}
