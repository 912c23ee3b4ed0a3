//! Textures end to end: a textured quad under a distant light shows the texture times what an
//! untextured quad shows (closed form: L = albedo · E / π); sRGB decoding of 8-bit images;
//! texture coordinates read back from pbrt `trianglemesh`, PLY and OBJ; a sphere's parametric
//! (u, v); malformed textures refused with file:line:column, and `dpm render` exiting 2.

mod support;

use dpm::scene::{self, Material, Shape, Texture};
use dpm::world::World;
use glam::{DVec3, Vec2, Vec3};
use std::f64::consts::PI;
use std::path::Path;
use support::eye::{radiance_along, whitted};
use support::pbrt::{load_text, loads, world as pbrt_world};

/// A PFM file of grey `values`, rows listed top first (PFM stores them bottom first).
fn write_grey_pfm(path: &Path, width: usize, rows_top_first: &[&[f32]]) {
    let mut bytes = format!("PF\n{width} {}\n-1.0\n", rows_top_first.len()).into_bytes();
    for row in rows_top_first.iter().rev() {
        for &v in row.iter() {
            for _ in 0..3 {
                bytes.extend(v.to_le_bytes());
            }
        }
    }
    std::fs::write(path, bytes).unwrap();
}

/// A 2 × 2 grey PNG of 8-bit `values`, top row first.
fn write_grey_png(path: &Path, values: [u8; 4]) {
    image::GrayImage::from_raw(2, 2, values.to_vec())
        .unwrap()
        .save(path)
        .unwrap();
}

/// A 2 × 2 quad at y = 0 facing up (x, z in [-1, 1]; u runs along +x, v along −z) lit
/// straight down by a distant light of irradiance 1, with `albedo` as its TOML value.
fn lit_quad(albedo: &str) -> String {
    format!(
        "[camera]\nposition = [0.0, 3.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
         fov_y = 60.0\nresolution = [8, 8]\n\n\
         [[lights]]\ntype = \"distant\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n\n\
         [materials.floor]\ntype = \"diffuse\"\nalbedo = {albedo}\n\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-1.0, 0.0, 1.0]\nedge_u = [2.0, 0.0, 0.0]\n\
         edge_v = [0.0, 0.0, -2.0]\nmaterial = \"floor\"\n"
    )
}

fn world_in(dir: &Path, text: &str) -> World {
    let path = support::write_scene(dir, "scene.toml", text);
    World::new(scene::load(&path).unwrap_or_else(|e| panic!("{e}"))).unwrap()
}

/// The radiance seen straight down at (x, z) on [`lit_quad`].
fn seen_at(world: &World, x: f64, z: f64) -> DVec3 {
    radiance_along(&whitted(world, 1), DVec3::new(x, 1.0, z), DVec3::NEG_Y)
}

#[test]
fn a_textured_quad_shows_the_texture_times_the_untextured_quads_radiance() {
    let dir = tempfile::tempdir().unwrap();
    // Texel values 0.1 0.3 (top row) over 0.5 0.9; their mean is 0.45.
    write_grey_pfm(&dir.path().join("grey.pfm"), 2, &[&[0.1, 0.3], &[0.5, 0.9]]);
    let textured = world_in(dir.path(), &lit_quad("{ image = \"grey.pfm\" }"));
    let white = world_in(dir.path(), &lit_quad("[1.0, 1.0, 1.0]"));
    let one = seen_at(&white, 0.1, 0.2).x;
    assert!((one - 1.0 / PI).abs() < 1e-5, "L = E/π for albedo 1: {one}");
    // Texel centres: u, v = 1/4 or 3/4, so x = 2u − 1, z = 1 − 2v; v = 3/4 is the top row.
    for (u, v, texel) in [
        (0.25, 0.75, 0.1),
        (0.75, 0.75, 0.3),
        (0.25, 0.25, 0.5),
        (0.75, 0.25, 0.9),
    ] {
        let got = seen_at(&textured, 2.0 * u - 1.0, 1.0 - 2.0 * v).x;
        assert!(
            (got - texel * one).abs() < 1e-4 * one,
            "({u}, {v}): {got} against {}",
            texel * one
        );
    }
    // The mean over the quad (repeat wrap: bilinear over one period keeps the texel mean).
    let n = 40;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let (x, z) = (
                -1.0 + 2.0 * (i as f64 + 0.5) / n as f64,
                -1.0 + 2.0 * (j as f64 + 0.5) / n as f64,
            );
            sum += seen_at(&textured, x, z).x;
        }
    }
    let mean = sum / (n * n) as f64;
    assert!(
        (mean - 0.45 * one).abs() < 2e-3 * one,
        "{mean} against {}",
        0.45 * one
    );
}

#[test]
fn a_checkerboard_quad_averages_its_two_colours() {
    let dir = tempfile::tempdir().unwrap();
    let board = "{ checkerboard = [[0.8, 0.8, 0.8], [0.2, 0.2, 0.2]], uv_scale = [4.0, 4.0] }";
    let world = world_in(dir.path(), &lit_quad(board));
    let n = 64;
    let mut sum = 0.0;
    for i in 0..n {
        for j in 0..n {
            let x = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
            let z = -1.0 + 2.0 * (j as f64 + 0.5) / n as f64;
            sum += seen_at(&world, x, z).x;
        }
    }
    let mean = sum / (n * n) as f64;
    let want = 0.5 * (0.8 + 0.2) / PI;
    assert!((mean - want).abs() < 1e-4, "{mean} against {want}");
}

#[test]
fn eight_bit_images_decode_from_srgb_unless_told_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    write_grey_png(&dir.path().join("grey.png"), [128, 128, 128, 128]);
    let texel = |albedo: &str| {
        let w = world_in(dir.path(), &lit_quad(albedo));
        seen_at(&w, 0.0, 0.0).x * PI
    };
    // sRGB 128/255 = 0.50196 decodes to ((0.50196 + 0.055) / 1.055)^2.4 = 0.21586.
    let decoded = texel("{ image = \"grey.png\" }");
    assert!((decoded - 0.215_861).abs() < 1e-4, "{decoded}");
    let raw = texel("{ image = \"grey.png\", srgb = false }");
    assert!((raw - 128.0 / 255.0).abs() < 1e-4, "{raw}");
    // pbrt: `gamma` defaults to true for PNG; false keeps the file's values.
    for (gamma, want) in [("", 0.215_861), ("\"bool gamma\" false", 128.0 / 255.0)] {
        let text = pbrt_world(&format!(
            "Texture \"g\" \"spectrum\" \"imagemap\" \"string filename\" \"grey.png\" {gamma}\n\
             Material \"matte\" \"texture Kd\" \"g\"\nShape \"sphere\"\n"
        ));
        let (s, _) = load_text(dir.path(), &text).unwrap();
        let Texture::Image { image, .. } = &s.textured_materials[0].textures[0].1 else {
            panic!("not an image texture");
        };
        assert!(
            (image.texels[0].x - want).abs() < 1e-5,
            "{gamma}: {:?}",
            image.texels[0]
        );
    }
}

#[test]
fn texture_coordinates_read_back_from_pbrt_ply_and_obj() {
    for uv in [
        "\"float uv\" [0 0 1 0 1 1]",
        "\"point2 uv\" [0 0 1 0 1 1]",
        "\"float st\" [0 0 1 0 1 1]",
    ] {
        let (s, _) = loads(&pbrt_world(&format!(
            "Shape \"trianglemesh\" \"point P\" [0 0 0 1 0 0 1 1 0] \"integer indices\" [0 1 2] {uv}\n"
        )));
        let Shape::Triangles(mesh) = &s.shapes[0] else {
            panic!()
        };
        assert_eq!(
            mesh.uvs.as_deref(),
            Some(&[Vec2::ZERO, Vec2::X, Vec2::ONE][..]),
            "{uv}"
        );
    }
    for (u, v) in [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ] {
        let ply = format!(
            "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nproperty float {u}\nproperty float {v}\nelement face 1\n\
             property list uchar int vertex_indices\nend_header\n\
             0 0 0 0.25 0.5\n1 0 0 0.75 0.5\n0 1 0 0.25 1\n3 0 1 2\n"
        );
        let mesh = scene::ply::parse(ply.as_bytes()).unwrap();
        let want = [
            Vec2::new(0.25, 0.5),
            Vec2::new(0.75, 0.5),
            Vec2::new(0.25, 1.0),
        ];
        assert_eq!(mesh.uvs.as_deref(), Some(&want[..]), "{u}, {v}");
    }
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("tri.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.1 0.2\nvt 0.3 0.4\nvt 0.5 0.6\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    let text = lit_quad("[0.5, 0.5, 0.5]")
        + "\n[[objects]]\ntype = \"mesh\"\nfile = \"tri.obj\"\nmaterial = \"floor\"\n";
    let path = support::write_scene(dir.path(), "scene.toml", &text);
    let s = scene::load(&path).unwrap();
    let Shape::Triangles(mesh) = &s.shapes[1] else {
        panic!()
    };
    let uvs = mesh.uvs.as_deref().unwrap();
    assert_eq!(
        uvs,
        &[
            Vec2::new(0.1, 0.2),
            Vec2::new(0.3, 0.4),
            Vec2::new(0.5, 0.6)
        ]
    );
}

#[test]
fn hits_resolve_their_uv_on_meshes_without_uv_and_on_spheres() {
    // A mesh without uv takes pbrt's corners (0, 0), (1, 0), (1, 1); the sphere sits at
    // (0, 5, 0), unturned, so its (u, v) are measured along the world's axes.
    let text = pbrt_world(
        "Texture \"c\" \"spectrum\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 2\n\
         Material \"matte\" \"texture Kd\" \"c\"\n\
         Shape \"trianglemesh\" \"point P\" [-1 0 -1  1 0 -1  1 0 1] \"integer indices\" [0 1 2]\n\
         AttributeBegin\nTranslate 0 5 0\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n",
    );
    let (s, _) = loads(&text);
    let world = World::new(s).unwrap();
    let down = |x: f32, z: f32| {
        world
            .intersect(Vec3::new(x, 1.0, z), Vec3::NEG_Y, 0.0, 3.0)
            .unwrap()
    };
    // (0.9, −0.5) = P0 + 0.7 (P1 − P0) + 0.25 (P2 − P0): uv = 0.7 (1, 0) + 0.25 (1, 1).
    let hit = down(0.9, -0.5);
    let uv = world.uv_at(&hit);
    assert!(
        (uv - Vec2::new(0.95, 0.25)).abs().max_element() < 1e-5,
        "{uv}"
    );
    // Checkerboard at (s, t) = (1.9, 0.5): ⌊s⌋ + ⌊t⌋ = 1 is odd, tex2 = 0.
    assert_eq!(
        world.material_at(0, &hit),
        Material::Diffuse { albedo: Vec3::ZERO }
    );
    // (0.2, −0.8): b1 = 0.5, b2 = 0.1, uv = (0.6, 0.1), (s, t) = (1.2, 0.2): tex2 again;
    // (−0.5, −0.9): b1 = 0.2, b2 = 0.05, uv = (0.25, 0.05): tex1 = 1.
    let white = world.material_at(0, &down(-0.5, -0.9));
    assert_eq!(white, Material::Diffuse { albedo: Vec3::ONE });
    let centre = Vec3::new(0.0, 5.0, 0.0);
    for (from, want) in [
        (Vec3::Z, Vec2::new(f32::NAN, 1.0)),
        (Vec3::NEG_Z, Vec2::new(f32::NAN, 0.0)),
        (Vec3::X, Vec2::new(0.0, 0.5)),
        (Vec3::Y, Vec2::new(0.25, 0.5)),
        (Vec3::NEG_X, Vec2::new(0.5, 0.5)),
    ] {
        let hit = world
            .intersect(centre + 3.0 * from, -from, 0.0, f32::INFINITY)
            .unwrap();
        let uv = world.uv_at(&hit);
        if !want.x.is_nan() {
            assert!((uv.x - want.x).abs() < 1e-3, "{from}: {uv}");
        }
        assert!((uv.y - want.y).abs() < 1e-3, "{from}: {uv}");
    }
}

#[test]
fn a_turned_sphere_measures_its_uv_along_its_own_axes() {
    // pbrt's Sphere takes (u, v) at the hit in object space: u = φ/2π with φ = atan2(y, x)
    // in [0, 2π), v = (θ − θ_min)/(θ_max − θ_min) = 1 − θ/π for a full sphere. The object
    // frame here is turned 130° about x, then 30° about z, and scaled by 2, mirrored in x.
    let text = pbrt_world(
        "Texture \"c\" \"spectrum\" \"checkerboard\"\n\
         Material \"matte\" \"texture Kd\" \"c\"\n\
         AttributeBegin\nTranslate 0 5 0\nRotate 130 1 0 0\nRotate 30 0 0 1\nScale -2 2 2\n\
         Shape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n",
    );
    let (s, _) = loads(&text);
    let world = World::new(s).unwrap();
    let centre = Vec3::new(0.0, 5.0, 0.0);
    let object_to_world = glam::Mat3::from_axis_angle(Vec3::X, 130f32.to_radians())
        * glam::Mat3::from_axis_angle(Vec3::Z, 30f32.to_radians())
        * glam::Mat3::from_diagonal(Vec3::new(-2.0, 2.0, 2.0));
    let world_to_object = object_to_world.inverse();
    let mut rng = dpm::sampling::Rng::for_index(7, dpm::sampling::Stream::Distribution, 0);
    for _ in 0..200 {
        let from = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        )
        .normalize();
        let hit = world
            .intersect(centre + 3.0 * from, -from, 0.0, f32::INFINITY)
            .unwrap();
        let p = world_to_object * (hit.position - centre);
        let phi = (p.y.atan2(p.x) + std::f32::consts::TAU) % std::f32::consts::TAU;
        let theta = (p.z / p.length()).clamp(-1.0, 1.0).acos();
        let want = Vec2::new(
            phi / std::f32::consts::TAU,
            1.0 - theta / std::f32::consts::PI,
        );
        let uv = world.uv_at(&hit);
        // u wraps at φ = 0.
        let du = (uv.x - want.x).abs();
        assert!(du.min(1.0 - du) < 2e-3, "{from}: {uv} against {want}");
        assert!((uv.y - want.y).abs() < 2e-3, "{from}: {uv} against {want}");
    }
}

#[test]
fn malformed_textures_are_refused_naming_file_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("bad.png"), b"\x89PNG\r\n\x1a\nnot really").unwrap();
    for (body, needle) in [
        (
            "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"missing.png\"\n",
            "cannot read",
        ),
        (
            "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"bad.png\"\n",
            "bad.png",
        ),
        ("Texture \"t\" \"spectrum\" \"wrinkled\"\n", "not supported"),
        (
            "Material \"matte\" \"texture Kd\" \"nowhere\"\n",
            "no texture is named \"nowhere\"",
        ),
        (
            "Texture \"f\" \"float\" \"constant\"\nMaterial \"matte\" \"texture Kd\" \"f\"\n",
            "float texture",
        ),
        (
            "Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"bad.png\" \"string wrap\" \"mirror\"\n",
            "wrap",
        ),
    ] {
        // Every texture is used: an unused one that cannot be read is no error (see below).
        let used = if body.contains("Material") {
            ""
        } else {
            "Material \"matte\" \"texture Kd\" \"t\"\n"
        };
        let text = pbrt_world(&format!("{body}{used}Shape \"sphere\"\n"));
        let err = load_text(dir.path(), &text).unwrap_err();
        assert!(err.message.contains(needle), "{body}: {err}");
        assert!(err.line.is_some() && err.column.is_some(), "{body}: {err}");
        assert!(err.to_string().contains("scene.pbrt:"), "{body}: {err}");
    }
    // A texture only a bump map uses (dpm ignores bump maps) may be one dpm cannot read.
    let bump = pbrt_world(
        "Texture \"b\" \"float\" \"fbm\"\nMaterial \"matte\" \"texture bumpmap\" \"b\"\nShape \"sphere\"\n",
    );
    let (_, report) = load_text(dir.path(), &bump).unwrap();
    assert!(
        report.warnings.iter().any(|w| w.contains("bumpmap")),
        "{report:?}"
    );
    // The same through `dpm render`: exit status 2 and the place in the message.
    let text = pbrt_world("Material \"matte\" \"texture Kd\" \"nowhere\"\nShape \"sphere\"\n");
    let scene = support::write_scene(dir.path(), "cli.pbrt", &text);
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_dpm"))
        .args(["render", support::path_str(&scene), "-o"])
        .arg(dir.path().join("out.pfm"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("cli.pbrt:") && stderr.contains("texture Kd"),
        "{stderr}"
    );
    // TOML: a missing image names the field.
    let path = support::write_scene(dir.path(), "t.toml", &lit_quad("{ image = \"gone.png\" }"));
    let err = scene::load(&path).unwrap_err();
    assert_eq!(err.field, "materials.floor.albedo.image", "{err}");
    assert!(err.line.is_some(), "{err}");
}

#[test]
fn an_untextured_scene_has_no_textured_materials() {
    let s = support::description(&lit_quad("[0.5, 0.5, 0.5]"));
    assert!(s.textured_materials.is_empty());
    // A constant texture in pbrt folds into the material's own value.
    let (s, _) = loads(&pbrt_world(
        "Texture \"k\" \"spectrum\" \"constant\" \"rgb value\" [0.2 0.3 0.4]\n\
         Material \"matte\" \"texture Kd\" \"k\"\nShape \"sphere\"\n",
    ));
    assert!(s.textured_materials.is_empty());
    assert_eq!(
        s.materials[0],
        Material::Diffuse {
            albedo: Vec3::new(0.2, 0.3, 0.4)
        }
    );
}

#[test]
fn the_image_fuzz_seeds_decode() {
    use dpm::image_io::{SceneImageFormat, decode_linear};
    let formats = [
        SceneImageFormat::Exr,
        SceneImageFormat::Pfm,
        SceneImageFormat::Png,
        SceneImageFormat::Tga,
    ];
    let dir = support::repo_path("fuzz/corpus/image");
    let mut seeds = 0;
    for entry in std::fs::read_dir(dir).unwrap() {
        let bytes = std::fs::read(entry.unwrap().path()).unwrap();
        let format = formats[usize::from(bytes[0] & 3)];
        let image = decode_linear(&bytes[1..], format, bytes[0] & 4 != 0).unwrap();
        assert_eq!((image.width, image.height), (2, 2));
        seeds += 1;
    }
    assert!(seeds >= 3);
}
