//! Light in participating media, rendered whole, against answers known without dpm: a
//! furnace (a medium of albedo 1 under a uniform sky is seen as the sky, whatever its density
//! and phase function, out to the rim where rays graze its wall), an absorbing medium's closed form, a spot light's single scattering
//! against quadrature, the volume photons' power against the geometric series an infinite
//! medium gives, and the same image whatever the thread count.

mod support;

use dpm::photon::tracer::{MapKind, trace_map_within};
use dpm::world::World;
use glam::{DVec3, Vec3};
use indicatif::ProgressBar;
use support::pbrt::loads;
use support::*;

/// Renders pbrt `text` with `extra` arguments (eight passes unless they say otherwise).
fn render(text: &str, extra: &[&str]) -> dpm::image_io::Image {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.pbrt", text);
    let out = dir.path().join("scene.pfm");
    let mut args = vec![path_str(&path), "-o", path_str(&out)];
    if !extra.contains(&"--passes") {
        args.extend_from_slice(&["--passes", "8"]);
    }
    args.extend_from_slice(extra);
    dpm::render::pipeline::run(&render_args(&args))
        .unwrap()
        .image
}

/// The mean of the square of pixels `lo..hi` on both axes.
fn mean(image: &dpm::image_io::Image, lo: usize, hi: usize) -> Vec3 {
    let mut sum = DVec3::ZERO;
    for y in lo..hi {
        for x in lo..hi {
            sum += image.pixels[y * image.width + x].as_dvec3();
        }
    }
    (sum / ((hi - lo) * (hi - lo)) as f64).as_vec3()
}

/// A sphere of radius 1 at the origin bounding `medium` (a `MakeNamedMedium` body), seen
/// from 6 units away at 32 × 32 under a uniform sky of radiance 1.
fn sphere_of(medium: &str) -> String {
    format!(
        "LookAt 0 0 6  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [25]\n\
         Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [32]\n\
         WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n\
         MakeNamedMedium \"fog\" {medium}\n\
         AttributeBegin\nMediumInterface \"fog\" \"\"\nMaterial \"\"\n\
         Shape \"sphere\" \"float radius\" [1]\nAttributeEnd\nWorldEnd\n"
    )
}

#[test]
fn a_scattering_medium_under_a_uniform_sky_is_seen_as_the_sky() {
    // Albedo 1: whatever σs and g, every ray sees radiance 1, in single scattering from the
    // sky, in the volume photons' multiple scattering, and in the sky let through.
    for (sigma, g) in [(0.5, 0.0), (3.0, 0.0), (2.0, 0.7), (2.0, -0.5)] {
        let medium = format!(
            "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \
             \"rgb sigma_s\" [{sigma} {sigma} {sigma}] \"float g\" [{g}]"
        );
        let args = ["--global-photons", "200000", "--spp", "16"];
        let image = render(&sphere_of(&medium), &args);
        let seen = mean(&image, 10, 22);
        for c in seen.to_array() {
            assert!((c - 1.0).abs() < 0.01, "σs {sigma}, g {g}: {seen}");
        }
    }
}

#[test]
fn the_rim_of_a_furnace_sphere_reads_the_sky_as_its_centre_does() {
    // Near the silhouette a camera ray runs close to the sphere's wall at a grazing angle,
    // where a photon kernel around the ray reaches past the wall: unless the estimate
    // accounts for the share cut off, the rim reads dark (0.94–0.96 without it).
    let medium = "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0 0 0] \
                  \"rgb sigma_s\" [3 3 3]";
    let args = ["--global-photons", "200000", "--spp", "16"];
    let image = render(&sphere_of(medium), &args);
    // The sphere's radius on the film: tan(asin(1/6)) over tan(12.5°), of 16 pixels.
    let rim = 16.0 * (1.0f64 / 35f64.sqrt()) / 12.5f64.to_radians().tan();
    for (lo, hi) in [(0.7, 0.85), (0.85, 0.95), (0.95, 1.0)] {
        let mut sum = DVec3::ZERO;
        let mut count = 0;
        for y in 0..32 {
            for x in 0..32 {
                let d = (x as f64 + 0.5 - 16.0).hypot(y as f64 + 0.5 - 16.0) / rim;
                if d > lo && d <= hi {
                    sum += image.pixels[y * 32 + x].as_dvec3();
                    count += 1;
                }
            }
        }
        let seen = sum / count as f64;
        for c in seen.to_array() {
            assert!((c - 1.0).abs() < 0.015, "ring {lo}..{hi}: {seen}");
        }
    }
}

/// The mean over pixel (x, y) of a 32 × 32 image at fov 25 from (0, 0, 6) of exp(−σ·chord)
/// through the unit sphere: the absorbing sphere's closed form.
fn absorbed(x: usize, y: usize, sigma: f64) -> f64 {
    let half = (12.5f64).to_radians().tan();
    let n = 16;
    let mut sum = 0.0;
    for j in 0..n {
        for i in 0..n {
            let u = (x as f64 + (i as f64 + 0.5) / n as f64) / 32.0 * 2.0 - 1.0;
            let v = 1.0 - (y as f64 + (j as f64 + 0.5) / n as f64) / 32.0 * 2.0;
            let d = DVec3::new(u * half, v * half, -1.0).normalize();
            let o = DVec3::new(0.0, 0.0, 6.0);
            // |o + t d|² = 1: t² + 2 (o·d) t + |o|² − 1 = 0.
            let b = o.dot(d);
            let disc = b * b - (o.length_squared() - 1.0);
            let chord = if disc > 0.0 { 2.0 * disc.sqrt() } else { 0.0 };
            sum += (-sigma * chord).exp();
        }
    }
    sum / (n * n) as f64
}

#[test]
fn an_absorbing_medium_lets_through_its_closed_form() {
    let medium = "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0.25 0.5 1] \
                  \"rgb sigma_s\" [0 0 0]";
    let image = render(&sphere_of(medium), &["--passes", "4"]);
    for (x, y) in [(16, 16), (12, 18), (9, 15), (20, 11)] {
        let seen = image.pixels[y * image.width + x];
        for (c, sigma) in [0.25, 0.5, 1.0].into_iter().enumerate() {
            let want = absorbed(x, y, sigma);
            assert!(
                (f64::from(seen[c]) / want - 1.0).abs() < 0.01,
                "pixel ({x}, {y}) channel {c}: {} against {want}",
                seen[c]
            );
        }
    }
}

#[test]
fn a_spot_lights_single_scattering_matches_quadrature() {
    // Fog everywhere (the camera and the light in it), pbrt's maxdepth 1: single scattering
    // alone, along the axis ray x = −3 + t under a spot at (0, 1, 0) aimed down whose cone
    // (89°) spans every direction the ray sees before its light has died away.
    let (sigma_a, sigma_s, g, intensity) = (0.2, 0.3, 0.3, 10.0);
    let text = format!(
        "Integrator \"volpath\" \"integer maxdepth\" [1]\n\
         MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \
         \"rgb sigma_a\" [{sigma_a} {sigma_a} {sigma_a}] \"rgb sigma_s\" [{sigma_s} {sigma_s} {sigma_s}] \
         \"float g\" [{g}]\nMediumInterface \"\" \"fog\"\n\
         LookAt -3 0 0  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [0.5]\n\
         Film \"image\" \"integer xresolution\" [4] \"integer yresolution\" [4]\n\
         WorldBegin\n\
         LightSource \"spot\" \"point from\" [0 1 0] \"point to\" [0 0 0] \
         \"float coneangle\" [89] \"float conedeltaangle\" [1] \"rgb I\" [{intensity} {intensity} {intensity}]\n\
         Material \"matte\" \"rgb Kd\" [0 0 0]\nTranslate 0 0 -1000\n\
         Shape \"sphere\" \"float radius\" [1]\nWorldEnd\n"
    );
    let image = render(&text, &["--passes", "16", "--spp", "256"]);
    let seen = mean(&image, 0, 4);
    // ∫ Tr(t) σs p(θ) I / d² Tr(d) dt along the axis, by the midpoint rule.
    let sigma_t = sigma_a + sigma_s;
    let hg = |mu: f64| {
        (1.0 - g * g) / (4.0 * std::f64::consts::PI * (1.0 + g * g - 2.0 * g * mu).powf(1.5))
    };
    let (steps, end) = (400_000, 60.0);
    let dt = end / steps as f64;
    let mut want = 0.0;
    for k in 0..steps {
        let t = (k as f64 + 0.5) * dt;
        let x = DVec3::new(-3.0 + t, 0.0, 0.0);
        let to_light = DVec3::new(0.0, 1.0, 0.0) - x;
        let d = to_light.length();
        let wi = to_light / d;
        let mu = wi.x; // the ray's direction (1, 0, 0) against the light's.
        want += (-sigma_t * t).exp() * sigma_s * hg(mu) * intensity / (d * d)
            * (-sigma_t * d).exp()
            * dt;
    }
    for c in seen.to_array() {
        assert!(
            (f64::from(c) / want - 1.0).abs() < 0.02,
            "{seen} against {want}"
        );
    }
}

#[test]
fn volume_photons_carry_the_power_an_infinite_medium_scatters() {
    // A point light of power Φ = 4π·I in fog everywhere (albedo a): a photon's k-th event
    // leaves Φ·a^k on average, and the global map keeps the events after the first (the
    // first is single scattering, the eye pass's own): Φ·(a² − a³³)/(1 − a) over 32 events.
    let albedo = 0.6f64;
    let text = format!(
        "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \
         \"rgb sigma_a\" [{a} {a} {a}] \"rgb sigma_s\" [{s} {s} {s}]\n\
         MediumInterface \"\" \"fog\"\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\n\
         WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\n\
         Material \"matte\" \"rgb Kd\" [0 0 0]\nTranslate 0 0 -1000\n\
         Shape \"sphere\" \"float radius\" [1]\nWorldEnd\n",
        a = 1.0 - albedo,
        s = albedo
    );
    let (description, _) = loads(&text);
    let world = World::new(description).unwrap();
    let global = MapKind::Global { with_direct: false };
    let (map, volume, counts) =
        trace_map_within(&world, global, 200_000, None, 7, &ProgressBar::hidden());
    assert!(map.is_empty(), "no surface keeps photons: {}", map.len());
    assert_eq!(counts.stored as usize, volume.len());
    let power: f64 = volume.iter().map(|p| f64::from(p.power.x)).sum();
    let phi = 4.0 * std::f64::consts::PI;
    let want = phi * (albedo.powi(2) - albedo.powi(33)) / (1.0 - albedo);
    assert!((power / want - 1.0).abs() < 0.02, "{power} against {want}");
}

#[test]
fn a_media_scene_renders_the_same_on_one_thread_and_two() {
    let medium = "\"string type\" \"heterogeneous\" \"integer nx\" [2] \"integer ny\" [2] \
                  \"integer nz\" [2] \"float density\" [0.5 1 2 4 1 0.2 3 1] \
                  \"point p0\" [-1 -1 -1] \"point p1\" [1 1 1] \
                  \"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [2 2 2] \"float g\" [0.3]";
    let text = sphere_of(medium);
    let args = |threads| {
        vec![
            "--passes",
            "2",
            "--global-photons",
            "20000",
            "--threads",
            threads,
        ]
    };
    let one = render(&text, &args("1"));
    let two = render(&text, &args("2"));
    assert!(
        one.pixels
            .iter()
            .any(|p| (*p - Vec3::ONE).abs().max_element() > 0.05)
    );
    assert_eq!(one.pixels, two.pixels);
}

#[test]
fn the_memory_check_counts_volume_photons_and_grids() {
    let medium = "\"string type\" \"heterogeneous\" \"integer nx\" [2] \"float density\" [1 2] \
                  \"rgb sigma_a\" [0.5 0.5 0.5] \"rgb sigma_s\" [2 2 2]";
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.pbrt", &sphere_of(medium));
    let out = dir.path().join("scene.pfm");
    let args = [
        path_str(&path),
        "-o",
        path_str(&out),
        "--global-photons",
        "100000000000",
    ];
    let Err(e) = dpm::render::pipeline::run(&render_args(&args)) else {
        panic!("a hundred billion photons fit");
    };
    let message = e.to_string();
    let per = dpm::render::memory_budget::VOLUME_BYTES_PER_PHOTON;
    assert!(
        message.contains("the media's grids") && message.contains(&format!("{per} bytes a photon")),
        "{message}"
    );
    assert!(!out.exists());
}

#[test]
fn films_of_a_media_scene_merge_and_resume_into_one_runs_image() {
    let medium = "\"string type\" \"homogeneous\" \"rgb sigma_a\" [0.2 0.2 0.2] \
                  \"rgb sigma_s\" [1.5 1 0.5] \"float g\" [0.4]";
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "scene.pbrt", &sphere_of(medium));
    let d = |n: &str| dir.path().join(n);
    let run = |out: &str, extra: &[&str]| {
        let out = d(out);
        let mut args = vec![path_str(&scene), "-o", path_str(&out)];
        args.extend_from_slice(&["--global-photons", "20000"]);
        args.extend_from_slice(extra);
        dpm::render::pipeline::run(&render_args(&args)).unwrap()
    };
    let stats = d("stats.json");
    let whole = run("whole.pfm", &["--passes", "4", "--stats", path_str(&stats)]);
    // The media's and the volume maps' memory are reported, in the outcome and the stats.
    let text = std::fs::read_to_string(&stats).unwrap();
    let json: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert!(
        json["media_bytes"].as_u64().is_some_and(|b| b > 0),
        "{text}"
    );
    assert!(
        json["volume_maps"]["photons"]
            .as_u64()
            .is_some_and(|n| n > 0),
        "{text}"
    );
    assert_eq!(
        whole.media_bytes,
        json["media_bytes"].as_u64().map(|b| b as usize)
    );
    let (a, b) = (d("a.film"), d("b.film"));
    run("a.pfm", &["--passes", "2", "--film", path_str(&a)]);
    run(
        "b.pfm",
        &["--first-pass", "2", "--passes", "2", "--film", path_str(&b)],
    );
    let merge = dpm::render::merge::MergeArgs {
        films: vec![b.clone(), a.clone()],
        output: d("merged.pfm"),
        film: None,
        expect: None,
        exposure: 0.0,
        kernel_field: None,
    };
    let merged = dpm::render::merge::run(&merge).unwrap();
    assert!(max_relative_difference(whole.film.sums(), merged.film.sums()) <= 1e-6);
    let resumed = run("r.pfm", &["--resume", path_str(&a), "--passes", "2"]);
    assert!(max_relative_difference(whole.film.sums(), resumed.film.sums()) <= 1e-6);
}

#[test]
fn a_glossy_surface_in_an_absorbing_medium_sees_the_sky_dimmed_by_it() {
    // A rough metal ball at the centre of a sphere of absorbing fog (radius 10), the camera
    // in the fog 2.5 from the ball: the sky reflected back to the camera crosses 2.5 and about
    // 9.5 of fog, whether the glossy lobe found it by a shadow ray or by its own sample.
    let scene = |sigma: f32| {
        format!(
            "LookAt 0 0 3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [20]\n\
             Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [32]\n\
             WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n\
             MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \
             \"rgb sigma_a\" [{sigma} {sigma} {sigma}] \"rgb sigma_s\" [0 0 0]\n\
             AttributeBegin\nMediumInterface \"fog\" \"\"\nMaterial \"\"\n\
             Shape \"sphere\" \"float radius\" [10]\nAttributeEnd\n\
             AttributeBegin\nMediumInterface \"fog\" \"fog\"\n\
             Material \"metal\" \"float roughness\" [0.05]\n\
             Shape \"sphere\" \"float radius\" [0.5]\nAttributeEnd\n\
             MediumInterface \"\" \"fog\"\nWorldEnd\n"
        )
    };
    let args = [
        "--passes",
        "4",
        "--spp",
        "16",
        "--caustic-photons",
        "0",
        "--global-photons",
        "0",
    ];
    let clear = mean(&render(&scene(0.0), &args), 14, 18);
    let dimmed = mean(&render(&scene(0.02), &args), 14, 18);
    let want = (-0.02f32 * (2.5 + 9.5)).exp();
    for c in 0..3 {
        let ratio = dimmed[c] / clear[c];
        assert!(
            (ratio / want - 1.0).abs() < 0.015,
            "channel {c}: {ratio} against {want}"
        );
    }
}
