//! pbrt's materials beyond diffuse, mirror and smooth glass, rendered: a convex object under a
//! constant environment reflects it by its directional albedo (nothing else reaches it), which
//! checks the eye pass's glossy path, its multiple importance sampling and its Lambert lobes'
//! photon estimates against the BSDF's own closed form; and the TOML format reads every model.

mod support;

use dpm::bsdf::{Bsdf, Part};
use dpm::image_metrics::channel_mean;
use dpm::scene::{self, Material};
use glam::Vec3;
use support::pbrt::render;

const SIZE: u32 = 48;
const RADIUS: f32 = 0.8;

/// A sphere of `material` under a white environment, seen by an orthographic camera whose
/// screen window is ±1: every camera ray runs along −z.
fn sphere_under_sky(material: &str) -> String {
    format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\"\n\
         Film \"image\" \"integer xresolution\" {SIZE} \"integer yresolution\" {SIZE}\nWorldBegin\n\
         LightSource \"infinite\" \"rgb L\" [1 1 1]\n{material}\nShape \"sphere\" \"float radius\" {RADIUS}\n"
    )
}

/// The image's mean under a unit environment: each pixel's 8 × 8 sub-samples see the
/// sphere's albedo at their angle of view, or the sky.
fn expected_mean(bsdf: &Bsdf) -> f64 {
    let (mut sum, n) = (0.0, 8);
    for j in 0..SIZE * n {
        for i in 0..SIZE * n {
            let x = -1.0 + (i as f32 + 0.5) * 2.0 / (SIZE * n) as f32;
            let y = -1.0 + (j as f32 + 0.5) * 2.0 / (SIZE * n) as f32;
            let r2 = (x * x + y * y) / (RADIUS * RADIUS);
            sum += if r2 < 1.0 {
                let cos = (1.0 - r2).sqrt();
                let wo = Vec3::new((1.0 - cos * cos).sqrt(), 0.0, cos);
                channel_mean(bsdf.albedo(wo, Part::All)) as f64
            } else {
                1.0
            };
        }
    }
    sum / f64::from(SIZE * SIZE * n * n)
}

fn image_mean(image: &dpm::image_io::Image) -> f64 {
    image.pixels.iter().map(|p| channel_mean(*p)).sum::<f64>() / image.pixels.len() as f64
}

#[test]
fn convex_objects_under_a_constant_sky_reflect_it_by_their_directional_albedo() {
    let dir = tempfile::tempdir().unwrap();
    let cases = [
        "Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\" \
         \"float roughness\" 0.3 \"bool remaproughness\" \"false\"",
        "Material \"conductor\" \"rgb eta\" [0.2 0.9 1.1] \"rgb k\" [3.9 2.4 2.1] \
         \"float uroughness\" 0.05 \"float vroughness\" 0.4 \"bool remaproughness\" \"false\"",
        "Material \"plastic\" \"rgb Kd\" [0.5 0.3 0.2] \"rgb Ks\" [0.4 0.4 0.4] \"float roughness\" 0.2 \
         \"bool remaproughness\" \"false\"",
        "Material \"uber\" \"rgb Kd\" [0.2 0.05 0.6] \"float roughness\" 0.01",
        "Material \"substrate\" \"rgb Kd\" [0.6 0.5 0.4] \"rgb Ks\" [0.05 0.05 0.05] \"float uroughness\" 0.1 \
         \"float vroughness\" 0.1",
        "Material \"coateddiffuse\" \"rgb reflectance\" [0.7 0.2 0.2] \"float roughness\" 0.1",
    ];
    for material in cases {
        let text = sphere_under_sky(material);
        let (desc, _) = support::pbrt::loads(&text);
        let Material::Bsdf(model) = desc.materials[0] else {
            panic!("{material}: {:?}", desc.materials[0]);
        };
        let expected = expected_mean(&Bsdf::new(&model));
        let image = render(dir.path(), "sky.pbrt", &text, "3", &[]);
        let got = image_mean(&image);
        eprintln!("{material}\n  image mean {got:.5}, albedo's {expected:.5}");
        assert!(
            (got / expected - 1.0).abs() < 0.015,
            "{material}: image mean {got:.5}, albedo's {expected:.5}"
        );
    }
}

#[test]
fn the_toml_format_reads_every_bsdf_material_and_refuses_fields_it_does_not_take() {
    let scene = |material: &str| {
        format!(
            "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov_y = 40\nresolution = [8, 8]\n\
             [[lights]]\ntype = \"point\"\nposition = [0, 3, 3]\npower = [10, 10, 10]\n\
             [materials.m]\n{material}\n\
             [[objects]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"m\"\n"
        )
    };
    let kinds = [
        (
            "plastic",
            "kd = [0.5, 0.2, 0.1]\nks = [0.3, 0.3, 0.3]\nroughness = 0.2",
        ),
        (
            "uber",
            "kd = [0.5, 0.2, 0.1]\nkr = [0.1, 0.1, 0.1]\nroughness = [0.1, 0.3]",
        ),
        ("substrate", "kd = [0.5, 0.2, 0.1]"),
        ("translucent", "transmit = [0.3, 0.3, 0.3]"),
        ("conductor", "metal = \"Au\"\nroughness = 0.2"),
        ("rough_glass", "ior = 1.33\nroughness = 0.1"),
        ("thin_glass", "ior = 1.5"),
        (
            "coated_diffuse",
            "reflectance = [0.6, 0.6, 0.6]\nthickness = 0.02",
        ),
        (
            "coated_conductor",
            "metal = \"Cu\"\nconductor_roughness = 0.2",
        ),
        ("diffuse_transmission", "transmittance = [0.4, 0.4, 0.4]"),
    ];
    for (kind, fields) in kinds {
        let text = scene(&format!("type = \"{kind}\"\n{fields}"));
        let desc = support::description(&text);
        assert!(
            matches!(desc.materials[0], Material::Bsdf(_)),
            "{kind}: {:?}",
            desc.materials[0]
        );
    }
    let bad = [
        ("type = \"plastic\"\nior = 1.5", "materials.m.ior"),
        ("type = \"conductor\"\nmetal = \"Zn\"", "materials.m.metal"),
        ("type = \"plastic\"\nkd = [2, 0, 0]", "materials.m.kd"),
    ];
    for (material, names) in bad {
        let e = scene::parse(&scene(material), std::path::Path::new("m.toml")).unwrap_err();
        assert!(
            e.to_string().contains(names) && e.line.is_some(),
            "{material}: {e}"
        );
    }
}

#[test]
fn mtl_highlights_and_the_pbr_extension_become_bsdf_models() {
    use dpm::bsdf::Model;
    let dir = tempfile::tempdir().unwrap();
    support::write_scene(
        dir.path(),
        "m.mtl",
        "newmtl shiny\nKd 0.5 0.1 0.1\nKs 0.3 0.3 0.3\nNs 98\nillum 2\n\
         newmtl gold\nKd 0.9 0.7 0.3\nPm 1\nPr 0.4\n\
         newmtl paint\nKd 0.2 0.4 0.6\nPm 0\nPr 0.2\n",
    );
    support::write_scene(
        dir.path(),
        "mesh.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 0\n\
         usemtl shiny\nf 1 2 3\nusemtl gold\nf 2 4 3\nusemtl paint\nf 2 5 4\n",
    );
    let toml = include_str!("fixtures/one-mesh.toml");
    let (desc, _) =
        scene::load_with_report(&support::write_scene(dir.path(), "s.toml", toml)).unwrap();
    let models: Vec<Model> = (desc.materials.iter())
        .filter_map(|m| match m {
            Material::Bsdf(model) => Some(*model),
            _ => None,
        })
        .collect();
    assert_eq!(models.len(), 3, "{:?}", desc.materials);
    assert!(
        models
            .iter()
            .any(|m| matches!(m, Model::Plastic { ks, alpha, .. }
        if *ks == Vec3::splat(0.3) && (alpha.x - 0.1414).abs() < 1e-3)),
        "{models:?}"
    );
    assert!(
        models
            .iter()
            .any(|m| matches!(m, Model::Conductor { alpha, .. }
        if (alpha.x - 0.16).abs() < 1e-5)),
        "{models:?}"
    );
    assert!(
        models
            .iter()
            .any(|m| matches!(m, Model::Plastic { kd, alpha, .. }
        if *kd == Vec3::new(0.2, 0.4, 0.6) && (alpha.x - 0.04).abs() < 1e-5)),
        "{models:?}"
    );
    // A conductor made from Kd reflects Kd at normal incidence.
    let gold = models
        .iter()
        .find(|m| matches!(m, Model::Conductor { .. }))
        .unwrap();
    let Model::Conductor { eta, k, .. } = gold else {
        unreachable!()
    };
    let f0 = ((*eta - 1.0) * (*eta - 1.0) + *k * *k) / ((*eta + 1.0) * (*eta + 1.0) + *k * *k);
    assert!(
        (f0 - Vec3::new(0.9, 0.7, 0.3)).abs().max_element() < 1e-4,
        "{f0}"
    );
    support::write_scene(
        dir.path(),
        "m.mtl",
        "newmtl shiny\nKd 0.5 0.1 0.1\nPm metal\n",
    );
    let e = scene::load(&support::write_scene(dir.path(), "s.toml", toml)).unwrap_err();
    assert!(e.to_string().contains("Pm"), "{e}");
}

/// A rough conductor floor under a point light and, above the light, a mirror: the mirror's
/// image of the light lights the floor through the caustic map alone (no ray followed from
/// the floor can find a point light), and the floor reflects it by its BSDF for the image's
/// direction. Seen straight down by an orthographic camera, the caustic layer is
/// f(up, towards the image)·I·cos θ/d² at each pixel, and the direct layer the same for the
/// light itself: both against dpm's own BSDF, pixel by pixel over the central disc. No ray
/// is followed from the floor (`--max-depth 0`), so the floor's view of its own reflection in
/// the mirror stays out.
#[test]
fn a_rough_floor_reflects_a_mirrored_point_light_through_its_caustic_photons() {
    let dir = tempfile::tempdir().unwrap();
    let (light_y, mirror_y, size) = (1.0f32, 2.0f32, 32u32);
    let text = format!(
        "LookAt 0 1.5 0  0 0 0  0 0 1\nCamera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\n\
         Film \"image\" \"integer xresolution\" {size} \"integer yresolution\" {size}\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0 {light_y} 0] \"rgb I\" [5 5 5]\n\
         AttributeBegin\nMaterial \"conductor\" \"rgb eta\" [0.2 0.9 1.1] \"rgb k\" [3.9 2.4 2.1] \
         \"float roughness\" 0.3 \"bool remaproughness\" \"false\"\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-4 0 -4  4 0 -4  4 0 4  -4 0 4]\nAttributeEnd\n\
         AttributeBegin\nMaterial \"mirror\" \"rgb Kr\" [1 1 1]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-1.5 {mirror_y} -1.5  1.5 {mirror_y} -1.5  1.5 {mirror_y} 1.5  -1.5 {mirror_y} 1.5]\nAttributeEnd\n"
    );
    let (desc, _) = support::pbrt::loads(&text);
    let Material::Bsdf(model) = desc.materials[0] else {
        panic!("{:?}", desc.materials[0]);
    };
    let bsdf = Bsdf::new(&model);
    assert!(bsdf.has(Part::Estimated) && !bsdf.has(Part::Followed));
    let path = dir.path().join("floor.pbrt");
    std::fs::write(&path, &text).unwrap();
    let out = dir.path().join("floor.exr");
    let args = [
        support::path_str(&path),
        "-o",
        support::path_str(&out),
        "--threads",
        "2",
        "--passes",
        "4",
        "--caustic-photons",
        "200000",
        "--global-photons",
        "0",
        "--max-depth",
        "0",
    ];
    let outcome = dpm::render::pipeline::run(&support::render_args(&args)).unwrap();
    // Radiance from a point source of intensity 5 at `source` towards the camera (up).
    let seen_from = |source: Vec3, x: Vec3| {
        let to = source - x;
        let wi = to.normalize();
        let f = bsdf.f(Vec3::Z, Vec3::new(wi.x, wi.z, wi.y), Part::All);
        channel_mean(f) as f64 * 5.0 * wi.y as f64 / to.length_squared() as f64
    };
    let image = Vec3::new(0.0, 2.0 * mirror_y - light_y, 0.0);
    let light = Vec3::new(0.0, light_y, 0.0);
    for (layer, source) in [("caustic", image), ("direct", light)] {
        let got = outcome.film.layer(layer).unwrap();
        let (mut sum_got, mut sum_want) = (0.0, 0.0);
        for y in 0..size {
            for x in 0..size {
                let u = (x as f32 + 0.5) / size as f32 - 0.5;
                let v = (y as f32 + 0.5) / size as f32 - 0.5;
                if u * u + v * v > 0.16 {
                    continue;
                }
                // Symmetric about the vertical axis: the pixel's orientation does not matter.
                sum_want += seen_from(source, Vec3::new(u, 0.0, v));
                sum_got += channel_mean(got.pixels[(y * size + x) as usize]) as f64;
            }
        }
        eprintln!("{layer}: {sum_got:.4} against {sum_want:.4}");
        assert!(
            (sum_got / sum_want - 1.0).abs() < 0.03,
            "{layer}: {sum_got:.4} against {sum_want:.4}"
        );
    }
}

/// The same rough floor, mirror and now a sphere light: the floor's lobe read from photons
/// (the mirrored light from the caustic map, the rest by sampling the lobe in the mode that
/// leaves the caustic map's paths out) and the floor's lobe followed (everything by sampling
/// it, the mirrored light found through the mirror) are two consistent estimates of one
/// image. They agree in the mean; light counted twice, or lost, between the caustic map and
/// the sampled rays would part them.
#[test]
fn reading_a_rough_lobe_from_photons_or_following_it_renders_the_same_light() {
    let dir = tempfile::tempdir().unwrap();
    let text = "LookAt 0 1.5 0  0 0 0  0 0 1\n\
         Camera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\n\
         Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 24\nWorldBegin\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [8 8 8]\nTranslate 0.3 1 0\n\
         Shape \"sphere\" \"float radius\" 0.1\nAttributeEnd\n\
         AttributeBegin\nMaterial \"conductor\" \"rgb eta\" [0.2 0.9 1.1] \"rgb k\" [3.9 2.4 2.1] \
         \"float roughness\" 0.3 \"bool remaproughness\" \"false\"\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-4 0 -4  4 0 -4  4 0 4  -4 0 4]\nAttributeEnd\n\
         AttributeBegin\nMaterial \"mirror\" \"rgb Kr\" [1 1 1]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-1.5 2 -1.5  1.5 2 -1.5  1.5 2 1.5  -1.5 2 1.5]\nAttributeEnd\n";
    let mean = |split: &str| {
        let image = render(
            dir.path(),
            &format!("split-{split}.pbrt"),
            text,
            "5",
            &[
                "--glossy-min-alpha",
                split,
                "--max-depth",
                "12",
                "--spp",
                "8",
            ],
        );
        image_mean(&image)
    };
    let (read, followed) = (mean("0"), mean("100"));
    eprintln!("read from photons {read:.5}, followed {followed:.5}");
    assert!(
        (read / followed - 1.0).abs() < 0.02,
        "read from photons {read:.5}, followed {followed:.5}"
    );
}

/// A rough glass sphere in front of a large emitter: the light the camera sees through it
/// arrives by transmission, which no shadow ray samples (they look to the side a ray came
/// from), so a BSDF sample that finds the emitter through the glass counts in full. Weighed
/// against shadow rays as a reflection would be, it would change with the shadow-ray count.
#[test]
fn light_through_rough_glass_does_not_depend_on_the_shadow_ray_count() {
    let dir = tempfile::tempdir().unwrap();
    let text = "LookAt 0 0 4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\n\
         Film \"image\" \"integer xresolution\" 24 \"integer yresolution\" 24\nWorldBegin\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3] \
         \"point P\" [-3 -3 -2  3 -3 -2  3 3 -2  -3 3 -2]\nAttributeEnd\n\
         Material \"glass\" \"float index\" 1.5 \"float roughness\" 0.3 \"bool remaproughness\" \"false\"\n\
         Shape \"sphere\" \"float radius\" 0.8\n";
    let mean = |samples: &str| {
        let image = render(
            dir.path(),
            &format!("pane-{samples}.pbrt"),
            text,
            "7",
            &["--light-samples", samples, "--spp", "4"],
        );
        image_mean(&image)
    };
    let (one, sixteen) = (mean("1"), mean("16"));
    eprintln!("through rough glass: 1 shadow ray {one:.5}, 16 shadow rays {sixteen:.5}");
    assert!((one / sixteen - 1.0).abs() < 0.01, "{one} vs {sixteen}");
}
