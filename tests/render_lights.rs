//! The eye pass with the lights pbrt scenes bring (spot, distant, environment, mesh emitter)
//! and with tinted mirrors and glass, checked against closed forms: every pixel of a diffuse
//! plane under each light, what an escaping ray and a visible mesh emitter show, the
//! irradiance under a mesh square against a rectangle's form factor and the quad light of the
//! same shape, and the Fresnel series of tinted glass.

mod support;

use dpm::estimate::Scratch;
use dpm::render::integrator::Integrator;
use dpm::sampling::{PathSampler, Rng, Stream};
use glam::DVec3;
use std::f64::consts::PI;
use support::eye::*;
use support::*;

// ---------------------------------------------------------------------------------------------
// 1. A diffuse plane under a spot, a distant light and the environment
// ---------------------------------------------------------------------------------------------

/// A spot's factor, written here from pbrt's definitions (not the crate's).
fn spot_factor(falloff: &str, cos_theta: f64, cos_cone: f64, cos_start: f64) -> f64 {
    if cos_theta >= cos_start {
        return 1.0;
    }
    if cos_theta <= cos_cone {
        return 0.0;
    }
    let t = (cos_theta - cos_cone) / (cos_start - cos_cone);
    match falloff {
        "smoothstep" => t * t * (3.0 - 2.0 * t),
        _ => t.powi(4),
    }
}

/// A spot light tilted over the plane, its cone's edge on the plane: every pixel equals
/// albedo/π · I f(θ) cos θ' / d² at the shading point, I = Φ / (2π ∫ f dμ) with the integral in
/// closed form (smoothstep: 1 − (cos α + cos β)/2; quartic: (1 − cos β) + (cos β − cos α)/5),
/// within 1e-3 relative where f ≥ 0.05 and within 1e-3 of the on-axis radiance where the factor
/// is smaller (near the cone's edge a relative check would measure f32's cosines); outside the
/// cone the plane is black. One exact shadow ray per pixel: no noise.
#[test]
fn diffuse_plane_under_a_spot_light_has_the_analytic_radiance() {
    let (alpha, beta) = (40.0f64, 25.0f64);
    let position = DVec3::new(0.0, 1.0, 0.0);
    let axis = DVec3::new(0.3, -1.0, 0.0).normalize();
    let power = DVec3::new(100.0, 60.0, 30.0);
    for falloff in ["smoothstep", "quartic"] {
        let light = format!(
            "[[lights]]\ntype = \"spot\"\nposition = [0.0, 1.0, 0.0]\ndirection = [0.3, -1.0, 0.0]\n\
             cone_angle = {alpha}\nfalloff_start = {beta}\nfalloff = \"{falloff}\"\npower = [100.0, 60.0, 30.0]"
        );
        let (outcome, desc) = render_scene(&plane_scene(&light, 64, 48), &[]);
        let (cos_a, cos_b) = (alpha.to_radians().cos(), beta.to_radians().cos());
        let band = if falloff == "smoothstep" { 0.5 } else { 0.2 };
        let intensity = power / (2.0 * PI * ((1.0 - cos_b) + (cos_b - cos_a) * band));
        // The radiance straight under the light at 1 m: the scale of the absolute bound.
        let scale = PLANE_ALBEDO / PI * intensity.max_element();
        let (mut dark, mut band_pixels) = (0, 0);
        let check = check_plane_pixels(
            &outcome.image,
            &desc,
            |p| {
                let to_light = position - p;
                let d = to_light.length();
                let f = spot_factor(falloff, -to_light.dot(axis) / d, cos_a, cos_b);
                let e = intensity * f * (to_light.y / d) / (d * d);
                let bound = if f < 0.05 {
                    dark += 1;
                    Some(1e-3 * scale)
                } else {
                    band_pixels += usize::from(f < 1.0);
                    None
                };
                (PLANE_ALBEDO / PI * e, bound)
            },
            |_, _| None,
            DVec3::ZERO,
            1e-3,
        );
        assert!(
            dark > 100 && band_pixels > 100,
            "{falloff}: {dark} dark, {band_pixels} in the band"
        );
        eprintln!(
            "{falloff}: worst relative error {:.2e} over {:?}",
            check.worst, check
        );
    }
}

/// Parallel light of irradiance E arriving 36.9° from the plane's normal: every pixel of the
/// plane shows albedo/π · E cos θ, and nothing else is lit.
#[test]
fn diffuse_plane_under_a_distant_light_has_the_analytic_radiance() {
    let light = "[[lights]]\ntype = \"distant\"\ndirection = [0.6, -0.8, 0.0]\nirradiance = [2.0, 1.0, 0.5]";
    let (outcome, desc) = render_scene(&plane_scene(light, 64, 48), &[]);
    let e = DVec3::new(2.0, 1.0, 0.5) * 0.8;
    let check = check_plane_pixels(
        &outcome.image,
        &desc,
        |_| (PLANE_ALBEDO / PI * e, None),
        |_, _| None,
        DVec3::ZERO,
        1e-3,
    );
    eprintln!("distant: worst relative error {:.2e}", check.worst);
}

/// Under a constant environment of radiance L with nothing else in the scene the plane's
/// irradiance is π L everywhere, so it shows albedo · L, from one cosine-weighted shadow ray a
/// pixel as from 16; every ray that misses the plane escapes and shows L.
#[test]
fn diffuse_plane_under_the_environment_has_irradiance_pi_l() {
    let radiance = DVec3::new(0.5, 0.25, 1.0);
    let light = "[[lights]]\ntype = \"environment\"\nradiance = [0.5, 0.25, 1.0]";
    for samples in ["1", "16"] {
        let (outcome, desc) =
            // Each pixel checked at its camera sample: the sky is not sampled apart.
            render_scene(
                &plane_scene(light, 64, 48),
                &["--light-samples", samples, "--emission-samples", "0"],
            );
        assert!(outcome.caustic.is_none() && outcome.global.is_none());
        let check = check_plane_pixels(
            &outcome.image,
            &desc,
            |_| (PLANE_ALBEDO * radiance, None),
            |_, _| None,
            radiance,
            1e-3,
        );
        eprintln!(
            "environment, {samples} samples: worst relative error {:.2e}",
            check.worst
        );
    }
}

// ---------------------------------------------------------------------------------------------
// 2. A mesh emitter
// ---------------------------------------------------------------------------------------------

/// A 1 × 1 square in the xz plane, centred on the origin, wound so that its normal is -y.
const SQUARE_OBJ: &str =
    "v -0.5 0 -0.5\nv 0.5 0 -0.5\nv 0.5 0 0.5\nv -0.5 0 0.5\nf 1 2 3\nf 1 3 4\n";

/// The square scaled to 2 × 2 and lifted to y = 1 (facing down at the plane), Φ = 40 W.
fn mesh_light(obj: &std::path::Path, two_sided: bool) -> String {
    format!(
        "[[lights]]\ntype = \"mesh\"\nfile = \"{}\"\nscale = 2.0\ntranslate = [0.0, 1.0, 0.0]\n\
         power = [40.0, 40.0, 40.0]\ntwo_sided = {two_sided}",
        obj.display()
    )
}

/// Whether a camera ray meets the 2 × 2 emitter at y = 1 (before the plane, from above).
fn meets_the_emitter(o: DVec3, d: DVec3) -> bool {
    hit_parallelogram(
        o,
        d,
        DVec3::new(-1.0, 1.0, -1.0),
        DVec3::new(2.0, 0.0, 0.0),
        DVec3::new(0.0, 0.0, 2.0),
    )
    .is_some()
}

/// Under a 2 × 2 mesh emitter of radiance L = Φ/(πA), 1 above the plane, the irradiance is L
/// times π × the form factor of the rectangle (closed form, summed over its corners); with 256
/// stratified shadow rays a pixel, each pixel is within 1.5% of it (worst seen: 0.84%, at the
/// plane's far corners, where the emitter is small and grazing), and so is the render with the
/// quad light of the same shape (worst seen 0.52%); the two images' means agree to 0.1%. Seen
/// from above, the emitter's back is black; a two-sided one of twice the power shows the
/// same L on both sides.
#[test]
fn irradiance_under_a_mesh_emitter_matches_the_rectangle_and_the_quad_light() {
    // The formula's limits: a huge rectangle gives π (the whole hemisphere), a far one nothing.
    assert!((rectangle_irradiance(1.0, -1e6, 1e6, -1e6, 1e6) - PI).abs() < 1e-5);
    assert!(rectangle_irradiance(1.0, 1e3, 1e3 + 1.0, 0.0, 1.0) < 1e-8);

    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("square.obj");
    std::fs::write(&obj, SQUARE_OBJ).unwrap();
    let quad = "[[lights]]\ntype = \"quad\"\ncorner = [-1.0, 1.0, -1.0]\nedge_u = [2.0, 0.0, 0.0]\n\
                edge_v = [0.0, 0.0, 2.0]\npower = [40.0, 40.0, 40.0]";
    let radiance = 40.0 / (PI * 4.0);
    // Pixels checked at their camera sample: the emitter they see is not sampled apart.
    let samples = ["--light-samples", "256", "--emission-samples", "0"];
    let mut means = Vec::new();
    for (what, light, back) in [
        ("mesh", mesh_light(&obj, false), 0.0),
        (
            "two-sided mesh, doubled power",
            mesh_light(&obj, true).replace("40.0", "80.0"),
            1.0,
        ),
        ("quad", quad.to_string(), 0.0),
    ] {
        let (outcome, desc) = render_scene(&plane_scene(&light, 64, 48), &samples);
        let check = check_plane_pixels(
            &outcome.image,
            &desc,
            |p| {
                let h = 1.0 - p.y;
                let e = radiance
                    * rectangle_irradiance(h, -1.0 - p.x, 1.0 - p.x, -1.0 - p.z, 1.0 - p.z);
                (DVec3::splat(PLANE_ALBEDO / PI * e), None)
            },
            |o, d| meets_the_emitter(o, d).then_some(DVec3::splat(back * radiance)),
            DVec3::ZERO,
            1.5e-2,
        );
        assert!(
            check.in_front > 100,
            "{what}: the emitter is in view: {check:?}"
        );
        let mean: f64 = outcome.image.pixels.iter().map(|p| p.x as f64).sum::<f64>()
            / outcome.image.pixels.len() as f64;
        means.push(mean);
        eprintln!(
            "{what}: worst relative error {:.2e} over {check:?}",
            check.worst
        );
    }
    let (mesh, quad) = (means[0], means[2]);
    eprintln!(
        "image means: mesh {mesh}, quad {quad}, relative difference {:.2e}",
        rel_err(mesh, quad)
    );
    assert!(rel_err(mesh, quad) < 1e-3, "mesh {mesh} vs quad {quad}");
}

/// Looking up at a mesh emitter from under it: every pixel that sees it shows Φ / (π A)
/// exactly, (Φ / (2π A) when two-sided), and the pixels past it see black.
#[test]
fn a_visible_mesh_emitter_shows_power_over_pi_area() {
    let dir = tempfile::tempdir().unwrap();
    let obj = dir.path().join("square.obj");
    std::fs::write(&obj, SQUARE_OBJ).unwrap();
    for two_sided in [false, true] {
        let text = plane_scene(&mesh_light(&obj, two_sided), 32, 32)
            .replace("position = [0.0, 2.5, 3.0]", "position = [0.3, 0.1, 0.2]")
            .replace("look_at = [0.0, 0.0, 0.0]", "look_at = [0.3, 1.0, 0.2]")
            .replace("up = [0.0, 1.0, 0.0]", "up = [0.0, 0.0, 1.0]")
            .replace("fov_y = 45.0", "fov_y = 120.0");
        // Whole pixels, lit or dark, from one camera sample each (the emitter's edge pixels
        // would mix both under emission samples).
        let (outcome, _) = render_scene(&text, &["--emission-samples", "0"]);
        let sides = if two_sided { 2.0 } else { 1.0 };
        let want = 40.0 / (sides * PI * 4.0);
        let (mut lit, mut dark) = (0, 0);
        for p in &outcome.image.pixels {
            if p.x == 0.0 {
                dark += 1;
            } else {
                lit += 1;
                assert!(rel_err(p.x as f64, want) < 1e-5, "{p} vs {want}");
            }
        }
        assert!(lit > 300 && dark > 50, "{lit} lit, {dark} dark");
    }
}

// ---------------------------------------------------------------------------------------------
// 3. Tinted mirrors and glass
// ---------------------------------------------------------------------------------------------

/// A mirror tinted [0.5, 1, 1] shows the emitter with its red halved, exactly, wherever the
/// untinted mirror shows it.
#[test]
fn a_tinted_mirror_halves_the_red_it_reflects() {
    let clear = world(&sphere_scene("chrome"));
    let tinted = world(&sphere_scene("red_halving_chrome"));
    let mut seen = 0;
    for b in [0.0, 0.3, 0.72, 0.8, 0.9, 0.95] {
        let o = DVec3::new(0.0, b, 10.0);
        let plain = radiance_along(&whitted(&clear, 10), o, DVec3::NEG_Z);
        let got = radiance_along(&whitted(&tinted, 10), o, DVec3::NEG_Z);
        seen += usize::from(plain.x > 0.0);
        assert_eq!(got, plain * DVec3::new(0.5, 1.0, 1.0), "b = {b}");
    }
    assert!(seen >= 3);
}

/// Glass whose reflections (or transmissions) halve the red: the red channel follows the
/// Fresnel series with every reflection (or every crossing of the surface) times 0.5, the
/// green and blue the untinted series, at every impact parameter and depth, splitting every
/// hit (tolerances as for clear glass, tests/render.rs); past `glass_split_depth` the mean of
/// 40,000 sampled paths matches the series too (each path brings back a tint product of the
/// emitter or nothing: σ ≤ 0.25% of the emitter).
#[test]
fn tinted_glass_scales_each_branch_by_its_tint() {
    let le = emitter_radiance();
    for (material, reflect_tint, transmit_tint) in [
        ("red_halving_reflection", 0.5, 1.0),
        ("red_halving_transmission", 1.0, 0.5),
    ] {
        let world = world(&sphere_scene(material));
        for max_depth in [1u32, 2, 3, 10] {
            let integrator = whitted(&world, max_depth);
            for b in [0.0, 0.3, 0.6, 0.8, 0.9] {
                let got = radiance_along(&integrator, DVec3::new(b, 0.0, 10.0), DVec3::NEG_Z);
                let red = tinted_glass_sphere_radiance(b, max_depth, reflect_tint, transmit_tint);
                let clear = glass_sphere_radiance(b, max_depth);
                for (c, want) in [(0, red), (1, clear), (2, clear)] {
                    assert!(
                        (got[c] / le[c] - want).abs() <= 2e-4,
                        "{material}, b = {b}, depth {max_depth}, channel {c}: {} vs {want}",
                        got[c] / le[c]
                    );
                }
            }
        }
        let sampled = Integrator {
            glass_split_depth: 0,
            ..whitted(&world, 10)
        };
        for b in [0.0, 0.5, 0.9] {
            let paths = 40_000;
            let mut scratch = Scratch::default();
            let mut sum = DVec3::ZERO;
            for i in 0..paths {
                let mut sampler = PathSampler::new(Rng::for_index(7, Stream::Pixels, i), None);
                let l = sampled.radiance(
                    DVec3::new(b, 0.0, 10.0).as_vec3(),
                    DVec3::NEG_Z.as_vec3(),
                    0,
                    &mut sampler,
                    &mut scratch,
                );
                sum += dvec(l.total()) / le;
            }
            let mean = sum / paths as f64;
            let red = tinted_glass_sphere_radiance(b, 10, reflect_tint, transmit_tint);
            assert!(
                (mean.x - red).abs() < 0.01,
                "{material}, b = {b}: {} vs {red}",
                mean.x
            );
            assert!((mean.y - glass_sphere_radiance(b, 10)).abs() < 0.01);
        }
    }
}
