//! pbrt's image environments (`infinite` with pbrt-v3's lat-long `mapname` or pbrt-v4's
//! equal-area `filename`): a constant image renders what the constant environment renders, a
//! ray leaving the scene sees the texel pbrt's mapping and the light's transform give it,
//! pbrt-v4's `illuminance` sets what an upward surface receives, and a bad image is refused
//! naming the file, line, column and parameter.

mod support;

use dpm::image_io::{self, Image, WriteOptions};
use dpm::render::pipeline;
use dpm::scene::{self, Light};
use glam::Vec3;
use std::path::Path;
use support::{path_str, render_args, write_scene};

/// A camera over a plane with a glass ball on it, under `light`.
fn scene_under(light: &str) -> String {
    format!(
        "LookAt 0 2.5 3  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
         Film \"image\" \"integer xresolution\" 48 \"integer yresolution\" 36\nWorldBegin\n\
         AttributeBegin\nRotate -90 1 0 0\n{light}\nAttributeEnd\n\
         Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-2 0 -2  -2 0 2  2 0 2  2 0 -2]\n\
         Material \"glass\"\nAttributeBegin\nTranslate 0 0.5 0\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n"
    )
}

fn write_map(
    dir: &Path,
    name: &str,
    width: usize,
    height: usize,
    f: impl FnMut(usize, usize) -> Vec3,
) {
    let image = Image::from_fn(width, height, f);
    image_io::write_image(&dir.join(name), &image, &WriteOptions::default()).unwrap();
}

/// The mean of every pixel, per channel.
fn image_mean(image: &Image) -> Vec3 {
    image
        .pixels
        .iter()
        .map(|p| p.as_dvec3())
        .sum::<glam::DVec3>()
        .as_vec3()
        / image.pixels.len() as f32
}

fn render(dir: &Path, name: &str, text: &str, extra: &[&str]) -> Image {
    let path = write_scene(dir, name, text);
    let out = dir.join(format!("{name}.pfm"));
    let mut args = vec![
        path_str(&path),
        "-o",
        path_str(&out),
        "--threads",
        "2",
        "--seed",
        "5",
    ];
    args.extend_from_slice(extra);
    pipeline::run(&render_args(&args))
        .unwrap_or_else(|e| panic!("{e}"))
        .image
}

#[test]
fn a_constant_image_renders_the_constant_environment_in_either_mapping() {
    let dir = tempfile::tempdir().unwrap();
    let l = Vec3::new(0.5, 0.25, 1.0);
    write_map(dir.path(), "wide.pfm", 32, 16, |_, _| l);
    write_map(dir.path(), "square.exr", 16, 16, |_, _| l);
    let photons = [
        "--passes",
        "4",
        "--spp",
        "4",
        "--caustic-photons",
        "20000",
        "--global-photons",
        "20000",
    ];
    let constant = render(
        dir.path(),
        "c.pbrt",
        &scene_under("LightSource \"infinite\" \"rgb L\" [0.5 0.25 1]"),
        &photons,
    );
    let reference = image_mean(&constant);
    for light in [
        "LightSource \"infinite\" \"string mapname\" \"wide.pfm\"",
        "LightSource \"infinite\" \"string filename\" \"square.exr\"",
    ] {
        let image = render(dir.path(), "m.pbrt", &scene_under(light), &photons);
        let mean = image_mean(&image);
        let ratio = mean / reference;
        assert!(
            (ratio - Vec3::ONE).abs().max_element() < 0.01,
            "{light}: mean {mean} against the constant environment's {reference}"
        );
        // The sky the camera sees directly is the same value, exactly.
        assert_eq!(image.get(0, 0), constant.get(0, 0), "{light}");
    }
}

#[test]
fn a_leaving_ray_sees_the_texel_pbrts_mapping_gives_its_direction() {
    let dir = tempfile::tempdir().unwrap();
    // Red where the map's +z (the first rows; the square's centre), blue elsewhere.
    let red = Vec3::new(1.0, 0.0, 0.0);
    let blue = Vec3::new(0.0, 0.0, 1.0);
    write_map(dir.path(), "wide.pfm", 32, 16, |_, y| {
        if y < 2 { red } else { blue }
    });
    write_map(dir.path(), "square.pfm", 16, 16, |x, y| {
        if (x as f32 - 7.5).abs() + (y as f32 - 7.5).abs() < 3.0 {
            red
        } else {
            blue
        }
    });
    // Looking straight up: `Rotate -90 1 0 0` turns the map's +z to the world's +y.
    let up = |light: &str| {
        format!(
            "LookAt 0 0 0  0 1 0  0 0 1\nCamera \"perspective\" \"float fov\" 10\n\
             Film \"image\" \"integer xresolution\" 8 \"integer yresolution\" 8\nWorldBegin\n\
             AttributeBegin\nRotate -90 1 0 0\n{light}\nAttributeEnd\n\
             Material \"matte\"\nAttributeBegin\nTranslate 0 -5 0\nShape \"sphere\" \"float radius\" 0.1\nAttributeEnd\n"
        )
    };
    for light in [
        "LightSource \"infinite\" \"string mapname\" \"wide.pfm\"",
        "LightSource \"infinite\" \"string filename\" \"square.pfm\"",
    ] {
        let text = up(light);
        let image = render(dir.path(), "up.pbrt", &text, &["--passes", "1"]);
        assert_eq!(image.get(4, 4), red, "{light}: looking up");
        let over = text.replace("Rotate -90 1 0 0", "Rotate 90 1 0 0");
        let image = render(dir.path(), "up.pbrt", &over, &["--passes", "1"]);
        assert_eq!(image.get(4, 4), blue, "{light}: the map turned over");
    }
}

#[test]
fn pbrt_v4_illuminance_sets_what_an_upward_surface_receives() {
    let dir = tempfile::tempdir().unwrap();
    write_map(dir.path(), "grey.pfm", 64, 64, |_, _| Vec3::splat(3.0));
    let text = "LookAt 0 2 3  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
                AttributeBegin\nRotate -90 1 0 0\n\
                LightSource \"infinite\" \"string filename\" \"grey.pfm\" \"float illuminance\" 10\n\
                AttributeEnd\nShape \"sphere\"\n";
    let path = write_scene(dir.path(), "e.pbrt", text);
    let desc = scene::load(&path).unwrap();
    let Light::EnvironmentMap(map) = &desc.lights[0] else {
        panic!("{:?}", desc.lights)
    };
    // A grey sky of radiance L gives an upward surface E = πL.
    let want = 10.0 / std::f32::consts::PI;
    for t in map.texels.iter() {
        assert!(
            (t.x - want).abs() < 2e-3 * want && t.x == t.y && t.y == t.z,
            "{t} against {want}"
        );
    }
}

#[test]
fn a_bad_environment_image_is_refused_naming_its_place() {
    let dir = tempfile::tempdir().unwrap();
    write_map(dir.path(), "wide.pfm", 8, 4, |_, _| Vec3::ONE);
    std::fs::write(
        dir.path().join("broken.png"),
        b"\x89PNG\r\n\x1a\nnot really",
    )
    .unwrap();
    let cases = [
        ("\"string mapname\" \"absent.exr\"", "cannot read"),
        ("\"string mapname\" \"broken.png\"", "broken.png"),
        ("\"string mapname\" \"sky.hdr\"", "EXR, PFM, PNG and TGA"),
        ("\"string filename\" \"wide.pfm\"", "square"),
    ];
    for (params, says) in cases {
        let text = format!(
            "LookAt 0 2 3  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
             LightSource \"infinite\" {params}\nShape \"sphere\"\n"
        );
        let path = write_scene(dir.path(), "bad.pbrt", &text);
        let e = scene::load(&path).unwrap_err();
        assert_eq!(
            (e.line, e.column.is_some()),
            (Some(4), true),
            "{params}: {e}"
        );
        assert!(e.field.contains("LightSource"), "{params}: {e}");
        assert!(e.to_string().contains(says), "{params}: {e}");
    }
    // A transform that stretches the map is refused too.
    let text = "LookAt 0 2 3  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\nScale 1 2 1\n\
                LightSource \"infinite\" \"string mapname\" \"wide.pfm\"\nShape \"sphere\"\n";
    let path = write_scene(dir.path(), "stretched.pbrt", text);
    let e = scene::load(&path).unwrap_err();
    assert!(e.to_string().contains("not a rotation"), "{e}");
}
