//! Scene description: reads the TOML scene format (docs/scene-format.md) and the OBJ/MTL meshes
//! it names, checks every value, and resolves it all into plain world-space data
//! ([`SceneDescription`]). This module owns parsing and error reporting: every problem becomes
//! a [`SceneError`] naming the file, the 1-based line and the field path, and nothing here
//! panics on bad input. It must not call Embree or trace anything; the [`crate::world`] module
//! turns a [`SceneDescription`] into an Embree scene.
//!
//! Inside: `document` holds the spanned TOML text and turns byte offsets into lines and field
//! paths, `format` holds the serde structs of the file format, `validate` checks them and builds
//! the public types, `mesh` reads OBJ/MTL files, `transform` places meshes in the world.

mod document;
pub mod files;
mod format;
mod mesh;
mod pbrt;
pub mod ply;
pub(crate) mod transform;
mod validate;

use glam::Vec3;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    /// The scene file this was read from.
    pub source: PathBuf,
    pub camera: Camera,
    pub lights: Vec<Light>,
    /// Scene materials in name order, then materials taken from MTL files in order of first use.
    pub materials: Vec<Material>,
    pub shapes: Vec<Shape>,
}

/// A pinhole camera. `up` is not parallel to `look_at - position`, which is not zero.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    /// Full vertical field of view, in (0, 180).
    pub fov_y_degrees: f32,
    pub width: u32,
    pub height: u32,
    /// Which way the image's x axis runs.
    pub handedness: Handedness,
}

/// The image's x axis runs along `forward × up` (right-handed, dpm's TOML default) or along
/// `up × forward` (left-handed, as pbrt's camera space: a pbrt `LookAt` camera).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Handedness {
    #[default]
    Right,
    Left,
}

/// `power` is the total emitted flux in watts per channel.
#[derive(Clone, Debug, PartialEq)]
pub enum Light {
    Point {
        position: Vec3,
        power: Vec3,
    },
    Sphere {
        center: Vec3,
        radius: f32,
        power: Vec3,
    },
    /// Emits from one side only: the side `edge_u × edge_v` points to.
    Quad {
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        power: Vec3,
    },
}

#[derive(Clone, Debug, PartialEq)]
pub enum Material {
    /// Lambertian reflector; every albedo channel lies in [0, 1].
    Diffuse { albedo: Vec3 },
    /// Perfect specular reflector.
    Mirror,
    /// Dielectric with index of refraction `ior >= 1` (outside is vacuum).
    Glass { ior: f32 },
}

#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    /// `material` indexes [`SceneDescription::materials`].
    Sphere {
        center: Vec3,
        radius: f32,
        material: u32,
    },
    Triangles(TriangleMesh),
}

/// World-space triangles with one material; `normals`, when present, are per vertex and unit.
/// Triangles are wound counter-clockwise seen from the side their geometric normal points to;
/// none has zero area.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub triangles: Vec<[u32; 3]>,
    /// Indexes [`SceneDescription::materials`].
    pub material: u32,
}

/// A scene error names the file, the line (when known) and the field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{}{}: {field}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default(), column.map(|c| format!(":{c}")).unwrap_or_default())]
pub struct SceneError {
    /// The scene file, or the OBJ/MTL file when the problem lies inside one.
    pub file: PathBuf,
    /// 1-based line in `file`.
    pub line: Option<usize>,
    /// 1-based column in `line`, where the format has a finer place than the line (pbrt).
    pub column: Option<usize>,
    /// Field path in the scene file, e.g. `objects[2].radius` or `camera.fov_y`.
    pub field: String,
    pub message: String,
}

/// What loading noticed and repaired without failing.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LoadReport {
    /// Zero-area mesh triangles left out (they would give NaN normals).
    pub degenerate_triangles_dropped: usize,
    /// Problems that do not stop a render but probably spoil it (e.g. a light sealed inside
    /// a closed opaque object the camera is outside of).
    pub warnings: Vec<String>,
    /// What was read and deliberately not used (a pbrt file's Sampler or Integrator).
    pub notes: Vec<String>,
}

/// How to read a scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Refuse what would otherwise be mapped with a warning (a pbrt material dpm cannot
    /// represent exactly).
    pub strict: bool,
}

/// Reads and checks the scene file at `path` (TOML, or pbrt by the `.pbrt` extension); mesh
/// files resolve relative to its folder.
pub fn load(path: &Path) -> Result<SceneDescription, SceneError> {
    load_with_report(path).map(|(scene, _report)| scene)
}

/// [`load`], also returning what was repaired on the way.
pub fn load_with_report(path: &Path) -> Result<(SceneDescription, LoadReport), SceneError> {
    load_with_options(path, &LoadOptions::default())
}

/// A pbrt scene read from `files` (the fuzz targets' in-memory set).
pub fn load_pbrt_from(
    path: &Path,
    files: &dyn files::SceneFiles,
    options: &LoadOptions,
) -> Result<(SceneDescription, LoadReport), SceneError> {
    pbrt::load(path, files, options)
}

/// [`load_with_report`] with `options`.
pub fn load_with_options(
    path: &Path,
    options: &LoadOptions,
) -> Result<(SceneDescription, LoadReport), SceneError> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("pbrt"))
        && !path.is_dir()
    {
        return pbrt::load(path, &files::Disk, options);
    }
    let whole_file_error = |message: String| SceneError {
        file: path.to_path_buf(),
        line: None,
        column: None,
        field: "scene".into(),
        message,
    };
    if path.is_dir() {
        return Err(whole_file_error("is a directory, not a scene file".into()));
    }
    let bytes = std::fs::read(path)
        .map_err(|err| whole_file_error(format!("cannot read the scene file: {err}")))?;
    let text = String::from_utf8(bytes).map_err(|err| not_utf8(path, err))?;
    parse(&text, path)
}

/// A scene file that is not UTF-8 text: the error points at the first bad byte's line.
fn not_utf8(path: &Path, err: std::string::FromUtf8Error) -> SceneError {
    let bytes = err.as_bytes();
    let at = err.utf8_error().valid_up_to();
    let line_start = bytes[..at]
        .iter()
        .rposition(|&b| b == b'\n')
        .map_or(0, |i| i + 1);
    SceneError {
        file: path.to_path_buf(),
        line: Some(1 + bytes[..at].iter().filter(|&&b| b == b'\n').count()),
        column: None,
        field: "scene".into(),
        message: format!(
            "is not UTF-8 text: byte 0x{:02x} at column {} is not valid UTF-8",
            bytes[at],
            1 + at - line_start
        ),
    }
}

/// Reads a scene from `text` as if it were the file `source` (which names it in errors and
/// anchors relative mesh paths; it need not exist when the scene has no meshes).
pub fn parse(text: &str, source: &Path) -> Result<(SceneDescription, LoadReport), SceneError> {
    let doc = document::Document::parse(source, text)?;
    let spec = format::read_scene(&doc)?;
    let scene_folder = source.parent().unwrap_or(Path::new("")).to_path_buf();

    let camera = validate::camera(&doc, &spec.camera)?;
    let lights = spec
        .lights
        .iter()
        .enumerate()
        .map(|(i, light)| validate::light(&doc, &format!("lights[{i}]"), light))
        .collect::<Result<Vec<_>, _>>()?;
    let mut materials = validate::MaterialTable::default();
    for (name, material) in &spec.materials {
        let path = document::child_path("materials", name);
        let material = validate::material(&doc, &path, material)?;
        materials.add_named(name, material);
    }

    let mut report = LoadReport::default();
    let mut shapes = Vec::new();
    for (i, object) in spec.objects.iter().enumerate() {
        let path = format!("objects[{i}]");
        match object {
            format::ObjectSpec::Sphere(sphere) => {
                shapes.push(validate::sphere(&doc, &path, sphere, &materials)?);
            }
            format::ObjectSpec::Quad(quad) => {
                shapes.push(validate::quad(&doc, &path, quad, &materials)?);
            }
            format::ObjectSpec::Mesh(mesh_spec) => {
                let placement = validate::mesh_placement(&doc, &path, mesh_spec, &materials)?;
                let loaded = mesh::load(&doc, &path, &scene_folder, &placement, &mut materials)?;
                report.degenerate_triangles_dropped += loaded.degenerate_triangles_dropped;
                shapes.extend(loaded.meshes.into_iter().map(Shape::Triangles));
            }
        }
    }

    let scene = SceneDescription {
        source: source.to_path_buf(),
        camera,
        lights,
        materials: materials.into_materials(),
        shapes,
    };
    report.warnings = validate::enclosed_light_warnings(&scene);
    Ok((scene, report))
}
