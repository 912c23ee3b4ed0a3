//! Many lights drawn from the light tree: the image a shading point gets from a few drawn
//! lights, each over its probability, converges to the one it gets from every light. Checked
//! on a diffuse plane under point lights of varied power (every light: the closed form at
//! every pixel; the tree: the same in the mean) and on a glossy floor under mesh emitters whose
//! triangles the tree holds one by one, where BSDF samples that find an emitter weigh
//! themselves against the tree's draws (MIS).

mod support;

use glam::DVec3;
use std::f64::consts::PI;
use support::eye::*;
use support::*;

/// Point lights over the analytic plane, spread and of uneven power: (position, power).
fn point_lights(count: usize) -> Vec<(DVec3, f64)> {
    (0..count)
        .map(|i| {
            let t = i as f64;
            let x = -2.4 + 4.8 * ((t * 0.618_034) % 1.0);
            let z = -2.4 + 4.8 * ((t * 0.414_214 + 0.3) % 1.0);
            let y = 0.4 + 1.6 * ((t * 0.732_051 + 0.1) % 1.0);
            (DVec3::new(x, y, z), 2.0 + 30.0 * ((t * 0.236_068) % 1.0))
        })
        .collect()
}

fn lights_toml(lights: &[(DVec3, f64)]) -> String {
    (lights.iter())
        .map(|(p, w)| {
            format!(
                "[[lights]]\ntype = \"point\"\nposition = [{}, {}, {}]\npower = [{w}, {w}, {w}]\n",
                p.x, p.y, p.z
            )
        })
        .collect()
}

/// Means over `block` × `block` tiles of both images, and the worst relative difference of
/// the tiles bright enough to say (a tenth of the brightest).
fn worst_tile_difference(a: &dpm::image_io::Image, b: &dpm::image_io::Image, block: usize) -> f64 {
    let tile = |image: &dpm::image_io::Image, tx: usize, ty: usize| {
        let mut sum = 0.0;
        for y in ty * block..(ty + 1) * block {
            for x in tx * block..(tx + 1) * block {
                sum += dvec(image.get(x, y)).element_sum();
            }
        }
        sum
    };
    let (nx, ny) = (a.width / block, a.height / block);
    let tiles: Vec<(f64, f64)> = (0..nx * ny)
        .map(|i| (tile(a, i % nx, i / nx), tile(b, i % nx, i / nx)))
        .collect();
    let brightest = tiles.iter().map(|t| t.0).fold(0.0, f64::max);
    (tiles.iter())
        .filter(|t| t.0 > 0.1 * brightest)
        .map(|&(x, y)| (x - y).abs() / x)
        .fold(0.0, f64::max)
}

#[test]
fn a_plane_under_forty_point_lights_gets_their_light_whether_each_is_sampled_or_drawn() {
    let lights = point_lights(40);
    let scene = plane_scene(&lights_toml(&lights), 48, 36);
    let irradiance = |p: DVec3| {
        (lights.iter())
            .map(|&(l, power)| {
                let to = l - p;
                power / (4.0 * PI) * to.y.max(0.0) / to.length().powi(3)
            })
            .sum::<f64>()
    };
    // Every light, one exact shadow ray each: the closed form at every pixel.
    let (every, desc) = render_scene(&scene, &["--every-light-max", "100"]);
    check_plane_pixels(
        &every.image,
        &desc,
        |p| (DVec3::splat(PLANE_ALBEDO / PI * irradiance(p)), None),
        |_, _| None,
        DVec3::ZERO,
        1e-3,
    );
    // Four lights drawn a hit: noisy, the same in the mean (at the same camera samples, so
    // that the plane's edges cover the same share of their pixels).
    let (every, _) = render_scene(&scene, &["--every-light-max", "100", "--spp", "64"]);
    let (drawn, _) = render_scene(&scene, &["--spp", "64"]);
    let worst = worst_tile_difference(&every.image, &drawn.image, 6);
    assert!(worst < 0.03, "a 6 × 6 tile differs by {worst}");
    let (a, b) = (mean_of(&every.image), mean_of(&drawn.image));
    assert!(
        (a / b - 1.0).abs() < 0.005,
        "means {a} (every light) and {b} (drawn)"
    );
    assert_ne!(every.image, drawn.image, "the tree was not used");
}

fn mean_of(image: &dpm::image_io::Image) -> f64 {
    let sum: f64 = image.pixels.iter().map(|p| dvec(*p).element_sum()).sum();
    sum / image.pixels.len() as f64
}

/// A glossy floor under a mesh emitter of 32 triangles and eight small square emitters, seen
/// from above at a slant so the floor reflects them: pbrt's language.
fn glossy_floor() -> String {
    let mut text = String::from(
        "LookAt 0 3 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [50]\n\
         Film \"image\" \"integer xresolution\" [48] \"integer yresolution\" [36]\n\
         WorldBegin\n\
         AttributeBegin\nMaterial \"plastic\" \"rgb Kd\" [0.3 0.3 0.3] \"rgb Ks\" [0.5 0.5 0.5] \
         \"float roughness\" [0.05]\n\
         Shape \"trianglemesh\" \"point P\" [-4 0 -4  4 0 -4  4 0 4  -4 0 4] \
         \"integer indices\" [0 2 1 0 3 2]\nAttributeEnd\n",
    );
    // A 4 × 4 grid of cells, two triangles each, facing down, 1.5 above the floor.
    let mut points = Vec::new();
    let mut indices = Vec::new();
    for j in 0..=4 {
        for i in 0..=4 {
            points.push(format!(
                "{} 1.5 {}",
                -1.0 + 0.5 * i as f64,
                -2.0 + 0.5 * j as f64
            ));
        }
    }
    for j in 0..4 {
        for i in 0..4 {
            let a = j * 5 + i;
            let (b, c, d) = (a + 1, a + 6, a + 5);
            indices.push(format!("{a} {b} {c} {a} {c} {d}"));
        }
    }
    text += &format!(
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n\
         Shape \"trianglemesh\" \"point P\" [{}] \"integer indices\" [{}]\nAttributeEnd\n",
        points.join("  "),
        indices.join("  ")
    );
    for k in 0..8 {
        let x = -3.0 + 0.8 * k as f64;
        let z = 1.0 + 0.3 * (k % 3) as f64;
        let l = 1.0 + k as f64;
        text += &format!(
            "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [{l} {l} {l}]\n\
             Shape \"trianglemesh\" \"point P\" [{x} 1 {z}  {} 1 {z}  {} 1 {}  {x} 1 {}] \
             \"integer indices\" [0 1 2 0 2 3]\nAttributeEnd\n",
            x + 0.2,
            x + 0.2,
            z + 0.2,
            z + 0.2
        );
    }
    text + "WorldEnd\n"
}

fn render_pbrt(text: &str, extra: &[&str]) -> dpm::image_io::Image {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "scene.pbrt", text);
    let out = dir.path().join("scene.pfm");
    let mut args = vec![path_str(&path), "-o", path_str(&out), "--threads", "2"];
    args.extend_from_slice(&["--caustic-photons", "0", "--global-photons", "0"]);
    args.extend_from_slice(extra);
    dpm::render::pipeline::run(&render_args(&args))
        .unwrap()
        .image
}

#[test]
fn a_glossy_floor_under_many_emitter_triangles_reflects_the_same_light_drawn_or_not() {
    let scene = glossy_floor();
    let every = render_pbrt(&scene, &["--every-light-max", "100", "--spp", "64"]);
    let drawn = render_pbrt(&scene, &["--spp", "64"]);
    let worst = worst_tile_difference(&every, &drawn, 6);
    assert!(worst < 0.04, "a 6 × 6 tile differs by {worst}");
    let (a, b) = (mean_of(&every), mean_of(&drawn));
    assert!(
        (a / b - 1.0).abs() < 0.01,
        "means {a} (every light) and {b} (drawn)"
    );
}
