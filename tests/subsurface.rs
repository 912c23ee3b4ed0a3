//! pbrt's `subsurface` and `kdsubsurface` materials as a dielectric boundary over a
//! homogeneous medium: the coefficients each reads (a measured name's σ′s and g = 0, defaults,
//! `scale`, `kdsubsurface`'s inversion of its diffuse reflectance), bad values refused naming
//! their place, and rendered whole against the furnace: a lossless medium under an index-
//! matched or a real dielectric boundary, under a uniform sky, is seen as the sky, whatever
//! the scene's cap on bounces (a walk under the surface is not a bounce).

mod support;

use dpm::scene::{MediumKind, SceneDescription};
use glam::{DVec3, Vec3};
use support::pbrt::{load_text, world};
use support::*;

fn under_surface(material: &str) -> SceneDescription {
    let dir = tempfile::tempdir().unwrap();
    let text = world(&format!(
        "Material {material}\nShape \"sphere\" \"float radius\" [1]\n"
    ));
    load_text(dir.path(), &text)
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
        .0
}

fn coefficients(scene: &SceneDescription) -> (Vec3, Vec3, f32) {
    assert_eq!(scene.media.media.len(), 1);
    let medium = &scene.media.media[0];
    assert!(medium.subsurface);
    match medium.kind {
        MediumKind::Homogeneous { sigma_a, sigma_s } => (sigma_a, sigma_s, medium.g),
        _ => panic!("{medium:?}"),
    }
}

fn near(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() <= 1e-5 * b.abs().max_element().max(1.0)
}

#[test]
fn subsurface_materials_put_the_medium_pbrt_v3_reads_under_a_dielectric() {
    // A measured name: its σ′s as σs, g forced to 0; scale multiplies both.
    let scene = under_surface(
        "\"subsurface\" \"string name\" \"Ketchup\" \"float g\" [0.5] \"float scale\" [2]",
    );
    let (a, s, g) = coefficients(&scene);
    assert!(near(a, Vec3::new(0.061, 0.97, 1.45) * 2.0), "{a}");
    assert!(near(s, Vec3::new(0.18, 0.07, 0.03) * 2.0), "{s}");
    assert_eq!(g, 0.0);
    // The sphere's inside is that medium, its outside none.
    let interface = scene.media.shape_interfaces[0].1;
    assert_eq!((interface.inside, interface.outside), (Some(0), None));
    // Whole milk by default; g as given without a name.
    let (a, s, g) = coefficients(&under_surface("\"subsurface\" \"float g\" [0.3]"));
    assert!(near(a, Vec3::new(0.0011, 0.0024, 0.014)) && near(s, Vec3::new(2.55, 3.21, 3.77)));
    assert_eq!(g, 0.3);
    // kdsubsurface: σt = 1/(mfp·scale), and the albedo whose dipole reflectance is Kd.
    let (a, s, _) = coefficients(&under_surface(
        "\"kdsubsurface\" \"rgb Kd\" [0.2 0.5 0.8] \"rgb mfp\" [0.5 1 2] \"float scale\" [2]",
    ));
    let mfp = Vec3::new(1.0, 2.0, 4.0);
    assert!(near(a + s, Vec3::ONE / mfp), "{a} {s}");
    let albedo = s * mfp;
    let eta = 1.33;
    for (kd, alb) in [0.2, 0.5, 0.8].into_iter().zip(albedo.to_array()) {
        let back = dpm::scene::dipole::dipole_reflectance(alb, eta);
        assert!(
            (back - kd).abs() < 1e-4,
            "Kd {kd}: albedo {alb} reflects {back}"
        );
    }
    // Brighter Kd, higher albedo.
    assert!(albedo.x < albedo.y && albedo.y < albedo.z, "{albedo}");
}

#[test]
fn bad_subsurface_values_are_refused_naming_their_place() {
    for (body, field) in [
        ("\"subsurface\" \"rgb sigma_a\" [-1 0 0]", "sigma_a"),
        ("\"subsurface\" \"float g\" [1]", "g"),
        ("\"kdsubsurface\" \"rgb mfp\" [0 1 1]", "mfp"),
        ("\"kdsubsurface\" \"texture Kd\" \"checks\"", "Material"),
    ] {
        let dir = tempfile::tempdir().unwrap();
        let text = world(&format!(
            "Texture \"checks\" \"spectrum\" \"checkerboard\"\n\
             Material {body}\nShape \"sphere\" \"float radius\" [1]\n"
        ));
        let e = load_text(dir.path(), &text).unwrap_err();
        assert_eq!(e.line, Some(7), "{body}: {e}");
        assert!(e.field.contains(field), "{body}: {e}");
    }
}

/// A unit sphere of material `material` seen from 6 units away at 32 × 32 under a uniform
/// sky of radiance 1, its paths capped at `depth` surfaces.
fn furnace(material: &str, depth: u32) -> Vec3 {
    let text = format!(
        "Integrator \"path\" \"integer maxdepth\" [{depth}]\n\
         LookAt 0 0 6  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [25]\n\
         Film \"image\" \"integer xresolution\" [32] \"integer yresolution\" [32]\n\
         WorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n\
         Material {material}\nShape \"sphere\" \"float radius\" [1]\nWorldEnd\n"
    );
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.pbrt", &text);
    let out = dir.path().join("scene.pfm");
    // Nothing diffuse: the caustic pass's photons, refracted in, carry all the light.
    let global = "--global-photons";
    let args = [
        path_str(&path),
        "-o",
        path_str(&out),
        "--passes",
        "8",
        "--spp",
        "16",
        global,
        "0",
    ];
    let image = dpm::render::pipeline::run(&render_args(&args))
        .unwrap()
        .image;
    let mut sum = DVec3::ZERO;
    // The middle of the disc: towards its rim the chords are short and a photon's disc
    // reaches past the medium, a bias that shrinks with the radii.
    for y in 12..20 {
        for x in 12..20 {
            sum += image.pixels[y * image.width + x].as_dvec3();
        }
    }
    (sum / 64.0).as_vec3()
}

#[test]
fn a_lossless_medium_under_the_surface_is_seen_as_the_sky() {
    // Paths capped at 3 surfaces: a walk of many events under the surface, and its
    // reflections back in off the surface, must count as none. Index-matched (eta 1), then a
    // real boundary: inside, light trapped by total internal reflection is η² brighter, and
    // the eye outside must see it 1/η² as bright.
    for (eta, sigma, depth) in [(1.0, 3.0, 3), (1.33, 2.0, 3)] {
        let material = format!(
            "\"subsurface\" \"float eta\" [{eta}] \"rgb sigma_a\" [0 0 0] \
             \"rgb sigma_s\" [{sigma} {sigma} {sigma}]"
        );
        let seen = furnace(&material, depth);
        for c in seen.to_array() {
            assert!((c - 1.0).abs() < 0.025, "eta {eta}, σs {sigma}: {seen}");
        }
    }
}
