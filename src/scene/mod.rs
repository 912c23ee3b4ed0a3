//! PLACEHOLDER: the scene helper replaces the body, keeping these types as the contract.
//! Scene description: the TOML scene format, OBJ/MTL meshes and their validation, resolved
//! into plain data ([`SceneDescription`]). Owns parsing and error reporting; must not call
//! Embree or trace anything (the [`crate::world`] module turns this into an Embree scene).

use glam::Vec3;
use std::path::{Path, PathBuf};

#[derive(Clone, Debug, PartialEq)]
pub struct SceneDescription {
    pub source: PathBuf,
    pub camera: Camera,
    pub lights: Vec<Light>,
    pub materials: Vec<Material>,
    pub shapes: Vec<Shape>,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub look_at: Vec3,
    pub up: Vec3,
    pub fov_y_degrees: f32,
    pub width: u32,
    pub height: u32,
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
    Diffuse { albedo: Vec3 },
    Mirror,
    Glass { ior: f32 },
}

#[derive(Clone, Debug, PartialEq)]
pub enum Shape {
    Sphere {
        center: Vec3,
        radius: f32,
        material: u32,
    },
    Triangles(TriangleMesh),
}

/// World-space triangles with one material; `normals`, when present, are per vertex.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub triangles: Vec<[u32; 3]>,
    pub material: u32,
}

/// A scene error names the file, the line (when known) and the field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{}{}: {field}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct SceneError {
    pub file: PathBuf,
    pub line: Option<usize>,
    pub field: String,
    pub message: String,
}

pub fn load(path: &Path) -> Result<SceneDescription, SceneError> {
    Err(SceneError {
        file: path.to_path_buf(),
        line: None,
        field: "scene".into(),
        message: "scene loading not written yet".into(),
    })
}
