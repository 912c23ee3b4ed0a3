//! Alpha cut-outs (pbrt's `alpha` and `shadowalpha` on a shape) through Embree's hit filters:
//! a cut mesh renders the image of its twin with the cut parts removed, for photons, eye rays
//! and shadow rays alike; a fractional alpha lets that fraction of light through; a bad mask
//! is refused naming its place.

mod support;

use dpm::image_metrics::{channel_mean, image_relative_mse};
use dpm::scene;
use support::pbrt::render;
use support::write_scene;

const HEAD: &str = "LookAt 0 4 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n\
    Film \"image\" \"integer xresolution\" 64 \"integer yresolution\" 48\nWorldBegin\n\
    LightSource \"point\" \"point from\" [0.3 4 0.2] \"rgb I\" [40 40 40]\n\
    Material \"matte\" \"rgb Kd\" [0.6 0.6 0.6]\n\
    Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \"point3 P\" [-5 0 -5  -5 0 5  5 0 5  5 0 -5]\n\
    Material \"matte\" \"rgb Kd\" [0.8 0.3 0.2]\n";

/// A 2 × 2 square at height 1.5 facing up, with (u, v) running over it; `params` are its alpha.
fn occluder(params: &str) -> String {
    format!(
        "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point3 P\" [-1 1.5 1  1 1.5 1  1 1.5 -1  -1 1.5 -1] \"float uv\" [0 0 1 0 1 1 0 1] {params}\n"
    )
}

/// The occluder's two opaque cells of a 2 × 2 checkerboard, (u, v) in [0, ½]² and [½, 1]².
const TWIN: &str = "Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3  4 5 6 4 6 7] \
    \"point3 P\" [-1 1.5 1  0 1.5 1  0 1.5 0  -1 1.5 0   0 1.5 0  1 1.5 0  1 1.5 -1  0 1.5 -1]\n";

const CHECKER: &str = "Texture \"holes\" \"float\" \"checkerboard\" \"float uscale\" 2 \
    \"float vscale\" 2 \"float tex1\" 1 \"float tex2\" 0\n";

#[test]
fn a_cut_mesh_renders_its_twin_with_the_cut_parts_removed() {
    let dir = tempfile::tempdir().unwrap();
    let cut = format!("{HEAD}{CHECKER}{}", occluder("\"texture alpha\" \"holes\""));
    let twin = format!("{HEAD}{TWIN}");
    let a = render(dir.path(), "cut.pbrt", &cut, "5", &[]);
    let b = render(dir.path(), "twin.pbrt", &twin, "5", &[]);
    let noise = image_relative_mse(&render(dir.path(), "twin.pbrt", &twin, "6", &[]), &b);
    let difference = image_relative_mse(&a, &b);
    eprintln!("cut against twin {difference:.3e}, seeds apart {noise:.3e}");
    assert!(
        difference < 1e-2 * noise,
        "cut against twin {difference:.3e}, seeds apart {noise:.3e}"
    );
    // And the cut-out is not the whole occluder, nor no occluder.
    for other in [format!("{HEAD}{}", occluder("")), HEAD.to_string()] {
        let c = render(dir.path(), "other.pbrt", &other, "5", &[]);
        assert!(image_relative_mse(&c, &b) > 10.0 * noise);
    }
}

#[test]
fn a_fractional_alpha_lets_that_fraction_through_and_shadowalpha_acts_on_shadow_rays_only() {
    let dir = tempfile::tempdir().unwrap();
    let mean = |text: String, name: &str| {
        let image = render(dir.path(), name, &text, "7", &[]);
        image.pixels.iter().map(|p| channel_mean(*p)).sum::<f64>() / image.pixels.len() as f64
    };
    let opaque = mean(format!("{HEAD}{}", occluder("")), "opaque.pbrt");
    let none = mean(HEAD.to_string(), "none.pbrt");
    let half = mean(
        format!("{HEAD}{}", occluder("\"float alpha\" 0.5")),
        "half.pbrt",
    );
    let expected = 0.5 * (opaque + none);
    eprintln!("opaque {opaque:.5}, none {none:.5}, half {half:.5}, halfway {expected:.5}");
    assert!(
        (half / expected - 1.0).abs() < 0.02,
        "{half} against {expected}"
    );
    // Alpha 0 everywhere: the occluder is not there at all.
    let gone = mean(
        format!("{HEAD}{}", occluder("\"float alpha\" 0")),
        "gone.pbrt",
    );
    assert!((gone / none - 1.0).abs() < 0.01, "{gone} against {none}");
    // A shadow mask of 0: the occluder is seen as before but casts no direct shadow, so the
    // floor under it is lit and the image brighter than the opaque one.
    let shadowless = mean(
        format!("{HEAD}{}", occluder("\"float shadowalpha\" 0")),
        "s.pbrt",
    );
    eprintln!("shadowless {shadowless:.5}");
    assert!(shadowless > opaque * 1.02, "{shadowless} against {opaque}");
}

#[test]
fn bad_cutouts_are_refused_naming_their_place() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        (
            occluder("\"texture alpha\" \"nowhere\""),
            "no texture is named \"nowhere\"",
        ),
        (
            format!(
                "Texture \"c\" \"color\" \"constant\" \"rgb value\" [1 0 1]\n{}",
                occluder("\"texture alpha\" \"c\"")
            ),
            "needs a float texture",
        ),
        (
            format!(
                "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n{}AttributeEnd\n",
                occluder("\"float alpha\" 0.5")
            ),
            "area light",
        ),
    ];
    for (body, says) in cases {
        let text = format!("{HEAD}{body}");
        let path = write_scene(dir.path(), "bad.pbrt", &text);
        let e = scene::load(&path).unwrap_err();
        assert!(
            e.line.is_some() && e.to_string().contains(says),
            "{body}: {e}"
        );
    }
}

#[test]
fn a_cut_sphere_is_tessellated_and_keeps_pbrts_texture_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let (desc, _) = support::pbrt::load_text(
        dir.path(),
        &format!(
            "{HEAD}{CHECKER}Shape \"sphere\" \"float radius\" 0.5 \"texture alpha\" \"holes\"\n"
        ),
    )
    .unwrap();
    let scene::Shape::Triangles(mesh) = &desc.shapes[1] else {
        panic!("a cut sphere is a mesh: {:?}", desc.shapes[1]);
    };
    assert!(mesh.cutout.is_some() && mesh.uvs.is_some());
    // Its texture coordinates cover [0, 1]², with v = 1 at the +z pole as pbrt's.
    let uvs = mesh.uvs.as_ref().unwrap();
    let top = (mesh.positions.iter().zip(uvs))
        .max_by(|a, b| a.0.z.total_cmp(&b.0.z))
        .unwrap();
    assert!((top.1.y - 1.0).abs() < 1e-3, "{top:?}");
}
