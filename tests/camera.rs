//! The cameras through the renderer and the scene formats: a crop window renders exactly the
//! full render's pixels (a thin lens and the caustic guide included), a thin-lens render is
//! the same with 1 and 2 threads, a pbrt `cropwindow` writes an image of the crop's size, and
//! pbrt's `perspective`, `orthographic` and `environment` cameras and the TOML camera fields
//! map to the cameras they name.

mod support;

use dpm::render::pipeline;
use dpm::scene::{CropWindow, Projection, ThinLens};
use support::pbrt::{LIGHT, loads};
use support::{description, path_str, render_args, write_scene};

/// A glass and a mirror sphere on a floor before a wall, lit by a point light (caustics, so the
/// caustic guide is learnt), with `camera_extra` lines added to the camera.
fn scene(camera_extra: &str) -> String {
    format!(
        "[camera]\nposition = [0.0, 2.2, 3.2]\nlook_at = [0.0, 0.3, 0.0]\nup = [0.0, 1.0, 0.0]\n\
         fov_y = 40.0\nresolution = [40, 30]\n{camera_extra}\n\
         [[lights]]\ntype = \"point\"\nposition = [0.6, 2.0, 0.4]\npower = [60.0, 60.0, 60.0]\n\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = [0.7, 0.7, 0.7]\n\n\
         [materials.glass]\ntype = \"glass\"\nior = 1.5\n\n\
         [materials.chrome]\ntype = \"mirror\"\n\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-2.0, 0.0, -1.5]\nedge_u = [0.0, 0.0, 3.5]\n\
         edge_v = [4.0, 0.0, 0.0]\nmaterial = \"floor\"\n\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [0.0, 0.5, 0.0]\nradius = 0.45\nmaterial = \"glass\"\n\n\
         [[objects]]\ntype = \"sphere\"\ncenter = [-0.9, 0.3, -0.6]\nradius = 0.3\nmaterial = \"chrome\"\n"
    )
}

const LENS: &str = "lens_radius = 0.08\nfocal_distance = 3.0\n";

/// Renders `text` with two passes of two samples a pixel on `threads` threads.
fn render(text: &str, threads: &str) -> dpm::image_io::Image {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.toml", text);
    let out = dir.path().join("out.pfm");
    let args = [
        path_str(&path),
        "-o",
        path_str(&out),
        "--threads",
        threads,
        "--seed",
        "5",
        "--passes",
        "2",
        "--spp",
        "2",
        "--caustic-photons",
        "4000",
        "--global-photons",
        "3000",
        "--emission-samples",
        "4",
        "--edge-samples",
        "6",
    ];
    pipeline::run(&render_args(&args)).expect("render").image
}

fn bits(image: &dpm::image_io::Image) -> Vec<[u32; 3]> {
    (image.pixels.iter())
        .map(|p| p.to_array().map(f32::to_bits))
        .collect()
}

#[test]
fn a_crop_is_the_full_renders_pixels_bit_for_bit() {
    let full = render(&scene(LENS), "2");
    let crop = render(
        &scene(&format!("{LENS}crop_window = [0.3, 0.8, 0.2, 0.7]\n")),
        "2",
    );
    // pbrt's rounding: columns ceil(12) .. ceil(32), rows ceil(6) .. ceil(21).
    assert_eq!((crop.width, crop.height), (20, 15));
    let mut differing = Vec::new();
    for y in 0..crop.height {
        for x in 0..crop.width {
            let (a, b) = (crop.get(x, y), full.get(x + 12, y + 6));
            if a.to_array().map(f32::to_bits) != b.to_array().map(f32::to_bits) {
                differing.push((x, y, a, b));
            }
        }
    }
    assert!(
        differing.is_empty(),
        "{} pixels differ: {:?}",
        differing.len(),
        &differing[..differing.len().min(5)]
    );
    assert!(full.pixels.iter().any(|p| p.max_element() > 0.0));
}

#[test]
fn a_thin_lens_render_is_the_same_with_1_and_2_threads() {
    let lens = scene(LENS);
    assert_eq!(bits(&render(&lens, "1")), bits(&render(&lens, "2")));
    // And the lens does blur: the image is not the pinhole's.
    assert_ne!(bits(&render(&lens, "2")), bits(&render(&scene(""), "2")));
}

#[test]
fn the_toml_camera_fields_name_the_projection_lens_and_crop() {
    let camera = |extra: &str| {
        let text = scene("").replace("fov_y = 40.0\n", extra);
        description(&text).camera
    };
    let perspective = camera("fov_y = 40.0\nlens_radius = 0.1\nfocal_distance = 2.5\n");
    assert_eq!(
        perspective.projection,
        Projection::Perspective {
            fov_y_degrees: 40.0
        }
    );
    assert_eq!(
        perspective.lens,
        ThinLens {
            radius: 0.1,
            focal_distance: 2.5
        }
    );
    assert_eq!(perspective.crop, CropWindow::FULL);
    let ortho = camera("projection = \"orthographic\"\nview_height = 3.0\n");
    assert_eq!(
        ortho.projection,
        Projection::Orthographic { view_height: 3.0 }
    );
    assert_eq!(ortho.lens, ThinLens::PINHOLE);
    let environment = camera("projection = \"environment\"\ncrop_window = [0.5, 0.0, 1.0, 0.25]\n");
    assert_eq!(environment.projection, Projection::Environment);
    // Each pair in order, as pbrt takes them.
    assert_eq!(
        environment.crop,
        CropWindow {
            x: [0.0, 0.5],
            y: [0.25, 1.0]
        }
    );
    assert_eq!(environment.image_size(), (20, 22));
}

/// A pbrt scene with `camera` and `film` lines.
fn pbrt(camera: &str, film: &str) -> dpm::scene::Camera {
    let text = format!(
        "LookAt 0 1 4  0 1 0  0 1 0\n{camera}\nFilm \"image\" \"integer xresolution\" 40 \
         \"integer yresolution\" 20 {film}\nWorldBegin\n{LIGHT}Shape \"sphere\"\nWorldEnd\n"
    );
    let (scene, report) = loads(&text);
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    scene.camera
}

#[test]
fn pbrts_cameras_map_their_parameters() {
    let lens = pbrt(
        "Camera \"perspective\" \"float fov\" 30 \"float lensradius\" 0.2 \"float focaldistance\" 7",
        "",
    );
    assert_eq!(
        lens.lens,
        ThinLens {
            radius: 0.2,
            focal_distance: 7.0
        }
    );
    assert_eq!(pbrt("Camera \"perspective\"", "").lens, ThinLens::PINHOLE);
    // pbrt's default screen window: ±1 on the shorter axis, so the film is 2 tall here.
    let ortho = pbrt("Camera \"orthographic\" \"float lensradius\" 0.1", "");
    assert_eq!(
        ortho.projection,
        Projection::Orthographic { view_height: 2.0 }
    );
    assert_eq!(ortho.lens.radius, 0.1);
    let window = pbrt(
        "Camera \"orthographic\" \"float screenwindow\" [-3 3 -1.5 1.5]",
        "",
    );
    assert_eq!(
        window.projection,
        Projection::Orthographic { view_height: 3.0 }
    );
    let environment = pbrt(
        "Camera \"environment\"",
        "\"float cropwindow\" [0.25 0.75 0 0.5]",
    );
    assert_eq!(environment.projection, Projection::Environment);
    assert_eq!(
        environment.crop,
        CropWindow {
            x: [0.25, 0.75],
            y: [0.0, 0.5]
        }
    );
    assert_eq!((environment.width, environment.height), (40, 20));
    assert_eq!(environment.image_size(), (20, 10));
}

#[test]
fn a_pbrt_cropwindow_writes_an_image_of_the_crops_size() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "LookAt 0 1 4  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
         Film \"image\" \"integer xresolution\" 32 \"integer yresolution\" 24 \
         \"float cropwindow\" [0.1 0.6 0.5 1]\nWorldBegin\n{LIGHT}Shape \"sphere\"\nWorldEnd\n"
    );
    let path = write_scene(dir.path(), "scene.pbrt", &text);
    let out = dir.path().join("out.pfm");
    let args = [
        path_str(&path),
        "-o",
        path_str(&out),
        "--caustic-photons",
        "1000",
    ];
    let outcome = pipeline::run(&render_args(&args)).expect("render");
    // Columns ceil(3.2) .. ceil(19.2), rows 12 .. 24.
    assert_eq!((outcome.image.width, outcome.image.height), (16, 12));
    let written = dpm::image_io::read_pfm(&out).unwrap();
    assert_eq!((written.width, written.height), (16, 12));
}
