//! pbrt's `mix` material in both dialects and the TOML format's: each point of a mixed surface
//! shows one of the two materials, the second with probability `amount` (pbrt-v3 weighs its
//! `namedmaterial1` by `amount`, pbrt-v4 chooses `materials[1]` with that probability); a mix
//! of a white and a black diffuse material renders the image of the diffuse twin of their
//! blended albedo, photons included; the image does not depend on the thread count; bad mixes
//! are refused naming their place.

mod support;

use dpm::image_io::Image;
use dpm::image_metrics::{channel_mean, relative_mse};
use dpm::scene::{self, LoadOptions, Material, TexturedParameter};
use dpm::world::{Surface, World};
use glam::{Vec2, Vec3};
use std::path::Path;
use support::pbrt::{load_text, loads, render};

const CAMERA: &str = "LookAt 0 4 0.01  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
    Film \"image\" \"integer xresolution\" 48 \"integer yresolution\" 48\nWorldBegin\n";

const WHITE_AND_BLACK: &str = "MakeNamedMaterial \"white\" \"string type\" \"matte\" \"rgb Kd\" [1 1 1]\n\
    MakeNamedMaterial \"black\" \"string type\" \"matte\" \"rgb Kd\" [0 0 0]\n";

/// A 4 × 4 floor at y = 0 with (u, v) over it, under a distant light, of `material`.
fn lit_floor(material: &str) -> String {
    format!(
        "{CAMERA}LightSource \"distant\" \"point from\" [0 1 0] \"point to\" [0 0 0] \"rgb L\" [1 1 1]\n\
         {WHITE_AND_BLACK}{material}\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point3 P\" [-2 0 2  2 0 2  2 0 -2  -2 0 -2] \"float uv\" [0 0 1 0 1 1 0 1]\n"
    )
}

/// The share of points on a `side`² grid over the floor's middle (x, z in [-1.9, 1.9]) that
/// show a material of albedo 1 rather than 0, and `Some(uv)` where the points lie.
fn white_share(world: &World, side: usize, region: Option<[f32; 4]>) -> f64 {
    let [x0, x1, z0, z1] = region.unwrap_or([-1.9, 1.9, -1.9, 1.9]);
    let mut white = 0usize;
    for i in 0..side {
        for j in 0..side {
            let x = x0 + (x1 - x0) * (i as f32 + 0.5) / side as f32;
            let z = z0 + (z1 - z0) * (j as f32 + 0.5) / side as f32;
            let hit = (world.intersect(Vec3::new(x, 1.0, z), Vec3::NEG_Y, 0.0, f32::INFINITY))
                .expect("the floor is there");
            let Surface::Material(m) = hit.surface else {
                panic!("not a material")
            };
            match world.material_at(m, &hit) {
                Material::Diffuse { albedo } if albedo == Vec3::ONE => white += 1,
                Material::Diffuse { albedo } if albedo == Vec3::ZERO => {}
                other => panic!("a mix shows one of its materials, not {other:?}"),
            }
        }
    }
    white as f64 / (side * side) as f64
}

fn world_of(text: &str) -> World {
    World::new(loads(text).0).unwrap()
}

#[test]
fn pbrt_v3_weighs_namedmaterial1_by_amount_and_pbrt_v4_chooses_its_second_with_that_probability() {
    let side = 400;
    for amount in [0.0, 0.1, 0.3, 0.75, 1.0] {
        let v3 = world_of(&lit_floor(&format!(
            "Material \"mix\" \"string namedmaterial1\" \"white\" \"string namedmaterial2\" \"black\" \
             \"rgb amount\" [{amount} {amount} {amount}]"
        )));
        let v4 = world_of(&lit_floor(&format!(
            "Material \"mix\" \"string materials\" [\"white\" \"black\"] \"float amount\" {amount}"
        )));
        let (v3_white, v4_white) = (white_share(&v3, side, None), white_share(&v4, side, None));
        eprintln!("amount {amount}: pbrt-v3 white share {v3_white:.4}, pbrt-v4 {v4_white:.4}");
        // 160,000 points: the share's standard deviation is at most 0.00125.
        assert!((v3_white - amount).abs() < 0.006, "v3 {amount}: {v3_white}");
        assert!(
            (v4_white - (1.0 - amount)).abs() < 0.006,
            "v4 {amount}: {v4_white}"
        );
        if amount == 0.0 || amount == 1.0 {
            assert_eq!(v3_white, amount);
        }
    }
    // Both dialects give pbrt-v4's convention: the second material with probability amount.
    let (v3, _) = loads(&lit_floor(
        "Material \"mix\" \"string namedmaterial1\" \"white\" \"string namedmaterial2\" \"black\" \
         \"float amount\" 0.3",
    ));
    let (v4, _) = loads(&lit_floor(
        "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [\"black\" \"white\"] \
         \"float amount\" 0.3\nNamedMaterial \"m\"",
    ));
    for scene in [&v3, &v4] {
        let mix = scene.materials[scene.shapes[0].material() as usize];
        let Material::Mix { materials, amount } = mix else {
            panic!("{mix:?}")
        };
        let [first, second] = materials.map(|m| scene.materials[m as usize]);
        assert_eq!(amount, 0.3);
        assert_eq!(first, Material::Diffuse { albedo: Vec3::ZERO });
        assert_eq!(second, Material::Diffuse { albedo: Vec3::ONE });
    }
}

#[test]
fn a_mix_of_mixes_and_a_textured_amount_choose_point_by_point() {
    // A checkerboard amount: 0.2 on the even squares, 0.9 on the odd ones.
    let text = lit_floor(
        "Texture \"a\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 2 \
         \"float tex1\" 0.2 \"float tex2\" 0.9\n\
         Material \"mix\" \"string materials\" [\"black\" \"white\"] \"texture amount\" \"a\"",
    );
    let (scene, report) = loads(&text);
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert_eq!(
        scene.textured_materials[0].textures[0].0,
        TexturedParameter::MixAmount
    );
    let world = World::new(scene).unwrap();
    // (u, v) = ((x + 2)/4, (2 − z)/4): the square u, v < ½ is x, z in (−2, 0) × (0, 2).
    let even = white_share(&world, 200, Some([-1.9, -0.1, 0.1, 1.9]));
    let odd = white_share(&world, 200, Some([0.1, 1.9, 0.1, 1.9]));
    eprintln!("textured amount: even squares {even:.4}, odd {odd:.4}");
    assert!((even - 0.2).abs() < 0.01 && (odd - 0.9).abs() < 0.01);
    // A mix of a mix: white with probability ½ · ½.
    let nested = world_of(&lit_floor(
        "MakeNamedMaterial \"half\" \"string type\" \"mix\" \"string materials\" [\"black\" \"white\"]\n\
         Material \"mix\" \"string materials\" [\"black\" \"half\"] \"float amount\" 0.5",
    ));
    let share = white_share(&nested, 400, None);
    eprintln!("a mix of mixes: white share {share:.4}");
    assert!((share - 0.25).abs() < 0.006, "{share}");
}

#[test]
fn a_named_material_redefined_after_the_mix_leaves_the_mix_as_it_was() {
    let (scene, _) = loads(&lit_floor(
        "Material \"mix\" \"string materials\" [\"black\" \"white\"] \"float amount\" 1\n\
         MakeNamedMaterial \"white\" \"string type\" \"matte\" \"rgb Kd\" [0.5 0.5 0.5]",
    ));
    let Material::Mix { materials, .. } = scene.materials[scene.shapes[0].material() as usize]
    else {
        panic!()
    };
    assert_eq!(
        scene.materials[materials[1] as usize],
        Material::Diffuse { albedo: Vec3::ONE }
    );
}

#[test]
fn a_colourful_amount_is_approximated_by_its_mean_with_a_warning_refused_under_strict() {
    let text = lit_floor(
        "Material \"mix\" \"string namedmaterial1\" \"white\" \"string namedmaterial2\" \"black\" \
         \"rgb amount\" [0.1 0.3 0.5]",
    );
    let (scene, report) = loads(&text);
    let Material::Mix { amount, .. } = scene.materials[scene.shapes[0].material() as usize] else {
        panic!()
    };
    assert!((amount - 0.3).abs() < 1e-6, "{amount}");
    assert!(
        report.warnings.iter().any(|w| w.contains("amount")),
        "{:?}",
        report.warnings
    );
    let dir = tempfile::tempdir().unwrap();
    let path = support::write_scene(dir.path(), "scene.pbrt", &text);
    let e = scene::load_with_options(&path, &LoadOptions::strict()).unwrap_err();
    assert!(
        e.line == Some(8) && e.to_string().contains("--strict"),
        "{e}"
    );
}

/// A 4 × 4 floor and a sphere over it under a white sky, the sphere and floor of `material`.
fn sky_scene(material: &str) -> String {
    format!(
        "{CAMERA}LightSource \"infinite\" \"rgb L\" [1 1 1]\n{WHITE_AND_BLACK}{material}\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point3 P\" [-2 0 2  2 0 2  2 0 -2  -2 0 -2]\n\
         Translate 0 0.8 0\nShape \"sphere\" \"float radius\" 0.8\n"
    )
}

/// Two passes of the scene at `path` on `threads` threads, plus `extra` arguments.
fn render_file(path: &Path, threads: &str, extra: &[&str]) -> Image {
    let out = path.with_extension(format!("{threads}.{}.pfm", extra.join("_")));
    let mut args = vec![
        support::path_str(path),
        "-o",
        support::path_str(&out),
        "--threads",
        threads,
        "--passes",
        "2",
    ];
    args.extend_from_slice(extra);
    dpm::render::pipeline::run(&support::render_args(&args))
        .unwrap()
        .image
}

fn mean(image: &Image) -> f64 {
    image.pixels.iter().map(|p| channel_mean(*p)).sum::<f64>() / image.pixels.len() as f64
}

/// The mean of each `block` × `block` square of pixels.
fn blocks(image: &Image, block: usize) -> Vec<f64> {
    let (w, h) = (image.width / block, image.height / block);
    let mut out = vec![0.0; w * h];
    for y in 0..h * block {
        for x in 0..w * block {
            out[(y / block) * w + x / block] += channel_mean(image.pixels[y * image.width + x]);
        }
    }
    out.iter().map(|s| s / (block * block) as f64).collect()
}

#[test]
fn a_white_and_black_mix_renders_the_image_of_its_blended_diffuse_twin() {
    let dir = tempfile::tempdir().unwrap();
    let mix = sky_scene(
        "Material \"mix\" \"string materials\" [\"black\" \"white\"] \"float amount\" 0.5",
    );
    let twin = sky_scene("Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]");
    let spp = ["--spp", "16"];
    let a = render(dir.path(), "mix.pbrt", &mix, "5", &spp);
    let a2 = render(dir.path(), "mix.pbrt", &mix, "6", &spp);
    let b = render(dir.path(), "twin.pbrt", &twin, "5", &spp);
    let (mix_mean, twin_mean) = (mean(&a), mean(&b));
    // 8 × 8 blocks: each point's choice is noise that a pixel's 16 samples do not average out.
    let difference = relative_mse(&blocks(&a, 8), &blocks(&b, 8));
    let noise = relative_mse(&blocks(&a, 8), &blocks(&a2, 8));
    eprintln!(
        "image mean: mix {mix_mean:.5}, twin {twin_mean:.5}; 8×8 blocks: mix against twin \
         {difference:.3e}, mix seeds apart {noise:.3e}"
    );
    assert!((mix_mean / twin_mean - 1.0).abs() < 0.01);
    assert!(difference < noise, "{difference:.3e} against {noise:.3e}");
}

#[test]
fn photons_landing_on_a_mix_count_whichever_material_their_point_shows() {
    // Half the points a white diffuse surface, half a mirror that reflects nothing: the
    // diffuse twin of albedo ½, as long as the photon maps count the photons that land on
    // the mirror points too (the density they estimate is over the whole surface).
    let room = |material: &str| {
        // A closed 4 × 3 × 4 box lit from inside, seen from inside: light bounces many times.
        format!(
            "LookAt 0 1.5 1.9  0 1.2 -2  0 1 0\nCamera \"perspective\" \"float fov\" 70\n\
             Film \"image\" \"integer xresolution\" 48 \"integer yresolution\" 32\nWorldBegin\n\
             LightSource \"point\" \"point from\" [0.5 2.5 0] \"rgb I\" [8 8 8]\n\
             MakeNamedMaterial \"white\" \"string type\" \"matte\" \"rgb Kd\" [1 1 1]\n\
             MakeNamedMaterial \"void\" \"string type\" \"mirror\" \"rgb Kr\" [0 0 0]\n{material}\n\
             Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3  4 5 6 4 6 7  0 1 5 0 5 4  \
             1 2 6 1 6 5  2 3 7 2 7 6  3 0 4 3 4 7] \
             \"point3 P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2  -2 3 -2  2 3 -2  2 3 2  -2 3 2]\n"
        )
    };
    let dir = tempfile::tempdir().unwrap();
    let mix = room("Material \"mix\" \"string materials\" [\"void\" \"white\"]");
    let twin = room("Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]");
    let render = |name: &str, text: &str, global_photons: &str| {
        let path = support::write_scene(dir.path(), name, text);
        let extra = ["--spp", "8", "--global-photons", global_photons];
        mean(&render_file(&path, "2", &extra))
    };
    let mix_mean = render("mix.pbrt", &mix, "100000");
    let twin_mean = render("twin.pbrt", &twin, "100000");
    let direct_mean = render("twin.pbrt", &twin, "0");
    eprintln!(
        "image mean: mix {mix_mean:.5}, twin {twin_mean:.5}, twin without indirect light \
         {direct_mean:.5}"
    );
    // Indirect light is a third of the picture or more, so losing the photons that land on
    // the mirror points (half of them) would show.
    assert!(twin_mean > 1.5 * direct_mean);
    assert!((mix_mean / twin_mean - 1.0).abs() < 0.02);
}

#[test]
fn a_textured_mix_renders_the_same_image_on_one_and_two_threads() {
    let dir = tempfile::tempdir().unwrap();
    let text = sky_scene(
        "Texture \"a\" \"float\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 4 \
         \"float tex1\" 0.2 \"float tex2\" 0.7\n\
         MakeNamedMaterial \"gloss\" \"string type\" \"plastic\" \"rgb Kd\" [0.2 0.3 0.6]\n\
         Material \"mix\" \"string materials\" [\"gloss\" \"white\"] \"texture amount\" \"a\"",
    );
    let path = support::write_scene(dir.path(), "mix.pbrt", &text);
    let photons = ["--caustic-photons", "20000", "--global-photons", "20000"];
    let image = |threads: &str| render_file(&path, threads, &photons);
    let (one, two) = (image("1"), image("2"));
    assert!(one.pixels.iter().any(|p| p.max_element() > 0.0));
    assert!(
        one.pixels == two.pixels,
        "the image differs between 1 and 2 threads"
    );
}

#[test]
fn bad_mixes_are_refused_naming_their_place() {
    let dir = tempfile::tempdir().unwrap();
    for (material, says) in [
        (
            "Material \"mix\" \"string materials\" [\"white\" \"grey\"]",
            "\"string materials\": no material is named \"grey\"",
        ),
        (
            "Material \"mix\" \"string namedmaterial1\" \"white\"",
            "needs \"string namedmaterial2\"",
        ),
        (
            "Material \"mix\" \"string materials\" [\"white\" \"black\" \"white\"]",
            "two materials, not 3",
        ),
        (
            "Material \"mix\" \"string materials\" [\"white\" \"black\"] \"float amount\" -0.5",
            "amount -0.5 is not in [0, 1]",
        ),
        // A mix names only materials defined before it.
        (
            "Material \"mix\" \"string materials\" [\"white\" \"later\"]\n\
             MakeNamedMaterial \"later\" \"string type\" \"matte\"",
            "no material is named \"later\"",
        ),
    ] {
        let e = load_text(dir.path(), &lit_floor(material)).unwrap_err();
        assert!(
            e.line == Some(8) && e.column.is_some() && e.to_string().contains(says),
            "{material}: {e}"
        );
    }
}

/// A TOML floor under a distant light, its material `m` a mix of `white` and `black` with
/// `fields`.
fn toml_floor(fields: &str) -> String {
    format!(
        "[camera]\nposition = [0.0, 4.0, 0.01]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\n\
         fov_y = 45.0\nresolution = [8, 8]\n\n\
         [[lights]]\ntype = \"distant\"\ndirection = [0.0, -1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n\n\
         [materials.white]\ntype = \"diffuse\"\nalbedo = [1.0, 1.0, 1.0]\n\n\
         [materials.black]\ntype = \"diffuse\"\nalbedo = [0.0, 0.0, 0.0]\n\n\
         [materials.m]\ntype = \"mix\"\n{fields}\n\n\
         [[objects]]\ntype = \"quad\"\ncorner = [-2.0, 0.0, 2.0]\nedge_u = [4.0, 0.0, 0.0]\n\
         edge_v = [0.0, 0.0, -4.0]\nmaterial = \"m\"\n"
    )
}

#[test]
fn a_toml_mix_shows_its_second_material_with_probability_amount() {
    let world = support::world(&toml_floor(
        "materials = [\"black\", \"white\"]\namount = 0.3",
    ));
    let share = white_share(&world, 400, None);
    eprintln!("TOML mix of amount 0.3: white share {share:.4}");
    assert!((share - 0.3).abs() < 0.006, "{share}");
    // The default amount is ½; a texture table's channels' mean is read at each point.
    let even_odd = support::description(&toml_floor(
        "materials = [\"white\", \"black\"]\namount = { checkerboard = [[0.1, 0.1, 0.1], [0.8, 0.8, 0.8]] }",
    ));
    let t = &even_odd.textured_materials[0];
    assert_eq!(t.textures[0].0, TexturedParameter::MixAmount);
    let mix = even_odd.materials[t.material as usize];
    let evaluated = t.evaluate(&mix, Vec2::new(0.25, 0.25));
    assert!(
        matches!(evaluated, Material::Mix { amount, .. } if amount == 0.1),
        "{evaluated:?}"
    );
    let plain = support::description(&toml_floor("materials = [\"white\", \"black\"]"));
    let m = plain.materials[plain.shapes[0].material() as usize];
    assert!(
        matches!(m, Material::Mix { amount, .. } if amount == 0.5),
        "{m:?}"
    );
}

#[test]
fn a_mix_reads_photons_and_makes_caustics_where_either_of_its_materials_does() {
    let world = |first: &str, second: &str| {
        world_of(&lit_floor(&format!(
            "MakeNamedMaterial \"glass\" \"string type\" \"glass\"\n\
             MakeNamedMaterial \"chrome\" \"string type\" \"mirror\"\n\
             Material \"mix\" \"string materials\" [\"{first}\" \"{second}\"]"
        )))
    };
    let floor = |w: &World| w.description.shapes[0].material();
    let specular = world("glass", "chrome");
    assert!(!specular.reads_photons(floor(&specular)) && !specular.caustic_targets.is_empty());
    let half = world("white", "chrome");
    assert!(half.reads_photons(floor(&half)) && !half.caustic_targets.is_empty());
    let diffuse = world("white", "black");
    assert!(diffuse.reads_photons(floor(&diffuse)) && diffuse.caustic_targets.is_empty());
}
