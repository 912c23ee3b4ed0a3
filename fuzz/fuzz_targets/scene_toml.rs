//! The TOML scene loader, with the OBJ meshes and MTL libraries it names taken from the same
//! input (`@@@ NAME` lines): a scene that loads is finite and consistent, a refusal names a
//! place.
#![no_main]

#[path = "support/mod.rs"]
mod support;

use dpm::scene::{LoadOptions, load_from};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let files = support::files(data, "scene.toml");
    match load_from(
        &support::scene_path("scene.toml"),
        &files,
        &LoadOptions::default(),
    ) {
        Ok((scene, _report)) => support::check_scene(&scene),
        Err(e) => support::check_error(&e),
    }
});
