//! Helpers of the pbrt tests: load a pbrt scene from text, a small world around a body of
//! directives (camera, film, one point light), the spheres a scene holds.

use super::write_scene;
use dpm::scene::{self, Shape};
use glam::Vec3;
use std::path::Path;

/// Loads pbrt `text` written as `scene.pbrt` in `dir`.
pub fn load_text(
    dir: &Path,
    text: &str,
) -> Result<(scene::SceneDescription, scene::LoadReport), scene::SceneError> {
    let path = write_scene(dir, "scene.pbrt", text);
    scene::load_with_report(&path)
}

pub fn loads(text: &str) -> (scene::SceneDescription, scene::LoadReport) {
    let dir = tempfile::tempdir().unwrap();
    load_text(dir.path(), text).unwrap_or_else(|e| panic!("{e}\n{text}"))
}

pub const CAMERA: &str = "LookAt 0 1 4  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
    Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24\n";
pub const LIGHT: &str = "LightSource \"point\" \"point from\" [0 3 0] \"rgb I\" [10 10 10]\n";

pub fn world(body: &str) -> String {
    format!("{CAMERA}WorldBegin\n{LIGHT}{body}WorldEnd\n")
}

pub fn spheres(scene: &scene::SceneDescription) -> Vec<(Vec3, f32)> {
    scene
        .shapes
        .iter()
        .filter_map(|s| match s {
            Shape::Sphere { center, radius, .. } => Some((*center, *radius)),
            _ => None,
        })
        .collect()
}

pub fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// Renders pbrt `text` (written as `name` in `dir`) with `seed`, two passes of 50k caustic
/// and 50k global photons on two threads, plus `extra` arguments.
pub fn render(
    dir: &Path,
    name: &str,
    text: &str,
    seed: &str,
    extra: &[&str],
) -> dpm::image_io::Image {
    let path = write_scene(dir, name, text);
    let out = dir.join(format!("{name}.pfm"));
    let mut args = vec![
        super::path_str(&path),
        "-o",
        super::path_str(&out),
        "--threads",
        "2",
        "--seed",
        seed,
        "--passes",
        "2",
        "--caustic-photons",
        "50000",
        "--global-photons",
        "50000",
    ];
    args.extend_from_slice(extra);
    dpm::render::pipeline::run(&super::render_args(&args))
        .unwrap_or_else(|e| panic!("{e}"))
        .image
}
