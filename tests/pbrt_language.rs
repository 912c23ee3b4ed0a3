//! pbrt's language as pbrt reads it, and what its files say about colour and the film:
//! `Include` splices tokens (a parameter list runs on after it), a parameter given twice keeps
//! its last value with a warning naming both places, pbrt-v4's `Attribute` defaults hold
//! within their scope, media are ignored with one warning, blackbody emission becomes the
//! linear sRGB of Planck's law in either dialect's normalisation, and the film's scale,
//! imaging ratio and white balance reach the written image (and nothing else changes it).

mod support;

use dpm::render::pipeline;
use dpm::scene::{self, Light, Material};
use dpm::spectrum;
use glam::{DVec3, Vec3};
use std::f32::consts::PI;
use support::pbrt::{CAMERA, load_text, loads, spheres, world};
use support::{path_str, render_args, write_scene};

const LUMINANCE: Vec3 = Vec3::new(0.212_672_9, 0.715_152_2, 0.072_175);

fn point_power(scene: &scene::SceneDescription) -> Vec3 {
    match scene.lights[0] {
        Light::Point { power, .. } => power,
        ref other => panic!("not a point light: {other:?}"),
    }
}

#[test]
fn include_splices_its_tokens_so_a_parameter_list_runs_on_after_it() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        "head.pbrt",
        "Translate 0 1 0\nShape \"sphere\"\n",
    );
    let text = world("Include \"head.pbrt\"\n  \"float radius\" 2.5\nShape \"sphere\"\n");
    let (scene, _) = load_text(dir.path(), &text).unwrap();
    let s = spheres(&scene);
    assert_eq!(s.len(), 2, "{s:?}");
    assert_eq!(s[0].1, 2.5, "the parameter after Include is the sphere's");
    assert_eq!(s[1].1, 1.0);
    // An error in a parameter that follows the Include names the including file's line.
    let text = world("Include \"head.pbrt\"\n  \"float radius\" [1 2]\n");
    let err = load_text(dir.path(), &text).unwrap_err().to_string();
    assert!(err.contains("scene.pbrt:7:3"), "{err}");
    // One inside the included file names that file's line and column.
    let broken = "Shape \"sphere\"\n \"float radius\" [1 Shape]";
    write_scene(dir.path(), "broken.pbrt", broken);
    let text = world("Include \"broken.pbrt\"\n");
    let err = load_text(dir.path(), &text).unwrap_err().to_string();
    assert!(
        err.contains("broken.pbrt:2:20") && err.contains("unexpected"),
        "{err}"
    );
    // A value list the included file leaves open runs on into the including file.
    write_scene(
        dir.path(),
        "open.pbrt",
        "Shape \"sphere\"\n \"float radius\" [",
    );
    let text = world("Include \"open.pbrt\"\n 0.75 ]\n");
    let (scene, _) = load_text(dir.path(), &text).unwrap();
    assert_eq!(spheres(&scene)[0].1, 0.75);
}

#[test]
fn a_parameter_given_twice_keeps_its_last_value_and_warns_naming_both_places() {
    let (scene, report) = loads(&world(
        "Shape \"sphere\" \"float radius\" 1 \"float radius\" 3\n",
    ));
    assert_eq!(spheres(&scene)[0].1, 3.0);
    let warning = report
        .warnings
        .iter()
        .find(|w| w.contains("given again"))
        .unwrap_or_else(|| panic!("{:?}", report.warnings));
    assert!(
        warning.contains("scene.pbrt:6:16") && warning.contains("scene.pbrt:6:33"),
        "{warning}"
    );
    // rgb and spectrum are one kind (spectra): the last stands.
    let (scene, _) = loads(&world(
        "Material \"matte\" \"rgb Kd\" [0.9 0.9 0.9] \"spectrum Kd\" 0.3\nShape \"sphere\"\n",
    ));
    assert_eq!(
        scene.materials[0],
        Material::Diffuse {
            albedo: Vec3::splat(0.3)
        }
    );
    // A texture and an rgb of one name both stand, and pbrt reads the texture first.
    let dir = tempfile::tempdir().unwrap();
    let text = world(
        "Material \"matte\" \"texture Kd\" \"checks\" \"rgb Kd\" [0.5 0.5 0.5]\nShape \"sphere\"\n",
    );
    let err = load_text(dir.path(), &text).unwrap_err().to_string();
    assert!(err.contains("no texture is named \"checks\""), "{err}");
    let (scene, _) = loads(&world(
        "Texture \"checks\" \"spectrum\" \"checkerboard\"\n\
         Material \"matte\" \"texture Kd\" \"checks\" \"rgb Kd\" [0.5 0.5 0.5]\nShape \"sphere\"\n",
    ));
    assert_eq!(scene.textured_materials.len(), 1);
}

#[test]
fn attribute_defaults_hold_for_their_kind_within_their_scope() {
    let (scene, report) = loads(&format!(
        "{CAMERA}WorldBegin\nAttributeBegin\n\
         Attribute \"light\" \"rgb I\" [1 2 3]\nLightSource \"point\" \"point from\" [0 3 0]\n\
         Attribute \"shape\" \"float radius\" 0.25\n\
         Attribute \"material\" \"rgb reflectance\" [0.2 0.2 0.2]\nMaterial \"diffuse\"\n\
         Shape \"sphere\"\nShape \"sphere\" \"float radius\" 2\nAttributeEnd\n\
         Material \"diffuse\"\nShape \"sphere\"\n"
    ));
    let radii: Vec<f32> = spheres(&scene).iter().map(|s| s.1).collect();
    assert_eq!(radii, [0.25, 2.0, 1.0]);
    assert!(
        (point_power(&scene) - Vec3::new(1.0, 2.0, 3.0) * 4.0 * PI).length() < 1e-4,
        "{:?}",
        point_power(&scene)
    );
    assert_eq!(
        scene.materials[0],
        Material::Diffuse {
            albedo: Vec3::splat(0.2)
        }
    );
    assert_eq!(
        scene.materials[1],
        Material::Diffuse {
            albedo: Vec3::splat(0.5)
        }
    );
    assert!(
        report.notes.iter().any(|n| n.contains("pbrt-v4")),
        "{report:?}"
    );
}

#[test]
fn media_are_placed_where_pbrt_places_them_camera_lights_and_shapes() {
    // pbrt-v3 takes the camera's medium at WorldEnd (the outside of the interface then in
    // force), a light the outside medium where it is declared, a shape both sides.
    let text = "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1]\n\
        MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\"\n\
        LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
        MediumInterface \"\" \"fog\"\nLightSource \"point\" \"rgb I\" [1 1 1]\n\
        AttributeBegin\nMediumInterface \"smoke\" \"fog\"\nMaterial \"glass\"\n\
        Shape \"sphere\"\nAttributeEnd\nMaterial \"matte\"\nShape \"sphere\" \"float radius\" 0.1\n\
        WorldEnd\n";
    let (scene, report) = loads(text);
    let media = &scene.media;
    assert_eq!(media.media.len(), 2);
    assert!(
        !report.warnings.iter().any(|w| w.contains("media")),
        "{:?}",
        report.warnings
    );
    assert_eq!(media.camera, Some(0), "fog is in force at WorldEnd");
    assert_eq!(media.light_media, vec![(0, 0)]);
    let sides = scene::MediumInterface {
        inside: Some(1),
        outside: Some(0),
    };
    // The matte sphere takes the world's "" "fog": vacuum inside it, as in pbrt.
    let hollow = scene::MediumInterface {
        inside: None,
        outside: Some(0),
    };
    assert_eq!(media.shape_interfaces, vec![(0, sides), (1, hollow)]);
    // pbrt-v4 takes the camera's medium at `Camera`, where none is in force here.
    let v4 = text.replace("\"glass\"", "\"dielectric\"");
    assert_eq!(loads(&v4).0.media.camera, None);
    let v4 = v4.replace("LookAt", "MediumInterface \"\" \"smoke\"\nLookAt");
    assert_eq!(loads(&v4).0.media.camera, Some(1));
}

#[test]
fn a_shape_that_only_bounds_a_medium_is_a_boundary_not_a_surface() {
    let body = "MakeNamedMedium \"smoke\" \"string type\" \"homogeneous\"\n\
        Shape \"sphere\" \"float radius\" 0.3\nAttributeBegin\nMaterial \"\"\n\
        MediumInterface \"smoke\" \"\"\nTranslate 0 1 0\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n\
        AttributeBegin\nReverseOrientation\nMaterial \"interface\"\nMediumInterface \"smoke\" \"\"\n\
        Shape \"sphere\"\nAttributeEnd\n";
    let (scene, report) = loads(&world(body));
    assert_eq!(scene.shapes.len(), 1, "boundaries are not surfaces");
    let boundaries = &scene.media.boundaries;
    assert_eq!(boundaries.len(), 2, "{:?}", report.warnings);
    let smoke_inside = scene::MediumInterface {
        inside: Some(0),
        outside: None,
    };
    assert_eq!(boundaries[0].interface, smoke_inside);
    // A sphere's normal points out whatever pbrt's orientation: reversed, its sides swap.
    let reversed = scene::MediumInterface {
        inside: None,
        outside: Some(0),
    };
    assert_eq!(boundaries[1].interface, reversed);
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.pbrt", &world(body));
    let strict = scene::LoadOptions::strict();
    assert!(scene::load_with_options(&path, &strict).is_ok());
}

/// Linear sRGB of a peak-normalised black body at `kelvin`.
fn blackbody_rgb(kelvin: f64) -> Vec3 {
    spectrum::xyz_to_linear_srgb(spectrum::blackbody_xyz(kelvin)).as_vec3()
}

fn rgb_close(a: Vec3, b: Vec3, relative: f32) -> bool {
    (a - b).abs().max_element() <= relative * b.abs().max_element()
}

#[test]
fn a_pbrt_v3_blackbody_is_planck_normalised_at_its_peak_times_its_scale() {
    let light = |values: &str| {
        let text = world(&format!(
            "LightSource \"point\" \"blackbody I\" [{values}]\nMaterial \"matte\"\nShape \"sphere\"\n"
        ))
        .replacen(
            "LightSource \"point\" \"point from\" [0 3 0] \"rgb I\" [10 10 10]\n",
            "",
            1,
        );
        point_power(&loads(&text).0)
    };
    let a = light("2856 1");
    assert!(rgb_close(a, blackbody_rgb(2856.0) * 4.0 * PI, 1e-5), "{a}");
    assert!(rgb_close(light("2856 3"), a * 3.0, 1e-5));
    assert!(
        rgb_close(light("2856"), a, 1e-5),
        "one number is a scale of 1"
    );
    // The peak-normalised spectrum's luminance is far from 1: this is not pbrt-v4's rule.
    assert!((a.dot(LUMINANCE) / (4.0 * PI) - 1.0).abs() > 0.1);
    // Illuminant A's chromaticity, through the light's RGB.
    let xyz = spectrum::XYZ_TO_LINEAR_SRGB.inverse() * a.as_dvec3();
    let xy = spectrum::chromaticity(xyz);
    assert!(
        (xy[0] - 0.44757).abs() < 1e-3 && (xy[1] - 0.40745).abs() < 1e-3,
        "{xy:?}"
    );
}

#[test]
fn a_pbrt_v4_blackbody_light_has_unit_luminance_before_scale_and_power() {
    let text = |light: &str| {
        format!(
            "{CAMERA}WorldBegin\n{light}\nMaterial \"diffuse\"\nShape \"sphere\"\n\
             AttributeBegin\nAreaLightSource \"diffuse\" \"blackbody L\" 4000\n\
             Translate 0 5 0\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n"
        )
    };
    let luminance = |light: &str| {
        let scene = loads(&text(light)).0;
        point_power(&scene).dot(LUMINANCE) / (4.0 * PI)
    };
    let y = luminance("LightSource \"point\" \"blackbody I\" 6500");
    assert!((y - 1.0).abs() < 1e-4, "{y}");
    let y = luminance("LightSource \"point\" \"blackbody I\" 6500 \"float scale\" 3");
    assert!((y - 3.0).abs() < 3e-4, "{y}");
    let y = luminance("LightSource \"point\" \"blackbody I\" 2000 \"float power\" 50");
    assert!((y * 4.0 * PI - 50.0).abs() < 2e-2, "{y}");
    // An rgb keeps its magnitude.
    let y = luminance("LightSource \"point\" \"rgb I\" [2 2 2]");
    assert!((y - 2.0).abs() < 1e-3, "{y}");
    // The colour is the black body's, whichever light carries it.
    let (scene, _) = loads(&text(
        "LightSource \"spot\" \"blackbody I\" 4000\nLightSource \"distant\" \"blackbody L\" 4000\n\
         LightSource \"infinite\" \"blackbody L\" 4000",
    ));
    let want = blackbody_rgb(4000.0);
    let want = want / want.dot(LUMINANCE);
    for light in &scene.lights {
        let c = match light {
            Light::Spot { power, .. } | Light::Sphere { power, .. } => *power,
            Light::Distant { irradiance, .. } => *irradiance,
            Light::Environment { radiance } => *radiance,
            other => panic!("{other:?}"),
        };
        assert!(rgb_close(c / c.dot(LUMINANCE), want, 1e-4), "{light:?}");
    }
    // A v4 blackbody is one temperature.
    let dir = tempfile::tempdir().unwrap();
    let err = load_text(
        dir.path(),
        &text("LightSource \"point\" \"blackbody I\" [4000 2]"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("scene.pbrt:5:21") && err.contains("one temperature"),
        "{err}"
    );
}

fn film_scene(film: &str, camera: &str) -> String {
    world("Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\nShape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-2 0 -2  -2 0 2  2 0 2  2 0 -2]\n")
        .replace("\"float fov\" 40", &format!("\"float fov\" 40 {camera}"))
        .replace(
            "\"integer yresolution\" 24",
            &format!("\"integer yresolution\" 24 {film}"),
        )
}

#[test]
fn film_scale_multiplies_the_written_image_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, text: &str| {
        let scene = write_scene(dir.path(), &format!("{name}.pbrt"), text);
        let out = dir.path().join(format!("{name}.pfm"));
        let args = [path_str(&scene), "-o", path_str(&out), "--passes", "1"];
        pipeline::run(&render_args(&args)).unwrap().image
    };
    let plain = run("plain", &film_scene("", ""));
    let doubled = run("doubled", &film_scene("\"float scale\" 2", ""));
    assert!(plain.pixels.iter().any(|p| p.max_element() > 0.0));
    for (a, b) in plain.pixels.iter().zip(&doubled.pixels) {
        assert_eq!(*b, *a * 2.0);
    }
}

#[test]
fn pbrt_v4_film_exposure_and_white_balance_become_the_image_response() {
    let response = |film: &str, camera: &str| {
        let text = film_scene(film, camera)
            .replace("\"matte\" \"rgb Kd\"", "\"diffuse\" \"rgb reflectance\"");
        loads(&text).0.response
    };
    assert!(response("", "").is_identity());
    assert!(loads(&world("Shape \"sphere\"\n")).0.response.is_identity());
    let r = response(
        "\"float iso\" 400",
        "\"float shutteropen\" 0.25 \"float shutterclose\" 0.75",
    );
    assert!((r.scale - 2.0).abs() < 1e-12, "{r:?}");
    let r = response("\"float iso\" 50 \"float exposuretime\" 3", "");
    assert!((r.scale - 1.5).abs() < 1e-12, "{r:?}");
    assert!(r.white_balance.is_none());
    // Daylight at 3000 K comes out grey; 6500 K is D65, left as it is.
    let r = response("\"float whitebalance\" 3000", "");
    let xy = spectrum::daylight_xy(3000.0);
    let white = DVec3::new(xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]);
    let [r_, g, b] = r.apply(spectrum::xyz_to_linear_srgb(white).to_array());
    assert!(
        (r_ / g - 1.0).abs() < 1e-3 && (b / g - 1.0).abs() < 1e-3,
        "{r_} {g} {b}"
    );
    let r = response("\"float whitebalance\" 6500", "");
    let [r_, g, b] = r.apply([0.2, 0.5, 0.8]);
    assert!((r_ - 0.2).abs() < 2e-3 && (g - 0.5).abs() < 2e-3 && (b - 0.8).abs() < 2e-3);
    // pbrt-v3 reads none of these: they are left unread (and reported), the image as rendered.
    let (scene, report) = loads(&film_scene("\"float iso\" 400", ""));
    assert!(scene.response.is_identity());
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains("dpm ignores \"float iso\""))
    );
    let dir = tempfile::tempdir().unwrap();
    let text = film_scene("", "\"float shutteropen\" 1 \"float shutterclose\" 1")
        .replace("\"matte\" \"rgb Kd\"", "\"diffuse\" \"rgb reflectance\"");
    let err = load_text(dir.path(), &text).unwrap_err().to_string();
    assert!(err.contains("never opens"), "{err}");
}

#[test]
fn an_undefined_named_material_keeps_the_current_one_with_a_warning() {
    // pbrt-v3 reports it and goes on (contemporary-bathroom names materials before defining them).
    let (scene, report) = loads(&world(
        "Material \"matte\" \"rgb Kd\" [0.25 0.5 0.75]\nNamedMaterial \"gold\"\nShape \"sphere\"\n",
    ));
    assert!(
        report
            .warnings
            .iter()
            .any(|w| w.contains("\"gold\"") && w.contains(":7:1")),
        "{:?}",
        report.warnings
    );
    let scene::Shape::Sphere { material, .. } = scene.shapes[0] else {
        panic!("{:?}", scene.shapes)
    };
    assert_eq!(
        scene.materials[material as usize],
        Material::Diffuse {
            albedo: Vec3::new(0.25, 0.5, 0.75)
        }
    );
}

#[test]
fn a_metal_from_sampled_spectrum_files_reflects_its_fresnel_colour() {
    // η = 1.5 and k = 0 at every wavelength: F0 = (0.5/2.5)² = 0.04 in every channel; an η
    // rising across the spectrum makes a redder F0 than a bluer one.
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("eta.spd"), "# flat\n300 1.5\n800 1.5\n").unwrap();
    std::fs::write(dir.path().join("k.spd"), "300 0\n800 0\n").unwrap();
    std::fs::write(dir.path().join("rising.spd"), "380 1.2\n780 3.0\n").unwrap();
    let metal = |eta: &str| {
        world(&format!(
            "Material \"metal\" \"spectrum eta\" \"{eta}\" \"spectrum k\" \"k.spd\" \"float roughness\" 0\nShape \"sphere\"\n"
        ))
    };
    let tint = |eta: &str| {
        let (scene, _) = load_text(dir.path(), &metal(eta)).unwrap_or_else(|e| panic!("{e}"));
        match scene.materials[..] {
            [.., Material::Mirror { tint }] => tint,
            ref other => panic!("{other:?}"),
        }
    };
    let flat = tint("eta.spd");
    assert!(
        (flat - Vec3::splat(0.04)).abs().max_element() < 1e-4,
        "{flat}"
    );
    let rising = tint("rising.spd");
    assert!(rising.x > rising.z, "{rising}");
    let e = load_text(dir.path(), &metal("absent.spd")).unwrap_err();
    assert!(
        e.to_string().contains("absent.spd") && e.line.is_some(),
        "{e}"
    );
}
