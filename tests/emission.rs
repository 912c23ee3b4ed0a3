//! The light a camera sees along its mirror and glass chains, sampled apart from the rest of
//! a pixel (`render::emission`): a light's edge crossing pixels, whose covered fraction the
//! emission samples resolve and one camera sample cannot; the same light seen in a mirror;
//! the pixels flagged; the expectation unchanged; and the flag's validation.

mod support;

use dpm::render::pipeline;
use glam::DVec3;
use std::f64::consts::PI;
use support::*;

/// The camera at z = 10 looks down −z at a quad light in the plane z = `light_z` (facing it)
/// that covers x < `edge` (and all of y), or, with `mirror`, at a mirror square at z = 0 that
/// shows that light behind the camera. 32 × 32 pixels, 30° field of view.
fn edge_scene(edge: f64, mirror: bool) -> String {
    let light = if mirror {
        // Behind the camera, facing −z, seen in the mirror at z = 0 as if at z = −20.
        format!(
            "[[lights]]\ntype = \"quad\"\ncorner = [-100.0, -100.0, 20.0]\n\
             edge_u = [0.0, 200.0, 0.0]\nedge_v = [{}, 0.0, 0.0]\npower = [4000.0, 2000.0, 1000.0]\n",
            edge + 100.0
        )
    } else {
        format!(
            "[[lights]]\ntype = \"quad\"\ncorner = [-100.0, -100.0, 0.0]\n\
             edge_u = [{}, 0.0, 0.0]\nedge_v = [0.0, 200.0, 0.0]\npower = [4000.0, 2000.0, 1000.0]\n",
            edge + 100.0
        )
    };
    let mirror = if mirror {
        "[materials.chrome]\ntype = \"mirror\"\n\n[[objects]]\ntype = \"quad\"\n\
         corner = [-50.0, -50.0, 0.0]\nedge_u = [100.0, 0.0, 0.0]\nedge_v = [0.0, 100.0, 0.0]\n\
         material = \"chrome\"\n"
    } else {
        ""
    };
    // Scenes need an object: a diffuse square out of sight, behind the camera and the light.
    let unseen = "[materials.grey]\ntype = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\n[[objects]]\n\
                  type = \"quad\"\ncorner = [0.0, 0.0, 40.0]\nedge_u = [1.0, 0.0, 0.0]\n\
                  edge_v = [0.0, 1.0, 0.0]\nmaterial = \"grey\"\n";
    format!(
        "[camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
         fov_y = 30.0\nresolution = [32, 32]\n\n{light}\n{mirror}\n{unseen}"
    )
}

/// The fraction of pixel column `i` in which the light (x < `edge` at distance `depth` from
/// the camera) is seen: image x is linear in world x on a plane facing the camera.
fn covered(i: usize, edge: f64, depth: f64) -> f64 {
    let tan_half = (15.0f64).to_radians().tan();
    let at = (edge / (depth * tan_half) + 1.0) * 16.0;
    (at - i as f64).clamp(0.0, 1.0)
}

fn render(text: &str, args: &[&str]) -> dpm::image_io::Image {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "edge.toml", text);
    let out = dir.path().join("edge.pfm");
    // No caustic photons: none would reach the unseen square.
    let mut all = vec![path_str(&scene), "-o", path_str(&out), "--threads", "2"];
    all.extend_from_slice(&["--caustic-photons", "0"]);
    all.extend_from_slice(args);
    pipeline::run(&render_args(&all))
        .unwrap_or_else(|e| panic!("{e}"))
        .image
}

/// Where the light's edge crosses a pixel, 64 emission samples give the covered fraction of
/// the light's radiance within 2% (Owen-scrambled Sobol points are stratified along x); one
/// camera sample gives all of it or nothing. Pixels wholly inside show the light exactly; seen
/// in a mirror, the same, from three times the distance.
#[test]
fn emission_samples_resolve_a_light_edge_inside_a_pixel() {
    // The edge a third of the way into column 21 (direct) and into column 18 (mirror).
    for (mirror, depth) in [(false, 10.0), (true, 30.0)] {
        let tan_half = (15.0f64).to_radians().tan();
        let column = if mirror { 18.0 } else { 21.0 };
        let edge = ((column + 0.37) / 16.0 - 1.0) * depth * tan_half;
        let le = DVec3::new(4000.0, 2000.0, 1000.0) / (PI * 200.0 * (edge + 100.0));
        let text = edge_scene(edge, mirror);
        let sampled = render(&text, &["--emission-samples", "64"]);
        // One camera sample a pixel: no emission samples, and no more at the edge either.
        let camera_only = render(&text, &["--emission-samples", "0", "--edge-samples", "0"]);
        let mut worst_camera: f64 = 0.0;
        for y in 0..32 {
            for x in 0..32 {
                let want = le * covered(x, edge, depth);
                let got = sampled.get(x, y).as_dvec3();
                let camera = camera_only.get(x, y).as_dvec3();
                for c in 0..3 {
                    assert!(
                        (got[c] - want[c]).abs() <= 0.02 * le[c] + 1e-6 * le[c],
                        "mirror {mirror}, pixel ({x}, {y}) channel {c}: {} vs {}",
                        got[c],
                        want[c]
                    );
                }
                worst_camera = worst_camera.max((camera.x - want.x).abs() / le.x);
            }
        }
        // One camera sample per pixel sees the edge pixel all lit or all dark.
        assert!(worst_camera > 0.3, "camera samples alone: {worst_camera}");
    }
}

/// Sampling the emitted light apart changes no expectation: over passes, the glass sphere's
/// image (the light through it, split at every glass hit) with and without emission samples
/// has the same mean, within the camera samples' noise.
#[test]
fn emission_samples_keep_the_image_mean() {
    let text = eye::sphere_scene("glass");
    let mean = |args: &[&str]| {
        let image = render(&text, args);
        image.pixels.iter().map(|p| p.as_dvec3()).sum::<DVec3>() / image.pixels.len() as f64
    };
    let sampled = mean(&["--emission-samples", "16", "--passes", "8"]);
    let camera_only = mean(&["--emission-samples", "0", "--passes", "64"]);
    let le = eye::emitter_radiance();
    for c in 0..3 {
        let e = (sampled[c] - camera_only[c]).abs() / le[c];
        assert!(e < 3e-3, "channel {c}: {sampled} vs {camera_only}");
    }
}

#[test]
fn too_many_emission_samples_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "edge.toml", &edge_scene(0.5, false));
    let out = dir.path().join("edge.pfm");
    let args = render_args(&[
        path_str(&scene),
        "-o",
        path_str(&out),
        "--emission-samples",
        "100000",
    ]);
    let e = pipeline::run(&args).err().expect("refused");
    assert_eq!(e.exit_code(), 2);
    assert!(e.to_string().contains("--emission-samples 100000"), "{e}");
}

/// A drawn chain and the same chain forced (`Integrator::emitted_chain`, as aimed emission
/// samples follow it) see the same light with the same tints and the same probability: the
/// product of the Fresnel choices the drawn chain took. Through the glass sphere in front of
/// the quad light, over rays across its face, with reflections and refractions both drawn;
/// and a forced chain that meets the light before its last choice sees nothing.
#[test]
fn a_forced_chain_sees_what_the_drawn_chain_saw() {
    use dpm::sampling::{Rng, Stream};
    for material in [
        "glass",
        "red_halving_reflection",
        "red_halving_transmission",
    ] {
        let world = world(&eye::sphere_scene(material));
        let integrator = eye::whitted(&world, 10);
        let (mut seen, mut reflected) = (0, 0);
        for i in 0..2000u64 {
            let b = (i as f32 + 0.5) / 2000.0 * 0.95;
            let (origin, dir) = (glam::Vec3::new(b, 0.0, 10.0), -glam::Vec3::Z);
            let mut rng = Rng::for_index(5, Stream::EmissionSamples, i);
            let mut again = rng.clone();
            let drawn = integrator.emitted_chain(origin, dir, &mut rng, None);
            // The drawn chain's value is the one `emitted` gives with the same numbers.
            assert_eq!(drawn.value, integrator.emitted(origin, dir, &mut again));
            if drawn.value == glam::Vec3::ZERO {
                continue;
            }
            seen += 1;
            reflected += usize::from(drawn.code.count_ones() < drawn.code.ilog2() + 1);
            let forced = integrator.emitted_chain(origin, dir, &mut rng, Some(drawn.code));
            assert_eq!(forced.code, drawn.code);
            assert!(
                (forced.value - drawn.value).abs().max_element()
                    <= 1e-5 * drawn.value.max_element()
            );
            assert!(
                (forced.probability - drawn.probability).abs() <= 1e-6,
                "{material}, b = {b}: {forced:?} against {drawn:?}"
            );
            // The probability is the Fresnel product along the chain, in (0, 1].
            assert!(drawn.probability > 0.0 && drawn.probability <= 1.0);
            // A chain one choice longer meets the light before its last choice: it is another
            // chain's path, which forcing this one must not count.
            let longer = integrator.emitted_chain(origin, dir, &mut rng, Some(drawn.code << 1));
            assert_eq!(longer.value, glam::Vec3::ZERO);
        }
        assert!(
            seen > 1000 && reflected > 10,
            "{material}: {seen} seen, {reflected} reflected"
        );
    }
}

/// A sphere light a fifth of a pixel across (`radius_pixels` 0.1), seen straight ahead and in
/// a flat mirror: each pixel holding its centre shows radiance × the disc's share of the
/// pixel, π · 0.1², with emission samples aimed at the image (most of them hit it) and, far
/// noisier, spread across the pixel.
#[test]
fn aimed_emission_samples_give_a_small_lights_share_of_its_pixel() {
    let tan_half = (15.0f64).to_radians().tan();
    let world_x = |column: f64, depth: f64| (column / 16.0 - 1.0) * depth * tan_half;
    // Directly at depth 5 in pixel (16, 15); in the mirror at z = 0 a light at z = 20 is seen
    // 30 units away, in pixel (15, 16).
    for (depth, z, column, row, mirror) in [
        (5.0, 5.0, 16.4, 15.6, false),
        (30.0, 20.0, 15.55, 16.4, true),
    ] {
        let pixel_size = world_x(1.0, depth) - world_x(0.0, depth);
        let radius = 0.1 * pixel_size;
        let (cx, cy) = (world_x(column, depth), -world_x(row, depth));
        let power = 10.0;
        let le = power / (PI * 4.0 * PI * radius * radius);
        let chrome = if mirror {
            "[materials.chrome]\ntype = \"mirror\"\n\n[[objects]]\ntype = \"quad\"\n\
             corner = [-50.0, -50.0, 0.0]\nedge_u = [100.0, 0.0, 0.0]\nedge_v = [0.0, 100.0, 0.0]\n\
             material = \"chrome\"\n"
        } else {
            ""
        };
        let text = format!(
            "[camera]\nposition = [0.0, 0.0, 10.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
             fov_y = 30.0\nresolution = [32, 32]\n\n[[lights]]\ntype = \"sphere\"\n\
             center = [{cx}, {cy}, {z}]\nradius = {radius}\npower = [{power}, {power}, {power}]\n\n\
             {chrome}\n[materials.grey]\ntype = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\n\
             [[objects]]\ntype = \"quad\"\ncorner = [0.0, 0.0, 40.0]\nedge_u = [1.0, 0.0, 0.0]\n\
             edge_v = [0.0, 1.0, 0.0]\nmaterial = \"grey\"\n"
        );
        let want = le * PI * 0.01;
        let (x, y) = (column as usize, row as usize);
        let pixel = |args: &[&str]| render(&text, args).get(x, y).as_dvec3().x;
        // 256 aimed samples a pass hit the image a quarter of the time: about 4% noise.
        let aimed = pixel(&["--emission-samples", "512", "--passes", "4"]);
        assert!(
            (aimed - want).abs() < 0.06 * want,
            "mirror {mirror}: {aimed} against {want}"
        );
        // Spread alone, 2048 samples meet the image about 64 times: about 12% noise.
        let spread = pixel(&[
            "--emission-samples",
            "512",
            "--passes",
            "4",
            "--no-light-images",
        ]);
        assert!(
            (spread - want).abs() < 0.4 * want,
            "mirror {mirror}: {spread} against {want}"
        );
    }
}
