//! Media (issue 48's first stage): pbrt's `MakeNamedMedium` read as each version defines it
//! (and refused, naming the place, where its values are bad), pbrt-v3's density grid against
//! its definition, the majorant grid as a bound and its DDA as a partition of the ray, and
//! delta and ratio tracking against the closed form on a constant grid and against
//! brute-force quadrature of exp(−∫σt) on a random one. The phase function and the
//! homogeneous medium are tested beside their code.

mod support;

use dpm::media::tracking::GridMedium;
use dpm::media::{DensityGrid, MajorantGrid, MajorantSegment};
use dpm::sampling::{Rng, Stream};
use dpm::scene::{Medium, MediumKind};
use glam::{Mat4, UVec3, Vec3};
use support::pbrt::{load_text, world};

fn random_grid(rng: &mut Rng, size: UVec3) -> DensityGrid {
    let n = (size.x * size.y * size.z) as usize;
    // Mostly empty, a few dense voxels: the wisps the majorant grid is for.
    let values = (0..n)
        .map(|_| {
            let u = rng.next_f32();
            if u < 0.7 { 0.0 } else { 4.0 * u * u }
        })
        .collect();
    DensityGrid::new(size, values).unwrap()
}

#[test]
fn the_density_is_trilinear_between_voxel_centres_and_fades_to_zero_outside() {
    let grid = DensityGrid::new(UVec3::new(2, 1, 1), vec![1.0, 3.0]).unwrap();
    let at = |x: f32, y: f32| grid.density(Vec3::new(x, y, 0.5));
    for (x, want) in [
        (0.25, 1.0),
        (0.75, 3.0),
        (0.5, 2.0),
        (0.0, 0.5),
        (1.0, 1.5),
        (-0.01, 0.0),
        (-0.3, 0.0),
    ] {
        assert!((at(x, 0.5) - want).abs() < 1e-6, "x = {x}: {}", at(x, 0.5));
    }
    // Half a voxel from the y border: three quarters of the way from outside's 0.
    assert!((at(0.25, 0.25) - 0.75).abs() < 1e-6);
    assert!(DensityGrid::new(UVec3::new(2, 2, 1), vec![1.0; 3]).is_none());
    assert!(DensityGrid::new(UVec3::new(1, 1, 1), vec![-1.0]).is_none());
    assert!(DensityGrid::new(UVec3::new(1, 1, 1), vec![f32::NAN]).is_none());
}

#[test]
fn no_point_of_a_cell_reads_more_than_its_majorant() {
    let mut rng = Rng::for_index(1, Stream::Pixels, 0);
    let grid = random_grid(&mut rng, UVec3::new(7, 5, 3));
    let majorants = MajorantGrid::new(&grid, 4);
    for _ in 0..200_000 {
        let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
        assert!(grid.density(p) <= majorants.at(p) + 1e-5, "{p}");
    }
}

#[test]
fn the_dda_cuts_a_ray_into_consecutive_cells_each_with_its_own_bound() {
    let mut rng = Rng::for_index(2, Stream::Pixels, 0);
    let grid = random_grid(&mut rng, UVec3::new(9, 9, 9));
    let majorants = MajorantGrid::new(&grid, 5);
    for i in 0..2_000 {
        let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 3.0 - 1.0;
        let mut d = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
        if i % 10 == 0 {
            d.y = if i % 20 == 0 { 0.0 } else { -0.0 }; // rays in a cell wall's plane
        }
        let mut segments: Vec<MajorantSegment> = Vec::new();
        majorants.segments(o, d, 0.0, 10.0, |s| {
            segments.push(s);
            true
        });
        // Brute force: where along the ray the point is in the cube.
        let inside = |t: f32| {
            let p = o + d * t;
            p.cmpge(Vec3::ZERO).all() && p.cmple(Vec3::ONE).all()
        };
        let steps = 4_000;
        let covered = (0..steps)
            .map(|k| 10.0 * (k as f32 + 0.5) / steps as f32)
            .filter(|&t| inside(t))
            .count();
        let length: f32 = segments.iter().map(|s| s.t1 - s.t0).sum();
        assert!(
            (length - 10.0 * covered as f32 / steps as f32).abs() < 0.02,
            "ray {i}: {length} against {covered} of {steps}"
        );
        for pair in segments.windows(2) {
            assert!((pair[0].t1 - pair[1].t0).abs() < 1e-5, "ray {i}: {pair:?}");
        }
        for s in &segments {
            for k in 0..8 {
                let t = s.t0 + (s.t1 - s.t0) * (k as f32 + 0.5) / 8.0;
                assert!(
                    grid.density(o + d * t) <= s.majorant + 1e-5,
                    "ray {i}: {s:?} at {t}"
                );
            }
        }
    }
}

/// exp(−∫σt) along the ray by the midpoint rule (σt per world length, `d` not unit).
fn quadrature(medium: &GridMedium, o: Vec3, d: Vec3, t_max: f32) -> f64 {
    let steps = 20_000;
    let h = t_max as f64 / steps as f64 * d.length() as f64;
    let optical: f64 = (0..steps)
        .map(|k| {
            let t = (k as f64 + 0.5) * t_max as f64 / steps as f64;
            medium.sigma_t_at(o + d * t as f32) as f64 * h
        })
        .sum();
    (-optical).exp()
}

#[test]
fn ratio_and_delta_tracking_agree_with_the_closed_form_and_with_quadrature() {
    let mut rng = Rng::for_index(3, Stream::Pixels, 0);
    let place = Mat4::from_translation(Vec3::new(-1.0, 2.0, 0.5))
        * Mat4::from_scale(Vec3::new(2.0, 1.0, 3.0));
    let (sigma_a, sigma_s) = (Vec3::splat(0.3), Vec3::splat(0.9));
    let constant = GridMedium::new(
        DensityGrid::new(UVec3::splat(8), vec![1.0; 512]).unwrap(),
        place,
        sigma_a,
        sigma_s,
    )
    .unwrap();
    let random = GridMedium::new(
        random_grid(&mut rng, UVec3::new(6, 7, 5)),
        place,
        sigma_a,
        sigma_s,
    )
    .unwrap();
    // Through the interior (more than half a voxel from the border), and across the whole box.
    let rays = [
        (
            constant,
            Vec3::new(-0.8, 2.2, 0.8),
            Vec3::new(1.0, 0.3, 1.0),
            1.2,
            true,
        ),
        (
            random.clone(),
            Vec3::new(-1.5, 2.5, 0.0),
            Vec3::new(1.2, 0.1, 1.0),
            3.5,
            false,
        ),
        (
            random,
            Vec3::new(1.2, 3.2, 3.8),
            Vec3::new(-0.5, -0.3, -0.9),
            4.0,
            false,
        ),
    ];
    for (i, (medium, o, d, t_max, closed)) in rays.into_iter().enumerate() {
        let want = if closed {
            (-1.2f64 * (d.length() * t_max) as f64).exp()
        } else {
            quadrature(&medium, o, d, t_max)
        };
        let n = 100_000;
        let ratio: f64 = (0..n)
            .map(|_| medium.transmittance(o, d, t_max, &mut rng) as f64)
            .sum::<f64>()
            / n as f64;
        let passed = (0..n)
            .filter(|_| medium.free_flight(o, d, t_max, &mut rng).is_none())
            .count() as f64
            / n as f64;
        assert!(
            (ratio / want - 1.0).abs() < 0.01,
            "ray {i}: ratio tracking {ratio} against {want}"
        );
        assert!(
            (passed - want).abs() < 4.0 * (want * (1.0 - want) / n as f64).sqrt() + 1e-3,
            "ray {i}: delta tracking {passed} against {want}"
        );
    }
}

fn media_of(text: &str) -> Vec<Medium> {
    let dir = tempfile::tempdir().unwrap();
    load_text(dir.path(), text)
        .unwrap_or_else(|e| panic!("{e}"))
        .0
        .media
        .media
}

#[test]
fn media_read_as_each_pbrt_defines_them() {
    // pbrt-v3: whole milk unless told, `scale` on both; a grid placed by the transform in
    // force times Translate(p0) · Scale(p1 − p0).
    let media = media_of(&world(
        "MakeNamedMedium \"milk\" \"string type\" \"homogeneous\" \"float scale\" 2\n\
         Translate 1 2 3\n\
         MakeNamedMedium \"smoke\" \"string type\" \"heterogeneous\" \"integer nx\" 2\n\
         \"point p0\" [0 0 0.5] \"point p1\" [2 1 1.5] \"float density\" [0.5 1]\n\
         \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [3 3 3] \"float g\" -0.3\nShape \"sphere\"\n\
         AttributeBegin\nMaterial \"\"\nMediumInterface \"smoke\" \"\"\nShape \"sphere\"\n\
         Shape \"sphere\" \"float radius\" 2\nAttributeEnd\nShape \"sphere\" \"float radius\" 3\n",
    ));
    assert_eq!(media.len(), 2);
    assert_eq!(
        media[0].kind,
        MediumKind::Homogeneous {
            sigma_a: Vec3::new(0.0022, 0.0048, 0.028),
            sigma_s: Vec3::new(5.1, 6.42, 7.54),
        }
    );
    let MediumKind::Grid {
        sigma_a,
        sigma_s,
        size,
        density,
        grid_to_world,
    } = &media[1].kind
    else {
        panic!("{:?}", media[1]);
    };
    assert_eq!(
        (*sigma_a, *sigma_s, *size),
        (Vec3::ONE, Vec3::splat(3.0), [2, 1, 1])
    );
    assert_eq!(density, &vec![0.5, 1.0]);
    assert_eq!(media[1].g, -0.3);
    // Two shapes name the smoke in their MediumInterface; the scope ends with the attributes.
    assert_eq!((media[0].bounded_by, media[1].bounded_by), (0, 2));
    assert!(
        media[1].describe().contains("bounded by 2 shapes"),
        "{}",
        media[1].describe()
    );
    let corner = grid_to_world.transform_point3(Vec3::ONE);
    assert!(
        (corner - Vec3::new(3.0, 3.0, 4.5)).length() < 1e-5,
        "{corner}"
    );
    // pbrt-v4: σa = σs = 1 unless told.
    let v4 = media_of(&format!(
        "ColorSpace \"srgb\"\n{}",
        world("MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\nShape \"sphere\"\n")
    ));
    assert_eq!(
        v4[0].kind,
        MediumKind::Homogeneous {
            sigma_a: Vec3::ONE,
            sigma_s: Vec3::ONE
        }
    );
}

#[test]
fn a_preset_gives_its_measured_coefficients_as_each_pbrt_lets_them_be_overridden() {
    // Jensen et al. 2001's apple: σ′s (2.29 2.39 1.97), σa (.0030 .0034 .046) per mm.
    let apple = |version: &str| {
        media_of(&format!(
            "{version}{}",
            world(
                "MakeNamedMedium \"a\" \"string type\" \"homogeneous\" \"string preset\" \"Apple\"\n\
                 \"rgb sigma_a\" [1 1 1]\nShape \"sphere\"\n"
            )
        ))[0]
            .kind
            .clone()
    };
    let s = Vec3::new(2.29, 2.39, 1.97);
    // pbrt-v3: sigma_a overrides the preset's; pbrt-v4: the preset wins.
    assert_eq!(
        apple(""),
        MediumKind::Homogeneous {
            sigma_a: Vec3::ONE,
            sigma_s: s
        }
    );
    assert_eq!(
        apple("ColorSpace \"srgb\"\n"),
        MediumKind::Homogeneous {
            sigma_a: Vec3::new(0.003, 0.0034, 0.046),
            sigma_s: s
        }
    );
    // pbrt-v4's `Attribute "medium"` gives the media defined after it their defaults.
    let v4 = media_of(&format!(
        "ColorSpace \"srgb\"\n{}",
        world(
            "AttributeBegin\nAttribute \"medium\" \"float g\" 0.5 \"rgb sigma_s\" [2 2 2]\n\
             MakeNamedMedium \"c\" \"string type\" \"homogeneous\" \"rgb sigma_s\" [3 3 3]\nAttributeEnd\n\
             MakeNamedMedium \"d\" \"string type\" \"homogeneous\"\nShape \"sphere\"\n"
        )
    ));
    assert_eq!((v4[0].g, v4[1].g), (0.5, 0.0));
    assert!(
        matches!(v4[0].kind, MediumKind::Homogeneous { sigma_s, .. } if sigma_s == Vec3::splat(3.0))
    );
    // An unknown name: whole milk, with a warning naming it.
    let dir = tempfile::tempdir().unwrap();
    let text = world(
        "MakeNamedMedium \"b\" \"string type\" \"homogeneous\" \"string preset\" \"Pudding\"\nShape \"sphere\"\n",
    );
    let (scene, report) = load_text(dir.path(), &text).unwrap();
    assert!(
        matches!(scene.media.media[0].kind, MediumKind::Homogeneous { sigma_s, .. } if sigma_s == Vec3::new(2.55, 3.21, 3.77))
    );
    assert!(
        report.warnings.iter().any(|w| w.contains("\"Pudding\"")),
        "{:?}",
        report.warnings
    );
}

#[test]
fn bad_media_are_refused_naming_their_place_and_field() {
    let dir = tempfile::tempdir().unwrap();
    for (body, field) in [
        (
            "\"string type\" \"homogeneous\" \"rgb sigma_a\" [1 -1 1]",
            "sigma_a",
        ),
        ("\"string type\" \"homogeneous\" \"float g\" 1", "g"),
        (
            "\"string type\" \"heterogeneous\" \"integer nx\" 2 \"float density\" [1 2 3]",
            "density",
        ),
        (
            "\"string type\" \"heterogeneous\" \"float density\" [1] \"rgb sigma_s\" [1 2 3]",
            "sigma_s",
        ),
        (
            "\"string type\" \"heterogeneous\" \"float density\" [1] \"point p1\" [1 0 1]",
            "p1",
        ),
        ("\"string type\" \"nanovdb\"", "MakeNamedMedium"),
        (
            "\"string type\" \"homogeneous\"\nMediumInterface \"m\" \"fig\"",
            "MediumInterface",
        ),
    ] {
        let text = world(&format!("MakeNamedMedium \"m\" {body}\nShape \"sphere\"\n"));
        let e = load_text(dir.path(), &text).unwrap_err();
        // The medium's own line, or, for a name no medium has, the shape's that uses it.
        let line = if field == "MediumInterface" { 8 } else { 6 };
        assert_eq!((e.line, e.column.is_some()), (Some(line), true), "{e}");
        assert!(e.field.contains(field), "{body}: {e}");
    }
}

/// A TOML scene: a camera, a point light in `light_medium`, media `media` and a sphere
/// whose material and sides `object` gives.
fn toml_scene(media: &str, light_medium: &str, object: &str) -> String {
    format!(
        "[camera]\nposition = [0, 0, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov_y = 30\nresolution = [32, 32]\n\
         medium = \"fog\"\n\n[[lights]]\ntype = \"point\"\nposition = [0, 2, 0]\n\
         power = [1, 1, 1]\n{light_medium}\n\n[materials.white]\ntype = \"diffuse\"\n\
         albedo = [0.5, 0.5, 0.5]\n\n{media}\n\n[[objects]]\ntype = \"sphere\"\n\
         center = [0, 0, 0]\nradius = 1\n{object}\n"
    )
}

const FOG: &str = "[media.fog]\ntype = \"homogeneous\"\nsigma_a = [0.1, 0.1, 0.1]\n\
                   sigma_s = [0.5, 0.5, 0.5]\ng = 0.3";

#[test]
fn the_toml_format_places_media_as_the_pbrt_readers_do() {
    let grid = "[media.smoke]\ntype = \"grid\"\nsigma_a = [1, 1, 1]\nsigma_s = [2, 2, 2]\n\
                size = [2, 1, 1]\ndensity = [0.5, 1]\np0 = [-1, -1, -1]\np1 = [1, 1, 1]";
    let text = toml_scene(
        &format!("{FOG}\n\n{grid}"),
        "medium = \"fog\"",
        "material = \"\"\ninside = \"smoke\"\noutside = \"fog\"",
    );
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    let (scene, _) = dpm::scene::parse(&text, &path).unwrap_or_else(|e| panic!("{e}"));
    let media = &scene.media;
    // In name order: fog, smoke.
    assert_eq!(media.media.len(), 2);
    assert_eq!(
        (media.media[0].name.as_str(), media.media[0].g),
        ("fog", 0.3)
    );
    assert!(matches!(
        media.media[1].kind,
        MediumKind::Grid {
            size: [2, 1, 1],
            ..
        }
    ));
    assert_eq!(media.camera, Some(0));
    assert_eq!(media.light_media, vec![(0, 0)]);
    assert!(scene.shapes.is_empty(), "a boundary is not a surface");
    let sides = dpm::scene::MediumInterface {
        inside: Some(1),
        outside: Some(0),
    };
    assert_eq!(media.boundaries.len(), 1);
    assert_eq!(media.boundaries[0].interface, sides);
    assert_eq!(media.media[1].bounded_by, 1);
    // A glass sphere of smoke in fog is a surface with an interface.
    let glass = toml_scene(
        &format!("{FOG}\n\n{grid}"),
        "",
        "material = \"white\"\ninside = \"smoke\"\noutside = \"fog\"",
    );
    let (scene, _) = dpm::scene::parse(&glass, &path).unwrap();
    assert_eq!(scene.media.shape_interfaces, vec![(0, sides)]);
    assert!(scene.media.light_media.is_empty());
}

#[test]
fn bad_toml_media_are_refused_naming_their_line_and_field() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.toml");
    let homogeneous = |fields: &str| format!("[media.fog]\ntype = \"homogeneous\"\n{fields}");
    let grid = |fields: &str| {
        format!("[media.fog]\ntype = \"grid\"\nsigma_a = [1, 1, 1]\nsigma_s = [1, 1, 1]\n{fields}")
    };
    for (media, object, field) in [
        (
            homogeneous("sigma_a = [1, -1, 1]\nsigma_s = [1, 1, 1]"),
            "material = \"white\"",
            "media.fog.sigma_a",
        ),
        (
            homogeneous("sigma_a = [1, 1, 1]\nsigma_s = [1, 1, 1]\ng = 1.0"),
            "material = \"white\"",
            "media.fog.g",
        ),
        (
            grid("size = [2, 2, 1]\ndensity = [1, 2, 3]"),
            "material = \"white\"",
            "media.fog.density",
        ),
        (
            grid("size = [1, 1, 1]\ndensity = [1]\np1 = [1, 0, 1]"),
            "material = \"white\"",
            "media.fog.p1",
        ),
        (
            FOG.to_string(),
            "material = \"white\"\ninside = \"fig\"",
            "objects[0].inside",
        ),
        (FOG.to_string(), "material = \"\"", "objects[0].material"),
    ] {
        let text = toml_scene(&media, "", object);
        let e = dpm::scene::parse(&text, &path).unwrap_err();
        assert_eq!(e.field, field, "{e}");
        assert!(e.line.is_some(), "{e}");
        let line = text.lines().position(|l| {
            let key = field.rsplit('.').next().unwrap();
            let key = key.split('[').next().unwrap();
            l.starts_with(&format!("{key} ")) || (key == "fog" && l.starts_with("[media"))
        });
        assert_eq!(e.line, line.map(|l| l + 1), "{field}: {e}");
    }
    // The camera's medium must exist.
    let text = toml_scene("", "", "material = \"white\"");
    let e = dpm::scene::parse(&text, &path).unwrap_err();
    assert_eq!(e.field, "camera.medium", "{e}");
}
