//! The pbrt parser and mapping, with includes and PLY meshes from the same input (`@@@ NAME`
//! lines): a scene that loads is finite and consistent, a refusal names a place.
#![no_main]

#[path = "support/mod.rs"]
mod support;

use dpm::scene::{LoadOptions, load_from};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let files = support::files(data, "scene.pbrt");
    let first = data.first().copied().unwrap_or(0);
    let (strict, pbrt_default_integrator) = (first & 1 == 1, first & 2 == 2);
    match load_from(
        &support::scene_path("scene.pbrt"),
        &files,
        &LoadOptions {
            strict,
            pbrt_default_integrator,
        },
    ) {
        Ok((scene, _report)) => support::check_scene(&scene),
        Err(e) => support::check_error(&e),
    }
});
