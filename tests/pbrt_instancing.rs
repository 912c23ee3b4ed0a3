//! pbrt's object instancing on Embree's instances: an instanced scene renders the image of its
//! flattened twin (the same shapes written out at each placement), photons and eye rays alike
//! resolve hits through an instance to the prototype's material and to world-space normals,
//! and malformed instancing is refused naming its file, line and column.

mod support;

use dpm::image_metrics::image_relative_mse;
use dpm::scene;
use std::path::Path;
use support::write_scene;

const HEAD: &str = "LookAt 0 3 7  0 0.5 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n\
    Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 48\nWorldBegin\n\
    LightSource \"point\" \"point from\" [1 5 2] \"rgb I\" [30 30 30]\n\
    LightSource \"infinite\" \"rgb L\" [0.2 0.2 0.25]\n\
    Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]\n\
    Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-5 0 -5  -5 0 5  5 0 5  5 0 -5]\n";

/// What the prototype holds: a red box-ish wedge and a ball of `ball` material, each with a
/// transform of its own inside the definition.
fn prototype_body(ball: &str) -> String {
    format!(
        "AttributeBegin\nMaterial \"matte\" \"rgb Kd\" [0.8 0.2 0.1]\nTranslate 0 0.01 0\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3 0 3 4 0 4 1] \
         \"point3 P\" [0 0.8 0  -0.4 0 -0.4  0.4 0 -0.4  0.4 0 0.4  -0.4 0 0.4]\nAttributeEnd\n\
         AttributeBegin\n{ball}\nTranslate 0.6 0.3 0\nShape \"sphere\" \"float radius\" 0.3\nAttributeEnd\n"
    )
}

/// Where the instances go.
const PLACEMENTS: [&str; 3] = [
    "Translate -1.5 0 0",
    "Translate 1.2 0 0.5\nRotate 40 0 1 0",
    "Translate 0 0 -1.5\nScale 1.5 1.5 1.5\nRotate -70 0 1 0",
];

fn instanced(ball: &str) -> String {
    let mut text = format!(
        "{HEAD}ObjectBegin \"thing\"\n{}ObjectEnd\n",
        prototype_body(ball)
    );
    for place in PLACEMENTS {
        text += &format!("AttributeBegin\n{place}\nObjectInstance \"thing\"\nAttributeEnd\n");
    }
    text
}

fn flattened(ball: &str) -> String {
    let mut text = HEAD.to_string();
    for place in PLACEMENTS {
        text += &format!(
            "AttributeBegin\n{place}\n{}AttributeEnd\n",
            prototype_body(ball)
        );
    }
    text
}

/// Without the open-scene probe: the flattened twin's objects could be aimed at, the
/// instances' not.
fn render(dir: &Path, name: &str, text: &str, seed: &str) -> dpm::image_io::Image {
    support::pbrt::render(dir, name, text, seed, &["--no-open-scene"])
}

#[test]
fn an_instanced_scene_renders_its_flattened_twin() {
    let dir = tempfile::tempdir().unwrap();
    // Diffuse prototypes: the same photons and eye paths, up to the last bits of the hits.
    let ball = "Material \"matte\" \"rgb Kd\" [0.2 0.3 0.9]";
    let a = render(dir.path(), "instanced.pbrt", &instanced(ball), "3");
    let b = render(dir.path(), "flat.pbrt", &flattened(ball), "3");
    let noise = image_relative_mse(&render(dir.path(), "flat.pbrt", &flattened(ball), "4"), &b);
    let twin = image_relative_mse(&a, &b);
    eprintln!("diffuse: instanced against flattened {twin:.3e}, seeds apart {noise:.3e}");
    assert!(
        twin < 1e-3 * noise,
        "instanced against flattened {twin:.3e}, seeds apart {noise:.3e}"
    );
    // Glass balls: caustics through instances, aimed at the prototype's own targets placed.
    let ball = "Material \"glass\"";
    let a = render(dir.path(), "instanced.pbrt", &instanced(ball), "3");
    let b = render(dir.path(), "flat.pbrt", &flattened(ball), "3");
    let noise = image_relative_mse(&render(dir.path(), "flat.pbrt", &flattened(ball), "4"), &b);
    let twin = image_relative_mse(&a, &b);
    eprintln!("glass: instanced against flattened {twin:.3e}, seeds apart {noise:.3e}");
    assert!(
        twin < 1e-2 * noise,
        "instanced against flattened {twin:.3e}, seeds apart {noise:.3e}"
    );
}

#[test]
fn textures_and_cutouts_inside_an_object_render_as_in_its_flattened_twin() {
    let dir = tempfile::tempdir().unwrap();
    // The wedge textured by a checkerboard over its corners' (u, v), and a cut-out square.
    let textured = "Texture \"check\" \"color\" \"checkerboard\" \"float uscale\" 4 \"float vscale\" 4 \
        \"rgb tex1\" [0.9 0.9 0.1] \"rgb tex2\" [0.1 0.2 0.8]\n\
        Texture \"holes\" \"float\" \"checkerboard\" \"float uscale\" 3 \"float vscale\" 3\n\
        Material \"matte\" \"texture Kd\" \"check\"\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3 0 3 4 0 4 1] \
        \"point3 P\" [0 0.8 0  -0.4 0 -0.4  0.4 0 -0.4  0.4 0 0.4  -0.4 0 0.4] \
        \"float uv\" [0.5 0.5  0 0  1 0  1 1  0 1]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"texture alpha\" \"holes\" \
        \"point3 P\" [-0.5 1.2 -0.5  0.5 1.2 -0.5  0.5 1.2 0.5  -0.5 1.2 0.5] \"float uv\" [0 0 1 0 1 1 0 1]\n";
    let mut instanced = format!("{HEAD}ObjectBegin \"thing\"\n{textured}ObjectEnd\n");
    let mut flat = HEAD.to_string();
    for place in PLACEMENTS {
        instanced += &format!("AttributeBegin\n{place}\nObjectInstance \"thing\"\nAttributeEnd\n");
        flat += &format!("AttributeBegin\n{place}\n{textured}AttributeEnd\n");
    }
    let a = render(dir.path(), "instanced.pbrt", &instanced, "3");
    let b = render(dir.path(), "flat.pbrt", &flat, "3");
    let noise = image_relative_mse(&render(dir.path(), "flat.pbrt", &flat, "4"), &b);
    let twin = image_relative_mse(&a, &b);
    eprintln!("textured: instanced against flattened {twin:.3e}, seeds apart {noise:.3e}");
    assert!(
        twin < 1e-2 * noise,
        "instanced against flattened {twin:.3e}, seeds apart {noise:.3e}"
    );
}

#[test]
fn instancing_loads_as_pbrt_defines_it() {
    let dir = tempfile::tempdir().unwrap();
    let path = write_scene(dir.path(), "i.pbrt", &instanced("Material \"glass\""));
    let (desc, _) = scene::load_with_report(&path).unwrap();
    assert_eq!((desc.prototypes.len(), desc.instances.len()), (1, 3));
    assert_eq!(desc.prototypes[0].shapes.len(), 2);
    assert_eq!(
        desc.shapes.len(),
        1,
        "only the floor stands outside the object"
    );
    // The second placement's transform: translate, then rotate 40° about y.
    let m = desc.instances[1].object_to_world;
    let p = m.transform_point3(glam::Vec3::X);
    let (s, c) = 40f32.to_radians().sin_cos();
    assert!(
        (p - glam::Vec3::new(1.2 + c, 0.0, 0.5 - s)).length() < 1e-5,
        "{p}"
    );
}

#[test]
fn malformed_instancing_is_refused_naming_its_place() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            "ObjectInstance \"nothing\"\n",
            9,
            "no object is named \"nothing\"",
        ),
        (
            "ObjectBegin \"a\"\nObjectBegin \"b\"\n",
            10,
            "objects do not nest",
        ),
        ("ObjectEnd\n", 9, "no ObjectBegin"),
        (
            "ObjectBegin \"a\"\nShape \"sphere\"\nObjectInstance \"a\"\n",
            11,
            "instances do not nest",
        ),
        (
            "ObjectBegin \"a\"\nShape \"sphere\"\nObjectEnd\nScale 0 1 1\nObjectInstance \"a\"\n",
            13,
            "invertible",
        ),
    ];
    for (body, line, says) in cases {
        let text = format!("{HEAD}{body}");
        let path = write_scene(dir.path(), "bad.pbrt", &text);
        let e = scene::load(&path).unwrap_err();
        assert_eq!(e.line, Some(line), "{body}: {e}");
        assert!(
            e.column.is_some() && e.to_string().contains(says),
            "{body}: {e}"
        );
    }
}

#[test]
fn many_placed_glass_meshes_aim_within_the_targets_photons_can_take() {
    // A glass wedge placed twelve times: more specular shapes than caustic targets, so the
    // photons aim at one sphere round them all, and the render runs.
    let dir = tempfile::tempdir().unwrap();
    let mut text = format!(
        "{HEAD}ObjectBegin \"wedge\"\nMaterial \"glass\"\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3 0 3 4 0 4 1] \
         \"point3 P\" [0 0.8 0  -0.4 0 -0.4  0.4 0 -0.4  0.4 0 0.4  -0.4 0 0.4]\nObjectEnd\n"
    );
    for i in 0..12 {
        text += &format!(
            "AttributeBegin\nTranslate {} 0 {}\nObjectInstance \"wedge\"\nAttributeEnd\n",
            (i % 4) as f32 - 1.5,
            (i / 4) as f32 - 1.0
        );
    }
    let image = render(dir.path(), "wedges.pbrt", &text, "1");
    assert!(image.pixels.iter().all(|p| p.is_finite()));
    let bright = image
        .pixels
        .iter()
        .filter(|p| p.max_element() > 0.0)
        .count();
    assert!(bright > image.pixels.len() / 2, "{bright} lit pixels");
}
