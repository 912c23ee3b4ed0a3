//! Textures on a BSDF material's parameters beyond its diffuse colour: each pbrt name becomes
//! the model parameter it is (roughness with its material's remap and axes), a plastic whose
//! `Ks` is a checkerboard shows, square by square, what a plastic of that square's constant
//! `Ks` shows, a textured roughness renders the image of the constant it evaluates to, and the
//! TOML format's colour fields take the texture tables `kd` takes.

mod support;

use dpm::bsdf::{Axes, Model, ModelParameter as P, Remap};
use dpm::image_metrics::image_relative_mse;
use dpm::scene::{Material, Texture, TexturedParameter};
use dpm::world::World;
use glam::{DVec3, Vec3};
use support::eye::{radiance_along, whitted};
use support::pbrt::{loads, render, world as pbrt_world};

/// The textured parameters of the one textured material of pbrt `body`, with its material.
fn textured(body: &str) -> (Material, Vec<(TexturedParameter, Texture)>) {
    let (scene, _) = loads(&pbrt_world(body));
    assert_eq!(scene.textured_materials.len(), 1, "{body}");
    let t = &scene.textured_materials[0];
    (scene.materials[t.material as usize], t.textures.clone())
}

fn parameters(body: &str) -> Vec<TexturedParameter> {
    textured(body).1.into_iter().map(|(p, _)| p).collect()
}

const CHECKER: &str = "Texture \"c\" \"spectrum\" \"checkerboard\" \"float uscale\" 2 \
    \"float vscale\" 2 \"rgb tex1\" [0.8 0.8 0.8] \"rgb tex2\" [0.1 0.1 0.1]\n\
    Texture \"f\" \"float\" \"checkerboard\" \"float uscale\" 2 \"float vscale\" 2 \
    \"float tex1\" 0.05 \"float tex2\" 0.5\n";

fn model(kind: &str, params: &str) -> String {
    format!("{CHECKER}Material \"{kind}\" {params}\nShape \"sphere\"\n")
}

fn model_parameter(p: P) -> TexturedParameter {
    TexturedParameter::Model(p)
}

fn roughness(axes: Axes, remap: Remap, conductor: bool) -> TexturedParameter {
    model_parameter(P::Roughness {
        axes,
        remap,
        conductor,
    })
}

#[test]
fn each_pbrt_parameter_becomes_the_model_parameter_it_is() {
    let cases: Vec<(&str, &str, Vec<TexturedParameter>)> = vec![
        (
            "uber",
            "\"texture Kd\" \"c\" \"texture Ks\" \"c\" \"texture Kr\" \"c\" \"texture Kt\" \"c\" \
             \"texture opacity\" \"c\" \"texture index\" \"f\" \"texture roughness\" \"f\"",
            vec![
                model_parameter(P::Diffuse),
                model_parameter(P::Specular),
                model_parameter(P::Reflection),
                model_parameter(P::Transmission),
                roughness(Axes::Both, Remap::PbrtV3, false),
                model_parameter(P::Eta),
                model_parameter(P::Opacity),
            ],
        ),
        (
            "translucent",
            "\"texture reflect\" \"c\" \"texture transmit\" \"c\"",
            vec![model_parameter(P::Reflect), model_parameter(P::Transmit)],
        ),
        // uroughness takes precedence: the isotropic roughness gives v alone.
        (
            "plastic",
            "\"texture roughness\" \"f\" \"float uroughness\" 0.2 \"bool remaproughness\" false",
            vec![roughness(Axes::V, Remap::None, false)],
        ),
        (
            "metal",
            "\"texture eta\" \"c\" \"texture k\" \"f\" \"texture uroughness\" \"f\"",
            vec![
                roughness(Axes::U, Remap::PbrtV3, false),
                model_parameter(P::ConductorEta),
                model_parameter(P::ConductorK),
            ],
        ),
        (
            "conductor",
            "\"texture reflectance\" \"c\" \"texture roughness\" \"f\"",
            vec![
                roughness(Axes::Both, Remap::PbrtV4, false),
                model_parameter(P::ConductorReflectance),
            ],
        ),
        (
            "dielectric",
            "\"texture eta\" \"f\" \"texture roughness\" \"f\"",
            vec![
                model_parameter(P::Eta),
                roughness(Axes::Both, Remap::PbrtV4, false),
            ],
        ),
        (
            "coateddiffuse",
            "\"texture reflectance\" \"c\" \"texture roughness\" \"f\" \"texture thickness\" \"f\"",
            vec![
                model_parameter(P::Diffuse),
                roughness(Axes::Both, Remap::PbrtV4, false),
                model_parameter(P::Thickness),
            ],
        ),
        (
            "coatedconductor",
            "\"texture interface.roughness\" \"f\" \"texture conductor.roughness\" \"f\" \
             \"texture conductor.eta\" \"c\"",
            vec![
                roughness(Axes::Both, Remap::PbrtV4, false),
                model_parameter(P::ConductorEta),
                roughness(Axes::Both, Remap::PbrtV4, true),
            ],
        ),
        // Oren–Nayar's sigma is not a parameter dpm varies: it keeps its typical value.
        (
            "matte",
            "\"texture sigma\" \"f\" \"texture Kd\" \"c\"",
            vec![TexturedParameter::Albedo],
        ),
    ];
    for (kind, params, expected) in cases {
        let mut got = parameters(&model(kind, params));
        let mut expected = expected;
        let key = |p: &TexturedParameter| format!("{p:?}");
        got.sort_by_key(key);
        expected.sort_by_key(key);
        assert_eq!(got, expected, "{kind} {params}");
    }
}

#[test]
fn a_diffuse_transmitters_scale_multiplies_its_textures_and_an_uber_stays_a_model() {
    let (_, textures) = textured(&model(
        "diffusetransmission",
        "\"texture reflectance\" \"c\" \"float scale\" 0.5",
    ));
    let [(parameter, texture)] = &textures[..] else {
        panic!("{textures:?}")
    };
    assert_eq!(*parameter, model_parameter(P::Diffuse));
    // The even squares: 0.8 × 0.5.
    let v = texture.evaluate(glam::Vec2::new(0.1, 0.1));
    assert!((v - Vec3::splat(0.4)).abs().max_element() < 1e-6, "{v}");
    // An uber of opacity ½ and no Ks is one Lambert lobe of ½ Kd: a textured Kd must stay the
    // model's (a diffuse material's albedo would be Kd itself).
    let (material, textures) = textured(&model(
        "uber",
        "\"texture Kd\" \"c\" \"rgb Ks\" [0 0 0] \"rgb opacity\" [0.5 0.5 0.5]",
    ));
    assert!(
        matches!(material, Material::Bsdf(Model::Uber { .. })),
        "{material:?}"
    );
    assert_eq!(textures[0].0, model_parameter(P::Diffuse));
    // A plastic without Ks is diffuse, its Kd texture its albedo.
    let (material, textures) =
        textured(&model("plastic", "\"texture Kd\" \"c\" \"rgb Ks\" [0 0 0]"));
    assert!(matches!(material, Material::Diffuse { .. }), "{material:?}");
    assert_eq!(textures[0].0, TexturedParameter::Albedo);
}

/// A 2 × 2 quad at y = 0 facing up, (u, v) over it (x = 2u − 1, z = 1 − 2v), of plastic
/// with `ks`, under a distant light from (1, 1, 0).
fn glossy_quad(ks: &str) -> String {
    pbrt_world(&format!(
        "{CHECKER}LightSource \"distant\" \"point from\" [1 1 0] \"point to\" [0 0 0] \"rgb L\" [2 2 2]\n\
         Material \"plastic\" \"rgb Kd\" [0.3 0.3 0.3] {ks} \"float roughness\" 0.3 \
         \"bool remaproughness\" false\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point3 P\" [-1 0 1  1 0 1  1 0 -1  -1 0 -1] \"float uv\" [0 0 1 0 1 1 0 1]\n"
    ))
}

fn world_of(text: &str) -> World {
    World::new(loads(text).0).unwrap()
}

/// The radiance seen at (x, z) on the quad from the light's mirror direction, where the
/// glossy lobe is brightest.
fn seen_at(world: &World, x: f64, z: f64) -> DVec3 {
    let d = DVec3::new(1.0, -1.0, 0.0).normalize();
    radiance_along(&whitted(world, 1), DVec3::new(x, 0.0, z) - 2.0 * d, d)
}

#[test]
fn a_plastic_with_a_checkerboard_ks_shows_each_squares_constant_ks() {
    let textured = world_of(&glossy_quad("\"texture Ks\" \"c\""));
    let bright = world_of(&glossy_quad("\"rgb Ks\" [0.8 0.8 0.8]"));
    let dull = world_of(&glossy_quad("\"rgb Ks\" [0.1 0.1 0.1]"));
    // Square centres: (u, v) at ¼ or ¾; ⌊2u⌋ + ⌊2v⌋ even is tex1 (0.8).
    for (u, v) in [(0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75)] {
        let (x, z) = (2.0 * u - 1.0, 1.0 - 2.0 * v);
        let even = ((2.0 * u) as i32 + (2.0 * v) as i32) % 2 == 0;
        let twin = if even { &bright } else { &dull };
        let (got, want) = (seen_at(&textured, x, z), seen_at(twin, x, z));
        eprintln!("({u}, {v}): textured {got:.5}, twin {want:.5}");
        assert!(
            (got - want).abs().max_element() <= 1e-6 * want.max_element(),
            "({u}, {v})"
        );
    }
    // The squares differ: the texture is what makes them.
    let (b, d) = (seen_at(&bright, 0.0, 0.0), seen_at(&dull, 0.0, 0.0));
    assert!(b.x > 1.2 * d.x, "{b} against {d}");
}

#[test]
fn a_textured_roughness_renders_the_image_of_the_constant_it_evaluates_to() {
    // A checkerboard squeezed to one point of (s, t) reads tex1 everywhere, while its typical
    // value (the untextured material's) is the two squares' mean: only a texture evaluated
    // and remapped at each hit gives the constant's image.
    let scene = |roughness: &str| {
        pbrt_world(&format!(
            "Texture \"r\" \"float\" \"checkerboard\" \"float uscale\" 0 \"float vscale\" 0 \
             \"float tex1\" 0.02 \"float tex2\" 0.6\n\
             Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]\n\
             Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
             \"point3 P\" [-5 0 -5  -5 0 5  5 0 5  5 0 -5]\n\
             Material \"plastic\" \"rgb Kd\" [0.02 0.03 0.05] \"rgb Ks\" [0.9 0.9 0.9] {roughness}\n\
             Shape \"sphere\" \"float radius\" 0.8\n"
        ))
    };
    let dir = tempfile::tempdir().unwrap();
    let textured = render(
        dir.path(),
        "t.pbrt",
        &scene("\"texture roughness\" \"r\""),
        "3",
        &[],
    );
    let constant = scene("\"float roughness\" 0.02");
    let twin = render(dir.path(), "c.pbrt", &constant, "3", &[]);
    let noise = image_relative_mse(&render(dir.path(), "c.pbrt", &constant, "4", &[]), &twin);
    let difference = image_relative_mse(&textured, &twin);
    let typical = render(
        dir.path(),
        "m.pbrt",
        &scene("\"float roughness\" 0.31"),
        "3",
        &[],
    );
    let off = image_relative_mse(&typical, &twin);
    eprintln!(
        "textured against twin {difference:.3e}, seeds apart {noise:.3e}, typical value {off:.3e}"
    );
    assert!(
        difference < 1e-2 * noise,
        "{difference:.3e} against {noise:.3e}"
    );
    // Ignoring the texture would fail the test by far: the same seed's typical-value image
    // lies at least ten times past the tolerance.
    assert!(
        off > 0.1 * noise,
        "the roughness shows: {off:.3e} against {noise:.3e}"
    );
}

#[test]
fn toml_bsdf_colour_fields_take_texture_tables() {
    let text = |ks: &str| {
        format!(
            "[camera]\nposition = [0.0, 3.0, 0.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 0.0, -1.0]\n\
             fov_y = 60.0\nresolution = [8, 8]\n\n\
             [[lights]]\ntype = \"distant\"\ndirection = [-1.0, -1.0, 0.0]\nirradiance = [1.0, 1.0, 1.0]\n\n\
             [materials.shiny]\ntype = \"plastic\"\nkd = [0.3, 0.3, 0.3]\nks = {ks}\nroughness = 0.3\n\n\
             [[objects]]\ntype = \"quad\"\ncorner = [-1.0, 0.0, 1.0]\nedge_u = [2.0, 0.0, 0.0]\n\
             edge_v = [0.0, 0.0, -2.0]\nmaterial = \"shiny\"\n"
        )
    };
    let board =
        text("{ checkerboard = [[0.8, 0.8, 0.8], [0.1, 0.1, 0.1]], uv_scale = [2.0, 2.0] }");
    let scene = support::description(&board);
    let [t] = &scene.textured_materials[..] else {
        panic!("{:?}", scene.textured_materials)
    };
    assert_eq!(t.textures[0].0, model_parameter(P::Specular));
    // The untextured copy holds the squares' mean.
    let Material::Bsdf(Model::Plastic { ks, .. }) = scene.materials[0] else {
        panic!("{:?}", scene.materials[0])
    };
    assert!((ks - Vec3::splat(0.45)).abs().max_element() < 1e-6, "{ks}");
    let textured = World::new(scene).unwrap();
    let bright = support::world(&text("[0.8, 0.8, 0.8]"));
    let got = seen_at(&textured, -0.5, 0.5);
    let want = seen_at(&bright, -0.5, 0.5);
    assert!(
        (got - want).abs().max_element() <= 1e-6 * want.max_element(),
        "{got} against {want}"
    );
    // Every colour field takes one; a bad table names its field.
    for (kind, field) in [
        ("uber", "kr"),
        ("uber", "opacity"),
        ("translucent", "transmit"),
        ("rough_glass", "transmit_tint"),
        ("diffuse_transmission", "transmittance"),
    ] {
        let text = text("[0.5, 0.5, 0.5]").replace(
            "type = \"plastic\"\nkd = [0.3, 0.3, 0.3]\nks = [0.5, 0.5, 0.5]\nroughness = 0.3",
            &format!("type = \"{kind}\"\n{field} = {{ checkerboard = [[1.0, 1.0, 1.0], [0.0, 0.0, 0.0]] }}"),
        );
        let scene = support::description(&text);
        assert_eq!(scene.textured_materials.len(), 1, "{kind}.{field}");
        let bad = text.replace("checkerboard", "chequerboard");
        let e = dpm::scene::parse(&bad, std::path::Path::new("bad.toml")).unwrap_err();
        assert!(
            e.field.contains(field) && e.line.is_some(),
            "{kind}.{field}: {e}"
        );
    }
}
