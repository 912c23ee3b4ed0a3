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
