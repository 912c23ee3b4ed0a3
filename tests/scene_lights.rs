//! The scene file's spot, distant, environment and mesh lights and its mirror and glass tints
//! come out as docs/scene-format.md says: defaults filled in (pbrt's cone of 30° with a 5°
//! falloff, smoothstep, untinted), directions made unit, a mesh light's OBJ placed like a mesh
//! object's (one flat mesh, material 0), MTL `Ks` tinting mirrors; and what loads passes
//! `check_light` and `check_material`, which refuse what the file would; and the photon-map
//! fingerprint sees every new field.

use dpm::scene::{
    self, Light, Material, SceneDescription, SpotFalloff, check_light, check_material,
};
use glam::Vec3;
use std::path::{Path, PathBuf};

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

/// A scene with these `[[lights]]` and `[materials.*]` (TOML), a white sphere, and whatever
/// `objects` adds, read as if it lived in tests/fixtures/ (so `meshes/...` names its meshes).
fn scene_with(
    lights: &str,
    materials: &str,
    objects: &str,
) -> (SceneDescription, scene::LoadReport) {
    let text = format!(
        "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nfov_y = 40\n\
         resolution = [64, 48]\n\n{lights}\n\n[materials.white]\ntype = \"diffuse\"\n\
         albedo = [0.5, 0.5, 0.5]\n\n{materials}\n\n[[objects]]\ntype = \"sphere\"\n\
         center = [0, 0, 0]\nradius = 1\nmaterial = \"white\"\n\n{objects}"
    );
    scene::parse(&text, &repo("tests/fixtures/inline.toml"))
        .unwrap_or_else(|e| panic!("{e}\n{text}"))
}

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-6
}

#[test]
fn spot_lights_take_pbrts_defaults_and_unit_directions() {
    let (scene, _) = scene_with(
        "[[lights]]\ntype = \"spot\"\nposition = [0, 3, 0]\ndirection = [0, -2, 0]\npower = [1, 2, 3]\n\n\
         [[lights]]\ntype = \"spot\"\nposition = [1, 3, 0]\ndirection = [3, 0, 4]\ncone_angle = 60\n\
         falloff_start = 12.5\nfalloff = \"quartic\"\npower = [1, 1, 1]\n\n\
         [[lights]]\ntype = \"spot\"\nposition = [0, 3, 0]\ndirection = [0, -1, 0]\ncone_angle = 3\n\
         power = [1, 1, 1]",
        "",
        "",
    );
    let spots: Vec<_> = (scene.lights.iter())
        .map(|l| match l {
            Light::Spot {
                direction,
                cone_angle_degrees,
                falloff_start_degrees,
                falloff,
                ..
            } => (
                *direction,
                *cone_angle_degrees,
                *falloff_start_degrees,
                *falloff,
            ),
            other => panic!("{other:?}"),
        })
        .collect();
    assert_eq!(spots[0], (-Vec3::Y, 30.0, 25.0, SpotFalloff::Smoothstep));
    assert!(close(spots[1].0, Vec3::new(0.6, 0.0, 0.8)));
    assert_eq!((spots[1].1, spots[1].2), (60.0, 12.5));
    assert_eq!(spots[1].3, SpotFalloff::Quartic);
    // A cone narrower than pbrt's 5° delta starts falling off at once.
    assert_eq!((spots[2].1, spots[2].2), (3.0, 0.0));
    assert!(scene.lights.iter().all(|l| check_light(l).is_ok()));
}

#[test]
fn distant_and_environment_lights() {
    let (scene, report) = scene_with(
        "[[lights]]\ntype = \"distant\"\ndirection = [0, -5, 0]\nirradiance = [1, 0.5, 0]\n\n\
         [[lights]]\ntype = \"environment\"\nradiance = [0.1, 0.2, 0.3]",
        "",
        "",
    );
    assert_eq!(
        scene.lights,
        [
            Light::Distant {
                direction: -Vec3::Y,
                irradiance: Vec3::new(1.0, 0.5, 0.0)
            },
            Light::Environment {
                radiance: Vec3::new(0.1, 0.2, 0.3)
            }
        ]
    );
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
}

/// A mesh light reads its OBJ as a mesh object does (the same transform: scale, rotate,
/// translate), into one mesh of material 0 without vertex normals (an emitter is flat), and
/// its zero-area triangles are dropped and counted.
#[test]
fn mesh_lights_are_placed_like_mesh_objects() {
    let (scene, _) = scene_with(
        "[[lights]]\ntype = \"mesh\"\nfile = \"meshes/transform.obj\"\nscale = 2\n\
         rotate = [0, 0, 90]\ntranslate = [0, 0, 3]\npower = [5, 5, 5]\ntwo_sided = true",
        "",
        "[[objects]]\ntype = \"mesh\"\nfile = \"meshes/transform.obj\"\nscale = 2\n\
         rotate = [0, 0, 90]\ntranslate = [0, 0, 3]\nmaterial = \"white\"",
    );
    let Light::Mesh {
        mesh,
        power,
        two_sided,
    } = &scene.lights[0]
    else {
        panic!("{:?}", scene.lights[0])
    };
    let scene::Shape::Triangles(object) = &scene.shapes[1] else {
        panic!("the mesh object")
    };
    assert_eq!(
        mesh.positions, object.positions,
        "placed as the mesh object is"
    );
    assert_eq!(mesh.triangles, object.triangles);
    assert!(object.normals.is_some() && mesh.normals.is_none());
    assert_eq!(
        (mesh.material, *power, *two_sided),
        (0, Vec3::splat(5.0), true)
    );
    // Scale 2, then x → y about z, then up 3: (1, 0, 0) goes to (0, 2, 3).
    assert!(
        close(mesh.positions[0], Vec3::new(0.0, 2.0, 3.0)),
        "{:?}",
        mesh.positions
    );

    let (scene, report) = scene_with(
        "[[lights]]\ntype = \"mesh\"\nfile = \"meshes/degenerate.obj\"\npower = [5, 5, 5]",
        "",
        "",
    );
    assert_eq!(report.degenerate_triangles_dropped, 2);
    let Light::Mesh {
        mesh, two_sided, ..
    } = &scene.lights[0]
    else {
        panic!()
    };
    assert_eq!((mesh.triangles.len(), *two_sided), (2, false));
    assert!(check_light(&scene.lights[0]).is_ok());
}

/// A mesh light's OBJ may name MTL materials: they are not read into the scene's materials.
#[test]
fn a_mesh_lights_mtl_materials_are_ignored() {
    let (scene, _) = scene_with(
        "[[lights]]\ntype = \"mesh\"\nfile = \"meshes/materials.obj\"\npower = [5, 5, 5]",
        "",
        "",
    );
    assert_eq!(scene.materials.len(), 1, "only `white`");
    let Light::Mesh { mesh, .. } = &scene.lights[0] else {
        panic!()
    };
    assert_eq!(mesh.triangles.len(), 8, "every face, whatever its material");
}

#[test]
fn mirror_and_glass_tints_default_to_one() {
    let (scene, _) = scene_with(
        "[[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\npower = [1, 1, 1]",
        "[materials.a_chrome]\ntype = \"mirror\"\n\n\
         [materials.b_gold]\ntype = \"mirror\"\ntint = [1, 0.8, 0.3]\n\n\
         [materials.c_glass]\ntype = \"glass\"\nior = 1.5\n\n\
         [materials.d_green_glass]\ntype = \"glass\"\nior = 1.4\nreflect_tint = [0.9, 0.9, 0.9]\n\
         transmit_tint = [0.2, 1, 0.3]",
        "",
    );
    assert_eq!(
        scene.materials[..4],
        [
            Material::MIRROR,
            Material::Mirror {
                tint: Vec3::new(1.0, 0.8, 0.3)
            },
            Material::clear_glass(1.5),
            Material::Glass {
                ior: 1.4,
                reflect_tint: Vec3::splat(0.9),
                transmit_tint: Vec3::new(0.2, 1.0, 0.3)
            },
        ]
    );
    assert!(scene.materials.iter().all(|m| check_material(m).is_ok()));
}

/// MTL `illum 3`/`5` mirrors take `Ks` as their tint; without `Ks` they are untinted.
#[test]
fn mtl_ks_tints_mirrors() {
    let (scene, _) = scene_with(
        "[[lights]]\ntype = \"point\"\nposition = [0, 3, 0]\npower = [1, 1, 1]",
        "",
        "[[objects]]\ntype = \"mesh\"\nfile = \"meshes/tinted-mirror.obj\"",
    );
    assert_eq!(
        scene.materials[1..],
        [
            Material::Mirror {
                tint: Vec3::new(0.9, 0.5, 0.2)
            },
            Material::MIRROR
        ]
    );
}

/// What the file refuses, `check_light` and `check_material` refuse too, naming the field as
/// the public types spell it: the one set of rules, for descriptions built in code.
#[test]
fn the_checks_for_built_descriptions_refuse_what_the_file_does() {
    let spot = |cone: f32, start: f32, direction: Vec3| Light::Spot {
        position: Vec3::ZERO,
        direction,
        cone_angle_degrees: cone,
        falloff_start_degrees: start,
        falloff: SpotFalloff::Smoothstep,
        power: Vec3::ONE,
    };
    let field = |l: &Light| check_light(l).unwrap_err().field;
    assert_eq!(field(&spot(30.0, 35.0, Vec3::Y)), "falloff_start_degrees");
    assert_eq!(field(&spot(181.0, 0.0, Vec3::Y)), "cone_angle_degrees");
    assert_eq!(field(&spot(30.0, 0.0, Vec3::ZERO)), "direction");
    assert_eq!(
        field(&spot(30.0, 0.0, Vec3::new(f32::NAN, 1.0, 0.0))),
        "direction[0]"
    );
    let e = check_light(&Light::Point {
        position: Vec3::ZERO,
        power: Vec3::new(1.0, -1.0, 0.0),
    })
    .unwrap_err();
    assert_eq!(e.to_string(), "power[1]: -1 watts must be finite and >= 0");
    let message: String = e.into();
    assert!(message.starts_with("power[1]: "));
    let glass = Material::Glass {
        ior: 0.9,
        reflect_tint: Vec3::ONE,
        transmit_tint: Vec3::ONE,
    };
    assert_eq!(check_material(&glass).unwrap_err().field, "ior");
    let mesh = Light::Mesh {
        mesh: scene::TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
            triangles: vec![[0, 1, 3]],
            ..Default::default()
        },
        power: Vec3::ONE,
        two_sided: false,
    };
    assert_eq!(field(&mesh), "mesh.triangles[0]");
}

/// The photon-map and film fingerprint of a scene sees every field of the new lights and every
/// tint: changing any one changes it, so maps and films of the old values are refused.
#[test]
fn the_scene_fingerprint_sees_every_new_field() {
    use dpm::photon::store::scene_fingerprint;
    let (base, _) = scene_with(
        "[[lights]]\ntype = \"spot\"\nposition = [0, 3, 0]\ndirection = [0, -1, 0]\npower = [1, 1, 1]\n\n\
         [[lights]]\ntype = \"distant\"\ndirection = [0, -1, 0]\nirradiance = [1, 1, 1]\n\n\
         [[lights]]\ntype = \"environment\"\nradiance = [1, 1, 1]\n\n\
         [[lights]]\ntype = \"mesh\"\nfile = \"meshes/transform.obj\"\npower = [1, 1, 1]",
        "[materials.chrome]\ntype = \"mirror\"\n\n[materials.glass]\ntype = \"glass\"\nior = 1.5",
        "",
    );
    let before = scene_fingerprint(&base);
    let changes: [&dyn Fn(&mut SceneDescription); 13] = [
        &|s| set_spot(s, |position, _, _, _, _| position.x = 0.5),
        &|s| set_spot(s, |_, direction, _, _, _| *direction = Vec3::X),
        &|s| set_spot(s, |_, _, cone, _, _| *cone = 31.0),
        &|s| set_spot(s, |_, _, _, start, _| *start = 20.0),
        &|s| set_spot(s, |_, _, _, _, falloff| *falloff = SpotFalloff::Quartic),
        &|s| {
            s.lights[1] = Light::Distant {
                direction: Vec3::X,
                irradiance: Vec3::ONE,
            }
        },
        &|s| {
            s.lights[1] = Light::Distant {
                direction: -Vec3::Y,
                irradiance: Vec3::splat(2.0),
            }
        },
        &|s| {
            s.lights[2] = Light::Environment {
                radiance: Vec3::splat(0.5),
            }
        },
        &|s| {
            if let Light::Mesh { two_sided, .. } = &mut s.lights[3] {
                *two_sided = true;
            }
        },
        &|s| {
            if let Light::Mesh { mesh, .. } = &mut s.lights[3] {
                mesh.positions[0].y += 0.1;
            }
        },
        &|s| {
            s.materials[0] = Material::Mirror {
                tint: Vec3::new(1.0, 1.0, 0.5),
            }
        },
        &|s| {
            s.materials[1] = Material::Glass {
                ior: 1.5,
                reflect_tint: Vec3::new(0.5, 1.0, 1.0),
                transmit_tint: Vec3::ONE,
            }
        },
        &|s| {
            s.materials[1] = Material::Glass {
                ior: 1.5,
                reflect_tint: Vec3::ONE,
                transmit_tint: Vec3::new(0.5, 1.0, 1.0),
            }
        },
    ];
    // Materials are numbered in name order: chrome, glass, white.
    assert_eq!(
        base.materials[..2],
        [Material::MIRROR, Material::clear_glass(1.5)]
    );
    for (i, change) in changes.iter().enumerate() {
        let mut changed = base.clone();
        change(&mut changed);
        assert_ne!(changed, base, "change {i} changes nothing");
        assert_ne!(
            scene_fingerprint(&changed),
            before,
            "change {i} is not in the fingerprint"
        );
    }
}

/// Applies `f` to the fields of the first light, a spot.
fn set_spot(
    scene: &mut SceneDescription,
    f: impl Fn(&mut Vec3, &mut Vec3, &mut f32, &mut f32, &mut SpotFalloff),
) {
    let Light::Spot {
        position,
        direction,
        cone_angle_degrees,
        falloff_start_degrees,
        falloff,
        ..
    } = &mut scene.lights[0]
    else {
        panic!("the first light is a spot")
    };
    f(
        position,
        direction,
        cone_angle_degrees,
        falloff_start_degrees,
        falloff,
    );
}
