//! An open scene's global map: most diffuse bounces drawn by the cosine leave the scene, so a
//! probe of the first paths finds it open and half the bounces aim at the other objects. The
//! aimed map stores the flux the cosine-drawn one does, on each object; the render says it
//! aimed and stores a photon for fewer paths; a closed box probes closed and aims nothing.

mod support;

use dpm::image_metrics::channel_mean;
use dpm::photon::tracer::{MapKind, trace_map};
use dpm::world::World;
use support::*;

/// A matte floor with two matte balls on it under a point light, the sky black and open.
fn open_floor(width: u32, height: u32) -> String {
    format!(
        "LookAt 0 3 7  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" [45]\n\
         Film \"image\" \"integer xresolution\" [{width}] \"integer yresolution\" [{height}]\n\
         WorldBegin\n\
         LightSource \"point\" \"point from\" [0 4 0] \"rgb I\" [5 5 5]\n\
         AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"point P\" [-5 0 -5  5 0 -5  5 0 5  -5 0 5] \
         \"integer indices\" [0 2 1 0 3 2]\nAttributeEnd\n\
         AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.2 0.6 0.3]\nTranslate -0.8 0.7 0\n\
         Shape \"sphere\" \"float radius\" [0.7]\nAttributeEnd\n\
         AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.7 0.3 0.2]\nTranslate 0.9 0.6 0.3\n\
         Shape \"sphere\" \"float radius\" [0.6]\nAttributeEnd\nWorldEnd\n"
    )
}

#[test]
fn aimed_bounces_in_an_open_scene_store_the_flux_cosine_drawn_ones_do_on_each_object() {
    let (description, _) = support::pbrt::loads(&open_floor(32, 24));
    let mut world = World::new(description).unwrap();
    let kind = MapKind::Global { with_direct: false };
    let bar = indicatif::ProgressBar::hidden();
    // Flux stored on the floor and on the balls (above it), over four seeds.
    let flux = |world: &World| {
        let (mut floor, mut balls, mut paths_a_photon) = (0.0, 0.0, 0.0);
        for seed in 1..=4 {
            let (map, counts) = trace_map(world, kind, 40_000, seed, &bar);
            paths_a_photon += counts.emitted as f64 / counts.stored as f64 / 4.0;
            for s in 0..map.len() as u32 {
                let power = channel_mean(map.attributes(s).power()) as f64;
                if map.position(s).y > 1e-3 {
                    balls += power;
                } else {
                    floor += power;
                }
            }
        }
        (floor, balls, paths_a_photon)
    };
    let cosine = flux(&world);
    assert!(
        world.aim_bounces_at_objects(0.5),
        "three objects can be aimed at"
    );
    let aimed = flux(&world);
    eprintln!("cosine {cosine:?}, aimed {aimed:?}");
    assert!(
        (aimed.0 / cosine.0 - 1.0).abs() < 0.03,
        "floor: {aimed:?} vs {cosine:?}"
    );
    assert!(
        (aimed.1 / cosine.1 - 1.0).abs() < 0.03,
        "balls: {aimed:?} vs {cosine:?}"
    );
    assert!(
        aimed.2 * 2.0 < cosine.2,
        "aiming stores a photon for fewer paths"
    );
}

#[test]
fn an_open_floor_probes_open_and_a_closed_box_closed() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "open.pbrt", &open_floor(32, 24));
    let out = dir.path().join("open.pfm");
    let args = [path_str(&scene), "-o", path_str(&out), "--passes", "1"];
    let outcome = dpm::render::pipeline::run(&render_args(&args)).unwrap();
    let table = outcome.times.table();
    assert!(table.contains("aimed=1"), "{table}");
    let box_scene = scene_with_resolution("scenes/cornell-box.toml", 32, 24);
    let boxed = write_scene(dir.path(), "box.toml", &box_scene);
    let out = dir.path().join("box.pfm");
    let args = [path_str(&boxed), "-o", path_str(&out), "--passes", "1"];
    let outcome = dpm::render::pipeline::run(&render_args(&args)).unwrap();
    let table = outcome.times.table();
    assert!(table.contains("aimed=0"), "{table}");
}

/// The indirect layer's mean over the image.
fn indirect_mean(outcome: &dpm::render::pipeline::RenderOutcome) -> f64 {
    let layer = outcome.film.layer("indirect").expect("an indirect layer");
    let sum: f64 = layer.pixels.iter().map(|p| dvec(*p).element_sum()).sum();
    sum / layer.pixels.len() as f64
}

#[test]
fn a_global_map_sized_by_its_share_of_the_image_keeps_the_indirect_light() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "open.pbrt", &open_floor(48, 36));
    let out = dir.path().join("open.pfm");
    let render = |extra: &[&str]| {
        let mut args = vec![path_str(&scene), "-o", path_str(&out), "--passes", "8"];
        args.extend_from_slice(&["--caustic-photons", "0"]);
        args.extend_from_slice(extra);
        dpm::render::pipeline::run(&render_args(&args)).unwrap()
    };
    let sized = render(&[]);
    let full = render(&["--global-photons", "300000"]);
    let (s, f) = (sized.global.unwrap(), full.global.unwrap());
    assert!(
        s.stored * 4 < f.stored,
        "the sized map is smaller: {s:?} vs {f:?}"
    );
    let (a, b) = (indirect_mean(&sized), indirect_mean(&full));
    eprintln!("indirect: sized {a}, full {b}");
    assert!(
        (a / b - 1.0).abs() < 0.03,
        "indirect light: sized {a}, full {b}"
    );
}
