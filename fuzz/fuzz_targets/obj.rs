//! The OBJ/MTL reader: the input is an OBJ (then any MTL libraries after `@@@ NAME` lines)
//! placed by a fixed scene that takes its materials from the MTL; a mesh that loads is finite
//! and consistent, a refusal names a place.
#![no_main]

#[path = "support/mod.rs"]
mod support;

use dpm::scene::{LoadOptions, load_from};
use libfuzzer_sys::fuzz_target;

const SCENE: &str = include_str!("../../tests/fixtures/one-mesh.toml");

fuzz_target!(|data: &[u8]| {
    let mut files = support::files(data, "mesh.obj");
    files.insert(support::scene_path("scene.toml"), SCENE);
    match load_from(
        &support::scene_path("scene.toml"),
        &files,
        &LoadOptions::default(),
    ) {
        Ok((scene, _report)) => support::check_scene(&scene),
        Err(e) => support::check_error(&e),
    }
});
