//! What the scene fuzz targets share: one input holds several files (`@@@ NAME` lines start
//! each after the first), and a loaded scene must be finite and consistent.
#![allow(dead_code)]

use dpm::scene::files::InMemory;
use dpm::scene::{SceneDescription, SceneError, Shape, check_light, check_material, check_mesh};
use std::path::{Path, PathBuf};

/// Splits `data` into files: the first is `first`, each later one follows a line `@@@ NAME`.
pub fn files(data: &[u8], first: &str) -> InMemory {
    let mut files = InMemory::default();
    let mut name = first.to_string();
    let mut start = 0;
    let marker = b"\n@@@ ";
    let mut at = 0;
    while let Some(i) = find(&data[at..], marker) {
        let head = at + i;
        files.insert(Path::new("fuzz").join(&name), &data[start..head]);
        let name_start = head + marker.len();
        let name_end = data[name_start..]
            .iter()
            .position(|&b| b == b'\n')
            .map_or(data.len(), |j| name_start + j);
        name = String::from_utf8_lossy(&data[name_start..name_end])
            .trim()
            .to_string();
        start = (name_end + 1).min(data.len());
        at = start;
    }
    files.insert(Path::new("fuzz").join(&name), &data[start..]);
    files
}

pub fn scene_path(first: &str) -> PathBuf {
    Path::new("fuzz").join(first)
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

/// A scene that loaded: every number finite, every index in range, every light emitting,
/// something to see (world shapes, instances of prototypes that have shapes, or media boundaries).
pub fn check_scene(scene: &SceneDescription) {
    let c = &scene.camera;
    assert!(c.position.is_finite() && c.look_at.is_finite() && c.up.is_finite());
    assert!(c.fov_y_degrees().is_none_or(|f| f > 0.0 && f < 180.0) && c.width > 0 && c.height > 0);
    assert!(!scene.lights.is_empty());
    // A medium's boundaries alone are something to see (a fog sphere under a sky).
    let boundaries = !scene.media.boundaries.is_empty();
    assert!(!scene.shapes.is_empty() || !scene.instances.is_empty() || boundaries);
    for light in &scene.lights {
        assert!(check_light(light).is_ok(), "{light:?}");
    }
    for m in &scene.materials {
        assert!(check_material(m).is_ok(), "{m:?}");
    }
    for shape in &scene.shapes {
        check_shape(shape, scene.materials.len());
    }
    for prototype in &scene.prototypes {
        for shape in &prototype.shapes {
            check_shape(shape, scene.materials.len());
        }
    }
    for instance in &scene.instances {
        let prototype = &scene.prototypes[instance.prototype as usize];
        assert!(!prototype.shapes.is_empty());
        let m = instance.object_to_world;
        assert!(m.is_finite() && m.determinant().is_normal());
    }
}

fn check_shape(shape: &Shape, materials: usize) {
    match shape {
        Shape::Sphere {
            center,
            radius,
            material,
            to_object,
        } => {
            assert!(to_object.is_finite());
            assert!(center.is_finite() && radius.is_finite() && *radius > 0.0);
            assert!((*material as usize) < materials);
        }
        Shape::Triangles(mesh) => {
            assert!((mesh.material as usize) < materials);
            assert!(!mesh.triangles.is_empty());
            assert!(check_mesh(mesh).is_ok());
        }
        Shape::Curves(curves) => {
            assert!((curves.material as usize) < materials);
            assert!(dpm::scene::check_curves(curves).is_ok());
        }
    }
}

/// A refusal names the file and a place in it, or the field it is about.
pub fn check_error(e: &SceneError) {
    assert!(!e.file.as_os_str().is_empty(), "{e}");
    assert!(e.line.is_some() || !e.field.is_empty(), "{e}");
    assert!(!e.message.is_empty(), "{e}");
}
