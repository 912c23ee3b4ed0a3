//! Value checks on the typed scene file, and construction of the public scene types from it.
//! Owns the scene file's own rules (defaults, names of spot falloffs, directions of any
//! length, material names that exist, usable camera geometry) and the numbering of materials;
//! the rules the public types obey are `rules`', applied here to what the file gives. Each
//! failure names the field path of the offending value. Must not read files (meshes are
//! `mesh`'s) or know TOML syntax (that is `format` and `document`).

use super::document::{Document, child_path};
use super::format::{
    CameraSpec, ColourSpec, DEFAULT_CONE_DELTA, LightSpec, MaterialSpec, MeshLightSpec, MeshSpec,
    ProjectionSpec, QuadSpec, Scale, SphereSpec,
};
use super::rules::{self, InvalidField, PARALLEL_SINE, check_light, check_material};
use super::toml_texture::{self, ImageSource};
use super::transform::Transform;
use super::{
    Camera, CropWindow, Light, Material, Projection, SceneError, Shape, SpotFalloff, Texture,
    TexturedParameter, ThinLens, TriangleMesh,
};
use glam::{Vec2, Vec3};
use rayon::slice::ParallelSliceMut;
use std::collections::HashMap;
use std::sync::Arc;

/// The names of [`SpotFalloff`]s in the scene file.
const FALLOFFS: [(&str, SpotFalloff); 2] = [
    ("smoothstep", SpotFalloff::Smoothstep),
    ("quartic", SpotFalloff::Quartic),
];

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

    pub(crate) fn materials(&self) -> &[Material] {
        &self.materials
    }

    pub(crate) fn into_materials(self) -> Vec<Material> {
        self.materials
    }
}

/// How a mesh object or mesh light is placed and coloured, checked.
pub(crate) struct MeshPlacement {
    pub file: String,
    pub material_override: Option<u32>,
    pub transform: Transform,
    /// Whether vertex normals are read (an emitter uses its geometric normals only).
    pub keep_normals: bool,
}

/// A rule broken by the value at `base`'s `e.field`, located in the scene file. `rename`
/// turns the public types' field names into the file's where they differ.
fn located(doc: &Document, base: &str, e: InvalidField, rename: &[(&str, &str)]) -> SceneError {
    let mut field = e.field;
    for (public, file) in rename {
        if let Some(rest) = field.strip_prefix(public) {
            field = format!("{file}{rest}");
        }
    }
    let path = if base.is_empty() {
        field
    } else {
        format!("{base}.{field}")
    };
    doc.error(&path, e.message)
}

/// The checks of `rules` on the table at `base`, with its errors located.
fn at<'d, 't>(doc: &'d Document<'t>, base: &'d str) -> impl Fn(InvalidField) -> SceneError + 'd {
    move |e| located(doc, base, e, &[])
}

pub(crate) fn camera(doc: &Document, spec: &CameraSpec) -> Result<Camera, SceneError> {
    let at = at(doc, "camera");
    let position = rules::finite3("position", Vec3::from_array(spec.position)).map_err(&at)?;
    let look_at = rules::finite3("look_at", Vec3::from_array(spec.look_at)).map_err(&at)?;
    let up = rules::finite3("up", Vec3::from_array(spec.up)).map_err(&at)?;
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
    for (axis, &pixels) in spec.resolution.iter().enumerate() {
        if pixels == 0 {
            return Err(doc.error(
                &format!("camera.resolution[{axis}]"),
                "must be at least 1 pixel",
            ));
        }
    }
    let camera = Camera {
        position,
        look_at,
        up,
        projection: projection(doc, spec)?,
        lens: thin_lens(doc, spec)?,
        handedness: match spec.handedness {
            super::format::HandednessSpec::Right => super::Handedness::Right,
            super::format::HandednessSpec::Left => super::Handedness::Left,
        },
        width: spec.resolution[0],
        height: spec.resolution[1],
        crop: match spec.crop_window {
            Some(window) => rules::crop_window("crop_window", window).map_err(&at)?,
            None => CropWindow::FULL,
        },
    };
    rules::crop_holds_pixels("crop_window", &camera.crop, camera.width, camera.height)
        .map_err(&at)?;
    Ok(camera)
}

/// The camera's projection: `fov_y` belongs to a perspective camera, `view_height` to an
/// orthographic one, and each needs its own.
fn projection(doc: &Document, spec: &CameraSpec) -> Result<Projection, SceneError> {
    let kind = spec.projection.name();
    let given = [("fov_y", spec.fov_y), ("view_height", spec.view_height)];
    let own = match spec.projection {
        ProjectionSpec::Perspective => Some("fov_y"),
        ProjectionSpec::Orthographic => Some("view_height"),
        ProjectionSpec::Environment => None,
    };
    if let Some((field, _)) = given
        .iter()
        .find(|(field, value)| value.is_some() && Some(*field) != own)
    {
        return Err(doc.error(
            &format!("camera.{field}"),
            format!("a {kind} camera has no {field}"),
        ));
    }
    let needed = |field: &str, value: Option<f32>| {
        value.ok_or_else(|| doc.error("camera", format!("a {kind} camera needs {field}")))
    };
    Ok(match spec.projection {
        ProjectionSpec::Perspective => {
            let fov = needed("fov_y", spec.fov_y)?;
            if !(fov.is_finite() && fov > 0.0 && fov < 180.0) {
                return Err(doc.error("camera.fov_y", format!("{fov} is not in (0, 180) degrees")));
            }
            Projection::Perspective { fov_y_degrees: fov }
        }
        ProjectionSpec::Orthographic => {
            let height = needed("view_height", spec.view_height)?;
            Projection::Orthographic {
                view_height: rules::positive("view_height", height).map_err(at(doc, "camera"))?,
            }
        }
        ProjectionSpec::Environment => Projection::Environment,
    })
}

/// The thin lens (a pinhole by default); an environment camera has none.
fn thin_lens(doc: &Document, spec: &CameraSpec) -> Result<ThinLens, SceneError> {
    let at = at(doc, "camera");
    let radius = spec.lens_radius.unwrap_or(ThinLens::PINHOLE.radius);
    let radius = rules::lens_radius("lens_radius", radius).map_err(&at)?;
    let focal_distance = spec
        .focal_distance
        .map(|f| rules::positive("focal_distance", f))
        .transpose()
        .map_err(&at)?
        .unwrap_or(ThinLens::PINHOLE.focal_distance);
    if spec.projection == ProjectionSpec::Environment && radius > 0.0 {
        return Err(doc.error("camera.lens_radius", "an environment camera has no lens"));
    }
    Ok(ThinLens {
        radius,
        focal_distance,
    })
}

/// A light other than a mesh light (whose OBJ `mesh` reads first: see [`mesh_light`]).
pub(crate) fn light(doc: &Document, path: &str, spec: &LightSpec) -> Result<Light, SceneError> {
    let v = Vec3::from_array;
    let at = at(doc, path);
    let light = match spec {
        LightSpec::Point(point) => Light::Point {
            position: v(point.position),
            power: v(point.power),
        },
        LightSpec::Sphere(sphere) => Light::Sphere {
            center: v(sphere.center),
            radius: sphere.radius,
            power: v(sphere.power),
        },
        LightSpec::Quad(quad) => Light::Quad {
            corner: v(quad.corner),
            edge_u: v(quad.edge_u),
            edge_v: v(quad.edge_v),
            power: v(quad.power),
        },
        LightSpec::Spot(spot) => {
            let falloff = match &spot.falloff {
                None => SpotFalloff::Smoothstep,
                Some(name) => spot_falloff(doc, &child_path(path, "falloff"), name)?,
            };
            Light::Spot {
                position: v(spot.position),
                direction: rules::direction("direction", v(spot.direction)).map_err(&at)?,
                cone_angle_degrees: spot.cone_angle,
                falloff_start_degrees: spot
                    .falloff_start
                    .unwrap_or((spot.cone_angle - DEFAULT_CONE_DELTA).max(0.0)),
                falloff,
                power: v(spot.power),
            }
        }
        LightSpec::Distant(distant) => Light::Distant {
            direction: rules::direction("direction", v(distant.direction)).map_err(&at)?,
            irradiance: v(distant.irradiance),
        },
        LightSpec::Environment(environment) => Light::Environment {
            radiance: v(environment.radiance),
        },
        LightSpec::Mesh(_) => unreachable!("mesh lights are built by `mesh_light`"),
    };
    checked_light(doc, path, light)
}

/// A mesh light from its loaded triangles.
pub(crate) fn mesh_light(
    doc: &Document,
    path: &str,
    mesh: TriangleMesh,
    spec: &MeshLightSpec,
) -> Result<Light, SceneError> {
    let light = Light::Mesh {
        mesh,
        power: Vec3::from_array(spec.power),
        two_sided: spec.two_sided,
    };
    checked_light(doc, path, light)
}

/// `light` if it obeys [`check_light`], else its error on the file's field.
fn checked_light(doc: &Document, path: &str, light: Light) -> Result<Light, SceneError> {
    const RENAME: [(&str, &str); 3] = [
        ("cone_angle_degrees", "cone_angle"),
        ("falloff_start_degrees", "falloff_start"),
        // The loader drops what `check_mesh` refuses; anything left is the file's fault.
        ("mesh", "file"),
    ];
    check_light(&light).map_err(|e| {
        let e = match e.field.starts_with("mesh.") {
            true => InvalidField::new("mesh", e.to_string()),
            false => e,
        };
        located(doc, path, e, &RENAME)
    })?;
    Ok(light)
}

fn spot_falloff(doc: &Document, path: &str, name: &str) -> Result<SpotFalloff, SceneError> {
    FALLOFFS
        .iter()
        .find(|(known, _)| *known == name)
        .map(|&(_, falloff)| falloff)
        .ok_or_else(|| {
            doc.error(
                path,
                format!("unknown falloff `{name}`, expected `smoothstep` or `quartic`"),
            )
        })
}

/// The material at `path`; `names` gives each `[materials]` entry's index, for a mix.
pub(crate) fn material(
    doc: &Document,
    path: &str,
    spec: &MaterialSpec,
    images: &ImageSource,
    names: &HashMap<&str, u32>,
) -> Result<(Material, Vec<(TexturedParameter, Texture)>), SceneError> {
    let mut textures = Vec::new();
    let mut colour = |field: &str,
                      given: Option<&ColourSpec>,
                      parameter: TexturedParameter|
     -> Result<Vec3, SceneError> {
        let Some(given) = given else {
            return Ok(Vec3::ONE);
        };
        let (value, texture) = toml_texture::colour(doc, &child_path(path, field), given, images)?;
        textures.extend(texture.map(|t| (parameter, t)));
        Ok(value)
    };
    let material = match spec {
        MaterialSpec::Diffuse(diffuse) => Material::Diffuse {
            albedo: colour("albedo", Some(&diffuse.albedo), TexturedParameter::Albedo)?,
        },
        MaterialSpec::Mirror(mirror) => Material::Mirror {
            tint: colour("tint", mirror.tint.as_ref(), TexturedParameter::Tint)?,
        },
        MaterialSpec::Glass(glass) => Material::Glass {
            ior: glass.ior,
            reflect_tint: colour(
                "reflect_tint",
                glass.reflect_tint.as_ref(),
                TexturedParameter::ReflectTint,
            )?,
            transmit_tint: colour(
                "transmit_tint",
                glass.transmit_tint.as_ref(),
                TexturedParameter::TransmitTint,
            )?,
        },
        MaterialSpec::Bsdf(kind, spec) => {
            let mut read =
                |field: &str, given: Option<&ColourSpec>, default: f32, parameter| match given {
                    None => Ok(Vec3::splat(default)),
                    Some(_) => colour(field, given, TexturedParameter::Model(parameter)),
                };
            let refuse =
                |field: &str, message: String| doc.error(&child_path(path, field), message);
            Material::Bsdf(super::toml_bsdf::model(kind, spec, &mut read, &refuse)?)
        }
        // Checked on its own: it has no colours.
        MaterialSpec::Mix(mix) => return super::toml_mix::mix(doc, path, mix, names, images),
    };
    check_material(&material).map_err(at(doc, path))?;
    Ok((material, textures))
}

pub(crate) fn sphere(
    doc: &Document,
    path: &str,
    spec: &SphereSpec,
    materials: &MaterialTable,
) -> Result<Shape, SceneError> {
    let at = at(doc, path);
    Ok(Shape::Sphere {
        center: rules::finite3("center", Vec3::from_array(spec.center)).map_err(&at)?,
        radius: rules::positive("radius", spec.radius).map_err(&at)?,
        material: materials.resolve(doc, &child_path(path, "material"), &spec.material)?,
        to_object: glam::Mat3::IDENTITY,
    })
}

/// A quad object becomes two triangles wound so their normal is `edge_u × edge_v`.
pub(crate) fn quad(
    doc: &Document,
    path: &str,
    spec: &QuadSpec,
    materials: &MaterialTable,
) -> Result<Shape, SceneError> {
    let [corner, edge_u, edge_v] = [spec.corner, spec.edge_u, spec.edge_v].map(Vec3::from_array);
    rules::parallelogram(corner, edge_u, edge_v).map_err(at(doc, path))?;
    let material = materials.resolve(doc, &child_path(path, "material"), &spec.material)?;
    Ok(Shape::Triangles(Arc::new(TriangleMesh {
        positions: vec![
            corner,
            corner + edge_u,
            corner + edge_u + edge_v,
            corner + edge_v,
        ],
        normals: None,
        // (u, v) run along edge_u and edge_v from the corner.
        uvs: Some(vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        material,
        cutout: None,
    })))
}

/// Where a mesh object or light takes its triangles from and how it places them.
pub(crate) struct PlacementSpec<'a> {
    pub file: &'a str,
    pub translate: [f32; 3],
    pub rotate: [f32; 3],
    pub scale: Scale,
}

/// The placement of a mesh object, with its `material` override resolved.
pub(crate) fn mesh_object_placement(
    doc: &Document,
    path: &str,
    spec: &MeshSpec,
    materials: &MaterialTable,
) -> Result<MeshPlacement, SceneError> {
    let material_override = match &spec.material {
        Some(name) => Some(materials.resolve(doc, &child_path(path, "material"), name)?),
        None => None,
    };
    let placement = PlacementSpec {
        file: &spec.file,
        translate: spec.translate,
        rotate: spec.rotate,
        scale: spec.scale,
    };
    mesh_placement(doc, path, placement, material_override)
}

impl<'a> From<&'a MeshLightSpec> for PlacementSpec<'a> {
    fn from(spec: &'a MeshLightSpec) -> Self {
        Self {
            file: &spec.file,
            translate: spec.translate,
            rotate: spec.rotate,
            scale: spec.scale,
        }
    }
}

/// Checks the file name and transform of the mesh object or light at `path`.
pub(crate) fn mesh_placement(
    doc: &Document,
    path: &str,
    spec: PlacementSpec,
    material_override: Option<u32>,
) -> Result<MeshPlacement, SceneError> {
    if spec.file.trim().is_empty() {
        return Err(doc.error(&child_path(path, "file"), "is empty; give an OBJ file path"));
    }
    let at = at(doc, path);
    let translate = rules::finite3("translate", Vec3::from_array(spec.translate)).map_err(&at)?;
    let rotate = rules::finite3("rotate", Vec3::from_array(spec.rotate)).map_err(&at)?;
    let scale = match spec.scale {
        Scale::Uniform(factor) => Vec3::splat(rules::positive("scale", factor).map_err(&at)?),
        Scale::PerAxis(factors) => {
            for (axis, &factor) in factors.iter().enumerate() {
                rules::positive(&format!("scale[{axis}]"), factor).map_err(&at)?;
            }
            Vec3::from_array(factors)
        }
    };
    Ok(MeshPlacement {
        file: spec.file.to_string(),
        material_override,
        transform: Transform::new(translate, rotate, scale),
        keep_normals: true,
    })
}

/// Warnings (not errors) for lights sealed inside a closed opaque object that the camera is
/// outside of: such a light cannot brighten anything the camera sees. A light inside a closed
/// room with the camera, or inside glass, is fine and gives none. Closed means a sphere, or a
/// triangle mesh (one material's part of an OBJ, or a quad... which is never closed) in which
/// every edge is shared by exactly two triangles; inside is decided by ray parity.
pub(crate) fn enclosed_light_warnings(scene: &super::SceneDescription) -> Vec<String> {
    let materials = &scene.materials;
    let opaque = |m: u32| {
        let glass = |m: &Material| matches!(m, Material::Glass { .. });
        !materials[m as usize].any_shown(materials, &glass)
    };
    // Where each light is: lights at infinity are inside nothing; a mesh light is judged by
    // its middle.
    let lights: Vec<(usize, Vec3)> = (scene.lights.iter().enumerate())
        .filter_map(|(l, light)| match light {
            Light::Point { position, .. } | Light::Spot { position, .. } => Some((l, *position)),
            Light::Sphere { center, .. } => Some((l, *center)),
            Light::Quad {
                corner,
                edge_u,
                edge_v,
                ..
            } => Some((l, *corner + 0.5 * (*edge_u + *edge_v))),
            Light::Mesh { mesh, .. } => {
                let (lo, hi) = mesh.bounds();
                Some((l, 0.5 * (lo + hi)))
            }
            Light::Distant { .. } | Light::Environment { .. } | Light::EnvironmentMap(_) => None,
        })
        .collect();
    let mut warnings = Vec::new();
    if lights.is_empty() {
        return warnings;
    }
    for (s, shape) in scene.shapes.iter().enumerate() {
        // The cheap tests first: a big mesh with no light within its bounds is never walked.
        let (inside, what): (Box<dyn Fn(Vec3) -> bool>, _) = match shape {
            Shape::Sphere {
                center,
                radius,
                material,
                ..
            } if opaque(*material) => {
                let (c, r) = (*center, *radius);
                let inside = move |p: Vec3| p.distance_squared(c) < r * r;
                (Box::new(inside), "an opaque sphere")
            }
            Shape::Triangles(mesh) if opaque(mesh.material) => {
                let (lo, hi) = mesh.bounds();
                let within = move |p: Vec3| p.cmpge(lo).all() && p.cmple(hi).all();
                if !lights.iter().any(|&(_, at)| within(at)) || !is_closed(mesh) {
                    continue;
                }
                let inside = move |p: Vec3| within(p) && inside_closed_mesh(mesh, p);
                // Curves are never closed (a tube is open at its ends).
                (Box::new(inside), "a closed opaque mesh")
            }
            _ => continue,
        };
        if inside(scene.camera.position) {
            continue;
        }
        for &(l, at) in &lights {
            if inside(at) {
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
/// faces split by normals repeat positions): sorted, each edge must appear exactly twice.
fn is_closed(mesh: &TriangleMesh) -> bool {
    let key = |i: u32| mesh.positions[i as usize].to_array().map(f32::to_bits);
    let mut edges: Vec<([u32; 3], [u32; 3])> = Vec::with_capacity(3 * mesh.triangles.len());
    for &[a, b, c] in &mesh.triangles {
        for (p, q) in [(a, b), (b, c), (c, a)] {
            let (p, q) = (key(p), key(q));
            edges.push(if p < q { (p, q) } else { (q, p) });
        }
    }
    edges.par_sort_unstable();
    let mut runs = edges.chunk_by(|x, y| x == y);
    !edges.is_empty() && runs.all(|run| run.len() == 2)
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
