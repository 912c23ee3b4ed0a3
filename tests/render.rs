//! The Whitted eye pass, checked against closed-form answers: a diffuse plane under a point
//! light (every pixel of a `dpm render`), light seen through a glass sphere (the Fresnel series
//! of its internal reflections, traced here independently in f64) and in a mirror sphere, and
//! the render's independence of the thread count.

mod support;

use dpm::estimate::Scratch;
use dpm::render::integrator::Integrator;
use dpm::render::pipeline;
use dpm::sampling::{PathSampler, Rng, Stream};
use dpm::scene::Light;
use glam::DVec3;
use std::f64::consts::PI;
use support::eye::*;
use support::*;

// ---------------------------------------------------------------------------------------------
// 1. A diffuse plane under a point light
// ---------------------------------------------------------------------------------------------

/// Every pixel of a render of scenes/point-plane.toml equals `albedo/π · Φ/(4π) · cosθ / d²`
/// at the point its centre ray meets the plane, and pixels whose ray misses the plane are black.
/// The scene has one diffuse object and no mirror or glass, so the render builds no photon
/// map: the picture is direct light only, one exact shadow ray per pixel, with no noise. The
/// tolerance (1e-3, a tenth of the 1% asked) covers f32 rounding; the analytic value is taken
/// at the shading point, the hit lifted by the ray epsilon (2e-5 of the scene's diagonal),
/// as for every plane check ([`check_plane_pixels`]); worst error seen 9.4e-7.
#[test]
fn diffuse_plane_under_a_point_light_has_the_analytic_radiance() {
    let text = scene_with_resolution("scenes/point-plane.toml", 64, 48);
    let (outcome, desc) = render_scene(&text, &[]);
    assert!(outcome.caustic.is_none() && outcome.global.is_none());
    let Light::Point { position, power } = desc.lights[0] else {
        panic!("point-plane has a point light")
    };
    let (light, phi) = (dvec(position), dvec(power));
    let check = check_plane_pixels(
        &outcome.image,
        &desc,
        |p| {
            let to_light = light - p;
            let d2 = to_light.length_squared();
            let cos = to_light.y / d2.sqrt();
            (PLANE_ALBEDO / PI * phi / (4.0 * PI) * cos / d2, None)
        },
        |_, _| None,
        DVec3::ZERO,
        1e-3,
    );
    eprintln!(
        "worst relative error {:.2e} over {} pixels",
        check.worst, check.on_plane
    );
}

/// `--resolution WxH` renders the scene at that size with its own vertical field of view: the
/// same pixels as the scene file with that `resolution`.
#[test]
fn the_resolution_flag_overrides_the_scenes_keeping_its_field_of_view() {
    let file = scene_with_resolution("scenes/point-plane.toml", 64, 48);
    let (flagged, desc) = render_scene(&file, &["--resolution", "40x20"]);
    let (written, _) = render_scene(
        &scene_with_resolution("scenes/point-plane.toml", 40, 20),
        &[],
    );
    assert_eq!((flagged.image.width, flagged.image.height), (40, 20));
    assert_eq!(flagged.image, written.image);
    assert_eq!(
        (desc.camera.width, desc.camera.height),
        (64, 48),
        "the file is unchanged"
    );
}

// ---------------------------------------------------------------------------------------------
// 2. Glass and mirror spheres in front of a large emitter
// ---------------------------------------------------------------------------------------------

/// Light seen through a glass sphere (ior 1.5): straight through the centre, the radiance is
/// the emitter's times (1 − R)/(1 + R) (R = 0.04: 0.923077) with a deep recursion, and times
/// exactly (1 − R)² = 0.9216 when the recursion stops before the first internal reflection
/// comes back out (max_depth 2 or 3), and zero with max_depth 1. Off the centre, at impact
/// parameters up to 0.97 radii, the radiance equals the Fresnel series traced above (entry
/// reflection included when it reaches the light). No sampling is involved, so the tolerance
/// is 2e-4 of the emitter's radiance (errors seen: ≤ 6e-5), well below the 0.15% that separates
/// max_depth 2 from 10 at the centre; at b = 0.97 (76° incidence, where the reflectance is
/// steep) 1e-3 (seen: 2.6e-4), since the ray offset, 2e-5 of the scene's 141-unit diagonal,
/// and f32 rounding move the grazing hits a little.
#[test]
fn glass_sphere_transmits_the_fresnel_series() {
    let world = world(&sphere_scene("glass"));
    let le = emitter_radiance();
    let r0 = ((IOR - 1.0) / (IOR + 1.0)).powi(2);
    // The model reproduces the closed forms at the centre.
    assert!((glass_sphere_radiance(0.0, 2) - (1.0 - r0).powi(2)).abs() < 1e-12);
    assert!((glass_sphere_radiance(0.0, 40) - (1.0 - r0) / (1.0 + r0)).abs() < 1e-12);

    for max_depth in [0u32, 1, 2, 3, 4, 5, 10] {
        let integrator = whitted(&world, max_depth);
        for b in [0.0, 0.1, 0.3, 0.5, 0.6, 0.7, 0.8, 0.9, 0.97] {
            let want = glass_sphere_radiance(b, max_depth);
            let got = radiance_along(&integrator, DVec3::new(b, 0.0, 10.0), DVec3::NEG_Z);
            let tolerance = if b > 0.95 { 1e-3 } else { 2e-4 };
            for c in 0..3 {
                let w = want * le[c];
                assert!(
                    (got[c] - w).abs() <= tolerance * le[c],
                    "b = {b}, max_depth = {max_depth}, channel {c}: {} vs {} (ratio {} vs {want})",
                    got[c],
                    w,
                    got[c] / le[c]
                );
            }
        }
    }
    // The centre ray, named: 0.9216 (one pass) and 0.923077 (all passes).
    let through = |depth| {
        radiance_along(
            &whitted(&world, depth),
            DVec3::new(0.0, 0.0, 10.0),
            DVec3::NEG_Z,
        )
        .x / le.x
    };
    assert!((through(2) - 0.9216).abs() < 2e-4, "{}", through(2));
    assert!((through(10) - 0.96 / 1.04).abs() < 2e-4, "{}", through(10));
    assert!(
        through(10) - through(2) > 0.001,
        "internal reflections add light"
    );
}

/// Past `glass_split_depth` an eye path follows one ray at each glass hit, reflection with
/// probability F: the mean over many paths is the same Fresnel series the split tracer sums.
/// 40,000 paths at each of three impact parameters; each path brings back the emitter's
/// radiance or nothing, so the mean's standard deviation is at most 0.25% of the emitter's.
#[test]
fn sampled_glass_paths_average_to_the_fresnel_series() {
    let world = world(&sphere_scene("glass"));
    let le = emitter_radiance();
    for split in [0u32, 1] {
        let integrator = Integrator {
            glass_split_depth: split,
            ..whitted(&world, 10)
        };
        for b in [0.0, 0.5, 0.9] {
            let want = glass_sphere_radiance(b, 10);
            let paths = 40_000;
            let mut sum = 0.0;
            let mut scratch = Scratch::default();
            for i in 0..paths {
                let mut sampler = PathSampler::new(Rng::for_index(7, Stream::Pixels, i), None);
                let l = integrator.radiance(
                    DVec3::new(b, 0.0, 10.0).as_vec3(),
                    DVec3::NEG_Z.as_vec3(),
                    0,
                    &mut sampler,
                    &mut scratch,
                );
                sum += l.total().x as f64 / le.x;
            }
            let mean = sum / paths as f64;
            assert!(
                (mean - want).abs() < 0.01,
                "split {split}, b = {b}: {mean} vs {want}"
            );
        }
    }
}

/// The centre pixel of a `dpm render` (odd resolution: its centre ray is the optical axis)
/// through the glass sphere shows (1 − R)/(1 + R) of the emitter, and a corner pixel, which
/// sees the emitter directly past the sphere, shows the emitter's radiance Φ / (πA) exactly.
#[test]
fn rendered_glass_sphere_centre_pixel() {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "glass.toml", &sphere_scene("glass"));
    let out = dir.path().join("glass.pfm");
    let args = render_args(&[
        path_str(&scene),
        "-o",
        path_str(&out),
        "--threads",
        "2",
        "--caustic-photons",
        "0",
        // The Whitted camera sample's exact value (emission samples sample the glass).
        "--emission-samples",
        "0",
    ]);
    let image = pipeline::run(&args).expect("render").image;
    let le = emitter_radiance();
    let centre = dvec(image.get(16, 16));
    let corner = dvec(image.get(0, 0));
    for c in 0..3 {
        assert!(
            rel_err(centre[c], le[c] * 0.96 / 1.04) < 2e-4,
            "{centre} vs {le}"
        );
        assert!(rel_err(corner[c], le[c]) < 1e-5, "{corner} vs {le}");
    }
}

/// Seen in a perfect mirror the emitter keeps its radiance: rays that reflect off the mirror
/// sphere towards the emitter (impact parameter b > 1/√2, where the reflection turns forward)
/// carry exactly Φ / (πA); those that reflect backwards see black; with max_depth 0 the mirror
/// is black. Tolerance 1e-5 relative: no sampling, no Fresnel, only f32 rounding.
#[test]
fn mirror_sphere_reflects_the_emitter_unchanged() {
    let world = world(&sphere_scene("chrome"));
    let le = emitter_radiance();
    let deep = whitted(&world, 10);
    let none = whitted(&world, 0);
    let mut seen = 0;
    for b in [0.0, 0.3, 0.6, 0.69, 0.72, 0.8, 0.9, 0.95, 0.99] {
        let o = DVec3::new(0.0, b, 10.0);
        let x = DVec3::new(0.0, b, (1.0 - b * b).sqrt());
        let want = if hits_light(x, reflect(DVec3::NEG_Z, x)) {
            seen += 1;
            le
        } else {
            DVec3::ZERO
        };
        let got = radiance_along(&deep, o, DVec3::NEG_Z);
        assert!(
            (got - want).abs().max_element() <= 1e-5 * le.max_element(),
            "b = {b}: {got} vs {want}"
        );
        assert_eq!(radiance_along(&none, o, DVec3::NEG_Z), DVec3::ZERO);
    }
    assert!(seen >= 4, "several rays see the emitter in the mirror");
}

// ---------------------------------------------------------------------------------------------
// 3. The render does not depend on the thread count
// ---------------------------------------------------------------------------------------------

/// Renders `text` at two thread counts and two seeds; returns the PFM bytes of (1 thread, seed
/// 7), (2 threads, seed 7), (2 threads, seed 8).
fn renders_for_determinism(text: &str) -> [(Vec<u8>, pipeline::RenderOutcome); 3] {
    let dir = tempfile::tempdir().unwrap();
    let scene = write_scene(dir.path(), "cornell.toml", text);
    let render = |threads: &str, seed: &str| {
        let out = dir.path().join(format!("t{threads}-s{seed}.pfm"));
        let args = render_args(&[
            path_str(&scene),
            "-o",
            path_str(&out),
            "--threads",
            threads,
            "--seed",
            seed,
            "--spp",
            "2",
            "--caustic-photons",
            "3000",
            "--global-photons",
            "3000",
            "--final-gather",
            "4",
            "--k",
            "100",
        ]);
        let outcome = pipeline::run(&args).expect("render");
        (std::fs::read(&out).expect("output"), outcome)
    };
    [render("1", "7"), render("2", "7"), render("2", "8")]
}

fn assert_deterministic(text: &str) {
    let [(one, o1), (two, o2), (other, o3)] = renders_for_determinism(text);
    for o in [&o1, &o2, &o3] {
        assert_eq!(
            o.caustic.map(|c| c.stored),
            Some(3000),
            "caustic map filled"
        );
        assert_eq!(o.global.map(|c| c.stored), Some(3000), "global map filled");
        assert!(o.estimator.is_some(), "the caustic estimate ran");
    }
    assert_eq!(o1.caustic, o2.caustic);
    assert_eq!(o1.global, o2.global);
    assert!(one == two, "1 and 2 threads wrote different bytes");
    assert_eq!(o1.image, o2.image);
    assert!(one != other, "seeds 7 and 8 gave the same image");
    assert!(o1.image.pixels.iter().all(|p| p.is_finite()));
}

/// The Cornell box (mirror and glass: a caustic map with the diffusion estimate; five diffuse
/// walls: a global map with final gathering; 2 samples per pixel), lit by a point light, gives
/// the same PFM bytes on 1 and 2 threads, and another seed gives another image.
#[test]
fn same_seed_same_bytes_on_one_and_two_threads() {
    assert_deterministic(&cornell_point_light(24, 20));
}

/// The same with the committed Cornell box and its quad light.
#[test]
fn same_seed_same_bytes_on_one_and_two_threads_committed_cornell_box() {
    assert_deterministic(&scene_with_resolution("scenes/cornell-box.toml", 24, 20));
}

#[test]
fn stats_name_the_embree_in_use() {
    let dir = tempfile::tempdir().unwrap();
    let text = scene_with_resolution("scenes/point-plane.toml", 8, 6);
    let scene = write_scene(dir.path(), "plane.toml", &text);
    let (out, stats) = (dir.path().join("plane.pfm"), dir.path().join("stats.json"));
    let args = render_args(&[
        path_str(&scene),
        "-o",
        path_str(&out),
        "--stats",
        path_str(&stats),
    ]);
    pipeline::run(&args).expect("render");
    let text = std::fs::read_to_string(&stats).expect("the stats file");
    let json: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let embree = json["embree"].as_str().expect("an \"embree\" field");
    let backend = if cfg!(feature = "embree4") {
        "Embree 4."
    } else {
        "Embree 3."
    };
    assert!(embree.starts_with(backend), "{embree}");
    assert_eq!(embree, dpm::embree::version_string());
}
