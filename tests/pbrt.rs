//! pbrt scene files: the same scene written in pbrt and in TOML renders the same image with
//! the same seed; pbrt's transforms, camera conventions, Include/Import and materials map as
//! pbrt defines them; every malformed pbrt or PLY file in tests/fixtures/pbrt/bad exits 2
//! naming its file and line (and column, in a pbrt file), never panicking; and mutated pbrt
//! files never panic the loader.

mod support;

use dpm::image_metrics::image_relative_mse as relative_mse;
use dpm::render::pipeline;
use dpm::scene::{self, Camera, Handedness, Light, LoadOptions, Material};
use glam::DVec3;
use glam::Vec3;
use proptest::prelude::*;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use support::eye::{PLANE_ALBEDO, check_plane_pixels};
use support::pbrt::{close, load_text, loads, spheres, world};
use support::{path_str, render_args, repo_path, scene_with_resolution, write_scene};

fn render(scene: &Path, out: &Path) -> dpm::image_io::Image {
    let args = [
        path_str(scene),
        "-o",
        path_str(out),
        "--threads",
        "2",
        "--caustic-photons",
        "20000",
        "--global-photons",
        "20000",
    ];
    pipeline::run(&render_args(&args))
        .unwrap_or_else(|e| panic!("{}: {e}", scene.display()))
        .image
}

#[test]
fn the_cornell_box_in_pbrt_renders_the_toml_image() {
    let dir = tempfile::tempdir().unwrap();
    let toml = write_scene(
        dir.path(),
        "box.toml",
        &scene_with_resolution("scenes/cornell-box.toml", 96, 96),
    );
    let pbrt_text = std::fs::read_to_string(repo_path("scenes/cornell-box.pbrt"))
        .unwrap()
        .replace("[512]", "[96]");
    let pbrt = write_scene(dir.path(), "box.pbrt", &pbrt_text);
    let a = render(&toml, &dir.path().join("a.pfm"));
    let b = render(&pbrt, &dir.path().join("b.pfm"));
    let e = relative_mse(&b, &a);
    eprintln!("relative MSE, pbrt against TOML: {e:e}");
    assert!(e <= 1e-4, "relative MSE {e}");
}

/// Writes the OBJ's mesh as a binary little-endian PLY with normals.
fn obj_to_ply(obj: &Path, ply: &Path) {
    let (models, _) = tobj::load_obj(
        obj,
        &tobj::LoadOptions {
            single_index: true,
            triangulate: true,
            ..Default::default()
        },
    )
    .unwrap();
    let m = &models[0].mesh;
    let n = m.positions.len() / 3;
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\ncomment from {}\nelement vertex {n}\n\
         property float x\nproperty float y\nproperty float z\nproperty float nx\n\
         property float ny\nproperty float nz\nelement face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        obj.display(),
        m.indices.len() / 3
    )
    .into_bytes();
    for i in 0..n {
        for x in m.positions[3 * i..3 * i + 3]
            .iter()
            .chain(&m.normals[3 * i..3 * i + 3])
        {
            b.extend(x.to_le_bytes());
        }
    }
    for t in m.indices.chunks_exact(3) {
        b.push(3);
        for i in t {
            b.extend((*i as i32).to_le_bytes());
        }
    }
    std::fs::write(ply, b).unwrap();
}

#[test]
fn the_torus_knot_from_a_binary_ply_renders_the_obj_image() {
    let dir = tempfile::tempdir().unwrap();
    let ply = dir.path().join("knot.ply");
    obj_to_ply(&repo_path("scenes/meshes/torus-knot.obj"), &ply);
    // scenes/torus-knot.toml: sphere light of 400 W, radius 0.05 → L = Φ / (π · 4πr²).
    let radiance = 400.0 / (std::f64::consts::PI * 4.0 * std::f64::consts::PI * 0.05 * 0.05);
    let text = format!(
        "Scale -1 1 1\nLookAt 0 3.4 4.4  0 0.2 0.4  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
         Film \"image\" \"integer xresolution\" 80 \"integer yresolution\" 60\nWorldBegin\n\
         AttributeBegin\n Translate 0.5 4.5 -1.5\n AreaLightSource \"diffuse\" \"rgb L\" [{radiance} {radiance} {radiance}]\n\
         Shape \"sphere\" \"float radius\" 0.05\nAttributeEnd\n\
         AttributeBegin\n Translate 0 1.1 0\n Rotate -90 1 0 0\n Material \"glass\" \"float index\" 1.5\n\
         Shape \"plymesh\" \"string filename\" \"knot.ply\"\nAttributeEnd\n\
         Material \"matte\" \"rgb Kd\" [0.75 0.75 0.75]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-4 0 -4  -4 0 4  4 0 4  4 0 -4]\n\
         WorldEnd\n"
    );
    let pbrt = write_scene(dir.path(), "knot.pbrt", &text);
    let toml_text = scene_with_resolution("scenes/torus-knot.toml", 80, 60).replace(
        "meshes/torus-knot.obj",
        path_str(&repo_path("scenes/meshes/torus-knot.obj")),
    );
    let toml = write_scene(dir.path(), "knot.toml", &toml_text);
    let a = render(&toml, &dir.path().join("a.pfm"));
    let b = render(&pbrt, &dir.path().join("b.pfm"));
    let e = relative_mse(&b, &a);
    eprintln!("relative MSE, pbrt against TOML: {e:e}");
    assert!(e <= 1e-4, "relative MSE {e}");
}

/// Each malformed file, the place its error must name (`file:line[:column]`, the file
/// relative to tests/fixtures/pbrt/bad) and a phrase of the message.
#[rustfmt::skip]
const MALFORMED: &[(&str, &str, &str)] = &[
    ("albedo-above-one", "albedo-above-one.pbrt:7:1", "not in [0, 1]"),
    ("attribute-closed-by-transform-end", "attribute-closed-by-transform-end.pbrt:8:1", "does not match"),
    ("attribute-unknown-target", "attribute-unknown-target.pbrt:7:1", "is not shape, light"),
    ("blackbody-reflectance", "blackbody-reflectance.pbrt:6:18", "read only where a light's emission is"),
    ("blackbody-three-numbers", "blackbody-three-numbers.pbrt:7:21", "[temperature scale]"),
    ("camera-negative-lensradius", "camera-negative-lensradius.pbrt:2:22", "\"float lensradius\": -0.5 is not a lens radius"),
    ("camera-zero-focaldistance", "camera-zero-focaldistance.pbrt:2:23", "\"float focaldistance\": 0 must be a finite number greater than 0"),
    ("cropwindow-empty", "cropwindow-empty.pbrt:3:64", "\"float cropwindow\": [0.5, 0.5, 0, 1] is empty"),
    ("cropwindow-outside", "cropwindow-outside.pbrt:3:64", "\"float cropwindow\": 1.5 is not a fraction of the film in [0, 1]"),
    ("cylinder-zmin-above-zmax", "cylinder-zmin-above-zmax.pbrt:7:18", "zmin 2 is not below zmax 1"),
    ("disk-negative-radius", "disk-negative-radius.pbrt:7:14", "\"float radius\": radius -2 is not > 0"),
    ("film-resolution-zero", "film-resolution-zero.pbrt:3:14", "not from 1"),
    ("heightfield-wrong-count", "heightfield-wrong-count.pbrt:7:51", "3 heights, not nu × nv"),
    ("include-cycle", "include-cycle.pbrt:7:1", "includes itself"),
    ("include-then-parameters", "include-then-parameters.pbrt:7:3", "not > 0"),
    ("include-with-a-bad-parameter", "included/negative-radius.pbrt:2:16", "not > 0"),
    ("index-out-of-range", "index-out-of-range.pbrt:7:22", "not one of the 3 points"),
    ("indices-not-triples", "indices-not-triples.pbrt:7:22", "not a multiple of 3"),
    ("infinite-in-parameter", "infinite-in-parameter.pbrt:7:16", "finite"),
    ("loopsubdiv-index-out-of-range", "loopsubdiv-index-out-of-range.pbrt:7:51", "not one of the 3 points"),
    ("loopsubdiv-non-manifold", "loopsubdiv-non-manifold.pbrt:7:64", "not a manifold"),
    ("missing-include", "missing-include.pbrt:7:1", "cannot read"),
    ("mix-amount-out-of-range", "mix-amount-out-of-range.pbrt:8:51", "\"float amount\": a mix's amount 1.5 is not in [0, 1]"),
    ("mix-one-material", "mix-one-material.pbrt:7:16", "\"string materials\": a mix takes two materials, not 1"),
    ("mix-undefined-material", "mix-undefined-material.pbrt:7:48", "\"string namedmaterial2\": no material is named \"grey\""),
    ("nan-in-transform", "nan-in-transform.pbrt:7:11", "expected a number"),
    ("negative-radius", "negative-radius.pbrt:7:16", "not > 0"),
    ("no-lights", "no-lights.pbrt:1:1", "no light"),
    ("normal-count-mismatch", "normal-count-mismatch.pbrt:7:53", "1 normals for 3 points"),
    ("orthographic-off-centre-screenwindow", "orthographic-off-centre-screenwindow.pbrt:2:23", "must be centred"),
    ("ply-huge-count", "huge-count.ply:3", "claims 1000000000000"),
    ("ply-index-out-of-range", "index-out-of-range.ply:13", "not one of the 3 vertices"),
    ("ply-missing-file", "ply-missing-file.pbrt:7:17", "cannot read"),
    ("ply-not-a-ply", "not-a-ply.ply:1", "does not start with `ply`"),
    ("ply-truncated-binary", "truncated-binary.ply", "ends inside this element"),
    ("ply-wrong-vertex-count", "wrong-vertex-count.ply:7", "claims 1 elements"),
    ("realistic-camera", "realistic-camera.pbrt:2:1", "not pbrt's realistic lens systems"),
    ("shape-before-world-begin", "shape-before-world-begin.pbrt:4:1", "after WorldBegin"),
    ("sphere-phimax-above-360", "sphere-phimax-above-360.pbrt:7:16", "\"float phimax\": phimax 400 is not in (0, 360]"),
    ("stray-number", "stray-number.pbrt:7:16", "is not a parameter"),
    ("unbalanced-attribute-end", "unbalanced-attribute-end.pbrt:7:1", "no AttributeBegin"),
    ("unclosed-attribute-begin", "unclosed-attribute-begin.pbrt:7:1", "never closed"),
    ("unclosed-value-list", "unclosed-value-list.pbrt:8:1", "in a value list"),
    ("undefined-coordinate-system", "undefined-coordinate-system.pbrt:7:1", "\"lamp\""),
    ("undefined-texture", "undefined-texture.pbrt:7:18", "no texture is named \"checks\""),
    ("unknown-camera", "unknown-camera.pbrt:2:1", "\"fisheye\": dpm has the \"perspective\", \"orthographic\" and \"environment\" cameras"),
    ("unknown-directive", "unknown-directive.pbrt:7:1", "`Shap` is not a pbrt directive"),
    ("unknown-material", "unknown-material.pbrt:7:1", "\"velvet\""),
    ("unknown-parameter-type", "unknown-parameter-type.pbrt:7:16", "`flaot`"),
    ("unterminated-string", "unterminated-string.pbrt:7:7", "string"),
    ("zero-rotation-axis", "zero-rotation-axis.pbrt:7:1", "zero vector"),
];

#[test]
fn every_malformed_pbrt_or_ply_file_exits_2_naming_its_place() {
    let bad = repo_path("tests/fixtures/pbrt/bad");
    let listed: Vec<PathBuf> = MALFORMED
        .iter()
        .map(|(name, ..)| bad.join(format!("{name}.pbrt")))
        .collect();
    let mut on_disk: Vec<PathBuf> = std::fs::read_dir(&bad)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "pbrt"))
        .collect();
    on_disk.sort();
    assert_eq!(on_disk, listed, "every fixture is listed, in name order");
    assert!(MALFORMED.len() >= 20);
    let out_dir = tempfile::tempdir().unwrap();
    let output = out_dir.path().join("never.png");
    let mut failures = Vec::new();
    for ((name, place, phrase), scene) in MALFORMED.iter().zip(&listed) {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_dpm"))
            .args([
                "render".as_ref(),
                scene.as_os_str(),
                "-o".as_ref(),
                output.as_os_str(),
            ])
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        let want_place = format!("{}/{place}: ", bad.display());
        if out.status.code() != Some(2)
            || err.contains("panicked")
            || !err.contains(&want_place)
            || !err.contains(phrase)
            || output.exists()
        {
            failures.push(format!(
                "{name}: exit {:?}, want `{want_place}` and `{phrase}`:\n{err}",
                out.status.code()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// scenes/point-plane.toml's plane and camera in pbrt, under `lights`; `end` is `WorldEnd`
/// for a pbrt-v3 file (with v3's `matte`) or empty for a pbrt-v4 one (with v4's `diffuse`).
fn pbrt_plane(lights: &str, end: &str) -> String {
    let material = if end.is_empty() {
        "Material \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]"
    } else {
        "Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]"
    };
    format!(
        "LookAt 0 2.5 3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
         Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 48\nWorldBegin\n{lights}\n\
         {material}\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-2 0 -2  -2 0 2  2 0 2  2 0 -2]\n{end}"
    )
}

/// A one-pass render of a pbrt scene, and its description.
fn render_pbrt(text: &str) -> (pipeline::RenderOutcome, scene::SceneDescription) {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.pbrt", text);
    let out = dir.path().join("scene.pfm");
    let outcome = pipeline::run(&render_args(&[
        path_str(&path),
        "-o",
        path_str(&out),
        "--threads",
        "2",
        // Pixels are checked at their one camera sample: emitters and sky not sampled apart,
        // and edge pixels take no more samples than the rest.
        "--emission-samples",
        "0",
        "--edge-samples",
        "0",
    ]))
    .unwrap_or_else(|e| panic!("{e}"));
    (outcome, scene::load(&path).unwrap())
}

#[test]
fn a_pbrt_spot_light_gives_the_plane_its_analytic_irradiance_in_either_dialect() {
    let (alpha, delta) = (40.0f64, 15.0f64);
    let beta = alpha - delta;
    let intensity = DVec3::new(10.0, 6.0, 3.0);
    let position = DVec3::new(0.0, 1.0, 0.0);
    let axis = DVec3::new(0.3, -1.0, 0.0).normalize();
    // pbrt-v3 (its file ends with WorldEnd) shapes the edge with t⁴ and names its width
    // "conedeltaangle", pbrt-v4 with a smoothstep and "conedelta".
    for (end, quartic, name) in [
        ("WorldEnd\n", true, "conedeltaangle"),
        ("", false, "conedelta"),
    ] {
        let light = format!(
            "LightSource \"spot\" \"point from\" [0 1 0] \"point to\" [0.3 0 0] \"float coneangle\" {alpha} \
             \"float {name}\" {delta} \"rgb I\" [10 6 3]"
        );
        let (outcome, desc) = render_pbrt(&pbrt_plane(&light, end));
        let (cos_a, cos_b) = (alpha.to_radians().cos(), beta.to_radians().cos());
        let falloff = |c: f64| {
            let t = ((c - cos_a) / (cos_b - cos_a)).clamp(0.0, 1.0);
            if quartic {
                t.powi(4)
            } else {
                t * t * (3.0 - 2.0 * t)
            }
        };
        let scale = PLANE_ALBEDO / PI * intensity.max_element();
        let check = check_plane_pixels(
            &outcome.image,
            &desc,
            |p| {
                let to_light = position - p;
                let d = to_light.length();
                let f = falloff(-to_light.dot(axis) / d);
                let e = intensity * f * (to_light.y / d) / (d * d);
                (PLANE_ALBEDO / PI * e, (f < 0.05).then_some(1e-3 * scale))
            },
            |_, _| None,
            DVec3::ZERO,
            1e-3,
        );
        eprintln!(
            "pbrt spot (quartic {quartic}): worst relative error {:.2e}",
            check.worst
        );
    }
}

#[test]
fn a_pbrt_constant_environment_gives_the_plane_pi_l() {
    let radiance = DVec3::new(0.5, 0.25, 1.0);
    let (outcome, desc) = render_pbrt(&pbrt_plane(
        "LightSource \"infinite\" \"rgb L\" [0.5 0.25 1]",
        "WorldEnd\n",
    ));
    let check = check_plane_pixels(
        &outcome.image,
        &desc,
        |_| (PLANE_ALBEDO * radiance, None),
        |_, _| None,
        radiance,
        1e-3,
    );
    eprintln!("pbrt environment: worst relative error {:.2e}", check.worst);
}

#[test]
fn pbrt_lights_and_tints_map_onto_dpms() {
    let (scene, report) = loads(&world(
        "LightSource \"distant\" \"point from\" [0 1 0] \"point to\" [0 0 0] \"rgb L\" [2 2 2] \"float scale\" 1.5\n\
         AttributeBegin\n AreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\n\
         Shape \"trianglemesh\" \"point3 P\" [0 2 0  1 2 0  0 2 1]\nAttributeEnd\n\
         Material \"glass\" \"rgb Kr\" [0.9 0.9 0.9] \"rgb Kt\" [0.5 1 1]\nShape \"sphere\"\n\
         Material \"mirror\"\nShape \"sphere\"\n",
    ));
    let Light::Distant {
        direction,
        irradiance,
    } = scene.lights[1]
    else {
        panic!("{:?}", scene.lights)
    };
    assert!(close(direction, -Vec3::Y) && close(irradiance, Vec3::splat(3.0)));
    let Light::Mesh {
        ref mesh,
        power,
        two_sided,
    } = scene.lights[2]
    else {
        panic!("{:?}", scene.lights)
    };
    // Φ = 2π · A · L for a two-sided emitter of area ½.
    assert!(
        two_sided && mesh.triangles.len() == 1 && (power.x - std::f32::consts::PI).abs() < 1e-5,
        "{power}"
    );
    assert_eq!(
        scene.materials[0],
        Material::Glass {
            ior: 1.5,
            reflect_tint: Vec3::splat(0.9),
            transmit_tint: Vec3::new(0.5, 1.0, 1.0)
        }
    );
    assert_eq!(
        scene.materials[1],
        Material::Mirror {
            tint: Vec3::splat(0.9)
        },
        "pbrt-v3's mirror reflects 0.9 by default"
    );
    assert!(
        report.notes.iter().any(|n| n.contains("pbrt-v3")),
        "{:?}",
        report.notes
    );
}

#[test]
fn transforms_compose_as_pbrt_composes_them() {
    let (scene, _) = loads(&world(
        "AttributeBegin\n Translate 1 0 0\n Rotate 90 0 0 1\n Translate 1 0 0\n Scale 2 2 2\n \
         Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n\
         TransformBegin\n ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 3 1]\n CoordinateSystem \"z3\"\nTransformEnd\n\
         Shape \"sphere\"\n\
         AttributeBegin\n CoordSysTransform \"z3\"\n Shape \"sphere\" \"float radius\" 0.25\nAttributeEnd\n\
         AttributeBegin\n Translate 5 5 5\n Transform [1 0 0 0  0 1 0 0  0 0 1 0  0 -2 0 1]\n Shape \"sphere\" \"float radius\" 0.125\nAttributeEnd\n",
    ));
    let s = spheres(&scene);
    assert_eq!(s.len(), 4, "{s:?}");
    // Translate(1,0,0)·Rz(90°)·Translate(1,0,0): the origin goes to (1, 1, 0); radius 0.5 · 2.
    assert!(
        close(s[0].0, Vec3::new(1.0, 1.0, 0.0)) && (s[0].1 - 1.0).abs() < 1e-6,
        "{s:?}"
    );
    // TransformEnd restored the identity; the named system kept the translation.
    assert!(close(s[1].0, Vec3::ZERO) && s[1].1 == 1.0, "{s:?}");
    assert!(close(s[2].0, Vec3::new(0.0, 0.0, 3.0)), "{s:?}");
    // Transform replaces the current transform.
    assert!(close(s[3].0, Vec3::new(0.0, -2.0, 0.0)), "{s:?}");
}

#[test]
fn non_uniformly_scaled_spheres_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let e = load_text(dir.path(), &world("Scale 1 2 1\nShape \"sphere\"\n")).unwrap_err();
    assert!(e.to_string().contains("not a uniform scale"), "{e}");
}

fn camera_of(text: &str) -> Camera {
    loads(text).0.camera
}

#[test]
fn the_camera_follows_pbrts_fov_and_handedness() {
    let body = "WorldBegin\nLightSource \"point\"\nShape \"sphere\"\nWorldEnd\n";
    let plain = camera_of(&format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
        Film \"image\" \"integer xresolution\" 200 \"integer yresolution\" 100\n{body}"
    ));
    assert_eq!(
        plain.handedness,
        Handedness::Left,
        "pbrt's LookAt camera space is left-handed"
    );
    assert!(close(plain.position, Vec3::new(0.0, 0.0, 5.0)));
    assert!(close(
        (plain.look_at - plain.position).normalize(),
        -Vec3::Z
    ));
    assert!(
        (plain.fov_y_degrees().unwrap() - 30.0).abs() < 1e-4,
        "landscape: fov is the vertical one"
    );
    let flipped = camera_of(&format!(
        "Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
        Film \"image\" \"integer xresolution\" 100 \"integer yresolution\" 200\n{body}"
    ));
    assert_eq!(flipped.handedness, Handedness::Right);
    // Portrait: 30° spans the width, so the height spans 2·atan(2·tan 15°).
    let want = 2.0 * (2.0 * 15f32.to_radians().tan()).atan().to_degrees();
    assert!(
        (flipped.fov_y_degrees().unwrap() - want).abs() < 1e-3,
        "{} vs {want}",
        flipped.fov_y_degrees().unwrap()
    );
    assert_eq!((flipped.width, flipped.height), (100, 200));
}

#[test]
fn materials_map_exactly_or_warn_once_and_strict_refuses_approximations() {
    let text = world(
        "MakeNamedMaterial \"coat\" \"string type\" \"uber\" \"rgb Kd\" [0.2 0.3 0.4] \"rgb Ks\" [0.5 0.5 0.5]\n\
         NamedMaterial \"coat\"\nShape \"sphere\"\nTranslate 3 0 0\nShape \"sphere\"\n\
         Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\"\nShape \"sphere\"\n\
         Material \"dielectric\" \"float eta\" 1.33\nShape \"sphere\"\n\
         Material \"diffuse\" \"rgb reflectance\" [0.1 0.2 0.3]\nShape \"sphere\"\n\
         Material \"matte\" \"float sigma\" 20\nShape \"sphere\"\n",
    );
    let (scene, report) = loads(&text);
    let m = &scene.materials;
    assert_eq!(
        m.len(),
        5,
        "one scene material per pbrt material used: {m:?}"
    );
    // pbrt-v3's uber with its defaults: roughness 0.1 remapped, index 1.5, opaque.
    let alpha = dpm::bsdf::pbrt_v3_roughness_to_alpha(0.1);
    assert_eq!(
        m[0],
        Material::Bsdf(dpm::bsdf::Model::Uber {
            kd: Vec3::new(0.2, 0.3, 0.4),
            ks: Vec3::splat(0.5),
            kr: Vec3::ZERO,
            kt: Vec3::ZERO,
            alpha: glam::Vec2::splat(alpha),
            eta: 1.5,
            opacity: Vec3::ONE,
        })
    );
    assert!(matches!(m[1], Material::Mirror { .. }), "{m:?}");
    assert!(
        matches!(m[2], Material::Glass { ior, .. } if (ior - 1.33).abs() < 1e-6),
        "{m:?}"
    );
    assert_eq!(
        m[3],
        Material::Diffuse {
            albedo: Vec3::new(0.1, 0.2, 0.3)
        }
    );
    assert!(
        !report.warnings.iter().any(|w| w.contains("uber")),
        "uber is rendered as pbrt defines it: {:?}",
        report.warnings
    );
    let sigma: Vec<_> = (report.warnings.iter())
        .filter(|w| w.contains("sigma"))
        .collect();
    assert_eq!(sigma.len(), 1, "{:?}", report.warnings);
    assert!(sigma[0].contains("scene.pbrt:17:1"), "{sigma:?}");
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.pbrt", &text);
    let e = scene::load_with_options(&path, &LoadOptions::strict()).unwrap_err();
    assert_eq!((e.line, e.column), (Some(17), Some(1)), "{e}");
    assert!(e.message.contains("--strict"), "{e}");
}

#[test]
fn include_shares_the_graphics_state_and_import_does_not() {
    let dir = tempfile::tempdir().unwrap();
    write_scene(
        dir.path(),
        "part.pbrt",
        "Translate 0 2 0\nShape \"sphere\" \"float radius\" 0.5\n",
    );
    let text = world(
        "Include \"part.pbrt\"\nShape \"sphere\"\nImport \"part.pbrt\"\nShape \"sphere\" \"float radius\" 2\n",
    );
    let (scene, _) = load_text(dir.path(), &text).unwrap();
    let s = spheres(&scene);
    assert!(close(s[0].0, Vec3::new(0.0, 2.0, 0.0)), "{s:?}");
    assert!(
        close(s[1].0, Vec3::new(0.0, 2.0, 0.0)),
        "Include kept the translation: {s:?}"
    );
    assert!(close(s[2].0, Vec3::new(0.0, 4.0, 0.0)), "{s:?}");
    assert!(
        close(s[3].0, Vec3::new(0.0, 2.0, 0.0)),
        "Import dropped its own translation: {s:?}"
    );
}

#[test]
fn a_quad_area_light_emits_to_the_side_pbrt_says() {
    let quad = "AreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [0 1 0  1 1 0  1 1 1  0 1 1]\n";
    let floor = "Shape \"sphere\"\n";
    // A mirroring transform keeps pbrt's object-space orientation (it flips the winding back).
    for (prefix, up) in [
        ("", false),
        ("ReverseOrientation\n", true),
        ("Scale 1 1 -1\n", false),
        ("Scale 1 1 -1\nReverseOrientation\n", true),
    ] {
        let (scene, _) = loads(&world(&format!(
            "{floor}AttributeBegin\n{prefix}{quad}AttributeEnd\n"
        )));
        let Some(Light::Quad {
            edge_u,
            edge_v,
            power,
            ..
        }) = scene.lights.last()
        else {
            panic!("a quad light: {:?}", scene.lights);
        };
        let n = edge_u.cross(*edge_v).normalize();
        // P winds (0,1,0) → (1,1,0) → (1,1,1): its normal is -y; ReverseOrientation turns it up.
        assert!(
            close(n, if up { Vec3::Y } else { -Vec3::Y }),
            "{prefix:?}: {n}"
        );
        // Φ = π · A · L with A = 1.
        assert!((power.x - std::f32::consts::PI).abs() < 1e-5, "{power}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]

    /// Deleting, repeating or replacing a token of a valid file, or cutting it short, gives a
    /// scene or an error that names a line; it never panics.
    #[test]
    fn mutated_pbrt_files_load_or_fail_with_a_place(
        which in 0usize..2,
        at in 0usize..10_000,
        op in 0usize..4,
        junk in prop::sample::select(vec!["[", "]", "\"", "-1e39", "nan", "\"float radius\"", "AttributeEnd", "0", "\"point3 P\" [1 2]", "Include \"x\""]),
    ) {
        let texts = [
            std::fs::read_to_string(repo_path("scenes/cornell-box.pbrt")).unwrap(),
            world("AttributeBegin\nMaterial \"glass\"\nShape \"trianglemesh\" \"integer indices\" [0 1 2] \"point3 P\" [0 0 0 1 0 0 0 1 0]\nAttributeEnd\n"),
        ];
        let text = &texts[which];
        let words: Vec<&str> = text.split(' ').collect();
        let i = at % words.len();
        let mutated = match op {
            0 => [&words[..i], &words[i + 1..]].concat().join(" "),
            1 => [&words[..=i], &words[i..]].concat().join(" "),
            2 => [&words[..i], &[junk], &words[i + 1..]].concat().join(" "),
            _ => text[..text.char_indices().nth(at % text.len()).map_or(0, |c| c.0)].to_string(),
        };
        let dir = tempfile::tempdir().unwrap();
        if let Err(e) = load_text(dir.path(), &mutated) {
            prop_assert!(e.line.is_some() || e.field == "WorldBegin", "no place: {e}");
        }
    }
}

#[test]
fn coated_layers_warn_where_dpm_approximates_them_and_strict_refuses_them() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "Material \"coatedconductor\" \"float conductor.roughness\" 0.2",
            "returns",
        ),
        (
            "Material \"coateddiffuse\" \"rgb albedo\" [0.5 0.5 0.5] \"float thickness\" 0.1",
            "medium",
        ),
    ];
    for (material, why) in cases {
        let text = world(&format!("{material}\nShape \"sphere\"\n"));
        let (_, report) = loads(&text);
        let warned: Vec<_> = (report.warnings.iter())
            .filter(|w| w.contains(why))
            .collect();
        assert_eq!(warned.len(), 1, "{material}: {:?}", report.warnings);
        let path = write_scene(dir.path(), "coat.pbrt", &text);
        let e = scene::load_with_options(&path, &LoadOptions::strict()).unwrap_err();
        assert!(e.message.contains("--strict") && e.line == Some(6), "{e}");
    }
    // A coated diffuse without a medium is within 0.03 of pbrt-v4's walk: no warning.
    let (_, report) = loads(&world("Material \"coateddiffuse\"\nShape \"sphere\"\n"));
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
}
