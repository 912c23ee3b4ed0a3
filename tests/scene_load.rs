//! Scene loading from the outside: every scene in scenes/ loads with the geometry its figure
//! needs, mesh transforms and MTL materials come out as computed by hand, and each malformed
//! file in tests/fixtures/bad/ fails with the expected file, line and field.

use dpm::scene::{
    self, Camera, Light, Material, SceneDescription, SceneError, Shape, TriangleMesh,
};
use glam::Vec3;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

fn repo(relative: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(relative)
}

fn load_scene(name: &str) -> SceneDescription {
    let path = repo(&format!("scenes/{name}"));
    scene::load(&path).unwrap_or_else(|e| panic!("{name} should load: {e}"))
}

/// Parses scene text as if it lived in tests/fixtures/, so `meshes/...` names fixture meshes.
fn parse_fixture_scene(text: &str) -> (SceneDescription, scene::LoadReport) {
    scene::parse(text, &repo("tests/fixtures/inline.toml")).unwrap_or_else(|e| panic!("{e}"))
}

fn meshes(scene: &SceneDescription) -> Vec<&TriangleMesh> {
    scene
        .shapes
        .iter()
        .filter_map(|s| match s {
            Shape::Triangles(mesh) => Some(&**mesh),
            Shape::Sphere { .. } | Shape::Curves(_) => None,
        })
        .collect()
}

fn face_normal(mesh: &TriangleMesh, [a, b, c]: [u32; 3]) -> Vec3 {
    let p = |i: u32| mesh.positions[i as usize];
    (p(b) - p(a)).cross(p(c) - p(a))
}

fn close(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).length() <= tolerance
}

/// The unit normal a quad object's two triangles share.
fn quad_normal(mesh: &TriangleMesh) -> Vec3 {
    assert_eq!(mesh.triangles.len(), 2, "a quad is two triangles");
    let n0 = face_normal(mesh, mesh.triangles[0]).normalize();
    let n1 = face_normal(mesh, mesh.triangles[1]).normalize();
    assert!(
        close(n0, n1, 1e-6),
        "both triangles of a quad face the same way"
    );
    n0
}

/// Vertex normals are unit and on the side the triangles' winding faces.
fn assert_normals_agree_with_winding(mesh: &TriangleMesh, name: &str) {
    let normals = mesh
        .normals
        .as_ref()
        .unwrap_or_else(|| panic!("{name} has smooth normals"));
    assert_eq!(normals.len(), mesh.positions.len());
    for n in normals {
        assert!(
            (n.length() - 1.0).abs() < 1e-4,
            "{name}: normal {n} is not unit"
        );
    }
    for &triangle in &mesh.triangles {
        let face = face_normal(mesh, triangle);
        for v in triangle {
            assert!(
                face.dot(normals[v as usize]) > 0.0,
                "{name}: {triangle:?} faces against its normals"
            );
        }
    }
}

fn bounds(mesh: &TriangleMesh) -> (Vec3, Vec3) {
    let min = mesh.positions.iter().fold(Vec3::INFINITY, |m, &p| m.min(p));
    let max = mesh
        .positions
        .iter()
        .fold(Vec3::NEG_INFINITY, |m, &p| m.max(p));
    (min, max)
}

#[test]
fn every_scene_in_scenes_loads() {
    let mut loaded = Vec::new();
    for entry in std::fs::read_dir(repo("scenes")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let (scene, report) = scene::load_with_report(&path).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(report.degenerate_triangles_dropped, 0, "{}", path.display());
            assert_eq!(scene.source, path);
            assert!(!scene.lights.is_empty() && !scene.shapes.is_empty());
            loaded.push(path.file_name().unwrap().to_string_lossy().into_owned());
        }
    }
    loaded.sort();
    assert_eq!(
        loaded,
        [
            "cornell-box.toml",
            "cornell-point.toml",
            "fog-caustic.toml",
            "metal-ring.toml",
            "point-plane.toml",
            "spot-and-sky.toml",
            "torus-knot.toml"
        ]
    );
}

#[test]
fn scenes_use_every_light_and_material_kind() {
    let scenes = [
        "cornell-box.toml",
        "metal-ring.toml",
        "point-plane.toml",
        "spot-and-sky.toml",
        "torus-knot.toml",
    ]
    .map(load_scene);
    let lights: Vec<&Light> = scenes.iter().flat_map(|s| &s.lights).collect();
    assert!(lights.iter().any(|l| matches!(l, Light::Point { .. })));
    assert!(lights.iter().any(|l| matches!(l, Light::Sphere { .. })));
    assert!(lights.iter().any(|l| matches!(l, Light::Quad { .. })));
    assert!(lights.iter().any(|l| matches!(
        l,
        Light::Spot {
            falloff: scene::SpotFalloff::Quartic,
            ..
        }
    )));
    assert!(lights.iter().any(|l| matches!(l, Light::Distant { .. })));
    assert!(
        lights
            .iter()
            .any(|l| matches!(l, Light::Environment { .. }))
    );
    assert!(lights.iter().any(|l| matches!(
        l,
        Light::Mesh {
            two_sided: true,
            ..
        }
    )));
    let materials: Vec<&Material> = scenes.iter().flat_map(|s| &s.materials).collect();
    assert!(
        materials
            .iter()
            .any(|m| matches!(m, Material::Diffuse { .. }))
    );
    assert!(
        materials
            .iter()
            .any(|m| matches!(m, Material::Mirror { .. }))
    );
    assert!(
        materials
            .iter()
            .any(|m| matches!(m, Material::Glass { .. }))
    );
    // Tints away from their defaults, every one.
    let tinted = |v: &Vec3| *v != Vec3::ONE;
    assert!(
        materials
            .iter()
            .any(|m| matches!(m, Material::Mirror { tint } if tinted(tint)))
    );
    assert!(materials.iter().any(|m| matches!(
        m,
        Material::Glass { reflect_tint, transmit_tint, .. } if tinted(reflect_tint) && tinted(transmit_tint)
    )));
}

#[test]
fn torus_knot_is_closed_glass_floating_over_the_floor_under_a_small_light() {
    let scene = load_scene("torus-knot.toml");
    let [Light::Sphere { center, radius, .. }] = scene.lights[..] else {
        panic!("one sphere light: {:?}", scene.lights);
    };
    assert!(radius <= 0.1 && center.y > 3.0);

    let all = meshes(&scene);
    assert_eq!(all.len(), 2, "knot and floor");
    let knot = all.iter().find(|m| m.triangles.len() > 2).unwrap();
    let floor = all.iter().find(|m| m.triangles.len() == 2).unwrap();
    assert_eq!(knot.triangles.len(), 600 * 24 * 2);
    assert_eq!(knot.positions.len(), 600 * 24);
    assert_eq!(
        scene.materials[knot.material as usize],
        Material::clear_glass(1.5)
    );
    assert!(matches!(
        scene.materials[floor.material as usize],
        Material::Diffuse { .. }
    ));
    assert_normals_agree_with_winding(knot, "torus knot");

    // Glass must be watertight and consistently wound: each directed edge once, with its
    // reverse in the neighbouring triangle.
    let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
    for t in &knot.triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *directed.entry((a, b)).or_default() += 1;
        }
    }
    assert!(
        directed
            .iter()
            .all(|(&(a, b), &n)| n == 1 && directed.get(&(b, a)) == Some(&1))
    );

    let (knot_min, knot_max) = bounds(knot);
    let floor_y = floor.positions[0].y;
    assert!(knot_min.y > floor_y + 0.3, "the knot floats: {knot_min}");
    assert!(
        knot_max.y < center.y - 1.0,
        "the light is well above the knot"
    );
    assert!(
        quad_normal(floor).dot(Vec3::Y) > 0.999,
        "the floor faces up"
    );
    // The rotation turned the knot's symmetry axis vertical: it is wide in x and z, flat in y.
    let size = knot_max - knot_min;
    assert!(size.x > 2.0 && size.z > 2.0 && size.y < 1.0, "{size}");
    // The camera looks down at the floor.
    let Camera {
        position, look_at, ..
    } = scene.camera;
    assert!((look_at - position).normalize().y < -0.4);
}

#[test]
fn metal_ring_is_a_squashed_mirror_shell_lit_from_a_low_angle() {
    let scene = load_scene("metal-ring.toml");
    let [Light::Sphere { center, .. }] = scene.lights[..] else {
        panic!("one sphere light: {:?}", scene.lights);
    };
    let elevation = (center.y / Vec3::new(center.x, 0.0, center.z).length())
        .atan()
        .to_degrees();
    assert!(
        (15.0..=25.0).contains(&elevation),
        "light elevation {elevation}°"
    );

    let all = meshes(&scene);
    let ring = all.iter().find(|m| m.triangles.len() > 2).unwrap();
    assert_eq!(
        ring.triangles.len(),
        3 * 720 * 2,
        "inner wall, outer wall, rim"
    );
    assert_eq!(scene.materials[ring.material as usize], Material::MIRROR);
    assert_normals_agree_with_winding(ring, "metal ring");

    let (min, max) = bounds(ring);
    assert!(
        min.y.abs() < 1e-6 && (max.y - 0.4).abs() < 1e-5,
        "stands on y = 0, 0.4 tall"
    );
    let normals = ring.normals.as_ref().unwrap();
    let radius = |p: Vec3| Vec3::new(p.x, 0.0, p.z).length();
    let inner_wall: Vec<usize> = (0..ring.positions.len())
        .filter(|&i| (radius(ring.positions[i]) - 1.0).abs() < 1e-4 && normals[i].y.abs() < 1e-6)
        .collect();
    assert_eq!(inner_wall.len(), 2 * 720);
    for i in inner_wall {
        // The y-squash keeps wall normals horizontal and pointing at the axis.
        let toward_axis = -Vec3::new(ring.positions[i].x, 0.0, ring.positions[i].z).normalize();
        assert!(close(normals[i], toward_axis, 1e-4));
    }
    let rim = normals.iter().filter(|n| close(**n, Vec3::Y, 1e-6)).count();
    assert_eq!(
        rim,
        2 * 720,
        "flat rim normals are kept apart from the walls'"
    );
}

#[test]
fn cornell_box_walls_face_inward_around_a_mirror_and_a_glass_sphere() {
    let scene = load_scene("cornell-box.toml");
    let [
        Light::Quad {
            corner,
            edge_u,
            edge_v,
            power,
        },
    ] = scene.lights[..]
    else {
        panic!("one quad light: {:?}", scene.lights);
    };
    assert!(
        close(edge_u.cross(edge_v).normalize(), -Vec3::Y, 1e-6),
        "the light faces down"
    );
    assert!(corner.y > 1.9 && corner.y < 2.0 && power.min_element() > 0.0);

    let walls = meshes(&scene);
    assert_eq!(walls.len(), 5);
    let box_centre = Vec3::new(0.0, 1.0, 0.0);
    let mut by_colour = Vec::new();
    for wall in &walls {
        let middle = (wall.positions[0] + wall.positions[2]) / 2.0;
        assert!(
            quad_normal(wall).dot(box_centre - middle) > 0.0,
            "wall at {middle} faces in"
        );
        let Material::Diffuse { albedo } = scene.materials[wall.material as usize] else {
            panic!("walls are diffuse");
        };
        by_colour.push((middle, albedo));
    }
    let left = by_colour.iter().find(|(m, _)| m.x < -0.99).unwrap().1;
    let right = by_colour.iter().find(|(m, _)| m.x > 0.99).unwrap().1;
    assert!(left.x > 2.0 * left.y, "left wall is red: {left}");
    assert!(right.y > 2.0 * right.x, "right wall is green: {right}");

    let sphere_materials: Vec<&Material> = scene
        .shapes
        .iter()
        .filter_map(|s| match s {
            Shape::Sphere { material, .. } => Some(&scene.materials[*material as usize]),
            _ => None,
        })
        .collect();
    assert_eq!(sphere_materials.len(), 2);
    assert!(sphere_materials.contains(&&Material::MIRROR));
    assert!(
        sphere_materials
            .iter()
            .any(|m| matches!(m, Material::Glass { ior, .. } if (*ior - 1.5).abs() < 1e-6))
    );
}

#[test]
fn point_plane_has_a_point_light_over_a_plane_facing_it() {
    let scene = load_scene("point-plane.toml");
    let [Light::Point { position, power }] = scene.lights[..] else {
        panic!("one point light: {:?}", scene.lights);
    };
    assert_eq!(power, Vec3::splat(100.0));
    let plane = meshes(&scene)[0];
    let normal = quad_normal(plane);
    let height = (position - plane.positions[0]).dot(normal);
    assert!(
        (height - 1.0).abs() < 1e-6,
        "the light is 1 above the plane, on its front side"
    );
    assert_eq!(scene.camera.width, 512);
    assert_eq!(scene.camera.height, 384);
}

#[test]
fn mesh_transform_scales_then_rotates_x_y_z_then_translates() {
    let (scene, _) = parse_fixture_scene(&fixture_scene(
        r#"
[[objects]]
type = "mesh"
file = "meshes/transform.obj"
material = "white"
translate = [1.0, 2.0, 3.0]
rotate = [90.0, 0.0, 90.0]
scale = [2.0, 1.0, 0.5]
"#,
    ));
    let mesh = meshes(&scene)[0];
    // By hand: p → Rz(90°) Rx(90°) (2x, y, z/2) + (1, 2, 3), where Rx(90°): (x, y, z) → (x, -z, y)
    // and Rz(90°): (x, y, z) → (-y, x, z).
    let expected = [
        Vec3::new(1.0, 4.0, 3.0),
        Vec3::new(1.0, 2.0, 4.0),
        Vec3::new(1.5, 2.0, 3.0),
    ];
    for (got, want) in mesh.positions.iter().zip(expected) {
        assert!(close(*got, want, 1e-5), "{got} != {want}");
    }
    // The normal is the transformed plane's: (p1 - p0) × (p2 - p0) = (0,-2,1) × (0.5,-2,0).
    let want = Vec3::new(2.0, 0.5, 1.0).normalize();
    for n in mesh.normals.as_ref().unwrap() {
        assert!(close(*n, want, 1e-5), "{n} != {want}");
        assert!((n.length() - 1.0).abs() < 1e-6);
        assert!(n.dot(expected[1] - expected[0]).abs() < 1e-5);
        assert!(n.dot(expected[2] - expected[0]).abs() < 1e-5);
    }
}

#[test]
fn uniform_scale_and_defaults() {
    let (scene, _) = parse_fixture_scene(&fixture_scene(
        "[[objects]]\ntype = \"mesh\"\nfile = \"meshes/transform.obj\"\nmaterial = \"white\"\nscale = 3\n",
    ));
    let mesh = meshes(&scene)[0];
    assert_eq!(
        mesh.positions,
        [Vec3::X * 3.0, Vec3::Y * 3.0, Vec3::Z * 3.0]
    );
    let (scene, _) = parse_fixture_scene(&fixture_scene(
        "[[objects]]\ntype = \"mesh\"\nfile = \"meshes/triangle.obj\"\nmaterial = \"white\"\n",
    ));
    let mesh = meshes(&scene)[0];
    assert_eq!(
        mesh.positions,
        [Vec3::ZERO, Vec3::X, Vec3::Y],
        "no transform given: identity"
    );
    assert_eq!(mesh.normals, None, "an OBJ without vn gives flat triangles");
}

#[test]
fn mtl_materials_map_to_diffuse_mirror_and_glass() {
    let (scene, _) = parse_fixture_scene(&fixture_scene(
        "[[objects]]\ntype = \"mesh\"\nfile = \"meshes/materials.obj\"\n",
    ));
    let all = meshes(&scene);
    let got: Vec<(&Material, usize)> = all
        .iter()
        .map(|m| (&scene.materials[m.material as usize], m.triangles.len()))
        .collect();
    let want = [
        (
            Material::Diffuse {
                albedo: Vec3::new(0.8, 0.2, 0.1),
            },
            2,
        ),
        (Material::MIRROR, 1),
        (Material::MIRROR, 1),
        (Material::clear_glass(1.45), 1),
        (Material::clear_glass(1.33), 1),
        (Material::clear_glass(1.6), 1),
        (
            Material::Diffuse {
                albedo: Vec3::splat(0.3),
            },
            1,
        ),
    ];
    assert_eq!(got.len(), want.len(), "{got:?}");
    for ((material, count), (want_material, want_count)) in got.iter().zip(&want) {
        assert_eq!(*material, want_material);
        assert_eq!(*count, *want_count);
    }
    // Scene materials come first; MTL materials are appended after them.
    assert_eq!(
        scene.materials[0],
        Material::Diffuse {
            albedo: Vec3::splat(0.5)
        }
    );
    assert!(all.iter().all(|m| m.material >= 1));
}

#[test]
fn scene_material_overrides_the_mtl() {
    let (scene, _) = parse_fixture_scene(&fixture_scene(
        "[[objects]]\ntype = \"mesh\"\nfile = \"meshes/materials.obj\"\nmaterial = \"white\"\n",
    ));
    let all = meshes(&scene);
    assert_eq!(all.len(), 1, "one material, one mesh");
    assert_eq!(all[0].triangles.len(), 8);
    assert_eq!(scene.materials.len(), 1, "no MTL material was taken");
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let (scene, report) = parse_fixture_scene(&fixture_scene(
        "[[objects]]\ntype = \"mesh\"\nfile = \"meshes/degenerate.obj\"\nmaterial = \"white\"\n",
    ));
    assert_eq!(report.degenerate_triangles_dropped, 2);
    let mesh = meshes(&scene)[0];
    assert_eq!(mesh.triangles, [[0, 1, 2], [0, 2, 3]]);
    for &t in &mesh.triangles {
        assert!(face_normal(mesh, t).normalize().is_finite());
    }
}

/// A valid scene around the given `[[objects]]` text: camera, a point light, material `white`.
/// Integers stand in for floats on purpose: TOML `5` must read as 5.0.
fn fixture_scene(objects: &str) -> String {
    format!(
        "[camera]\nposition = [0, 1, 5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\n\
         fov_y = 40\nresolution = [64, 48]\n\n[[lights]]\ntype = \"point\"\n\
         position = [0.0, 3.0, 0.0]\npower = [10, 10, 10]\n\n[materials.white]\n\
         type = \"diffuse\"\nalbedo = [0.5, 0.5, 0.5]\n\n{objects}"
    )
}

/// Malformed fixtures: (file in tests/fixtures/bad/, the file the error names when it is not
/// the scene (relative to bad/), line, field, a fragment of the message).
#[rustfmt::skip]
const MALFORMED: &[(&str, Option<&str>, usize, &str, &str)] = &[
    ("syntax",                        None,                                 6,  "camera.up",                       "syntax"),
    ("duplicate_key",                 None,                                 7,  "camera.fov_y",                    "syntax"),
    ("unknown_field",                 None,                                 21, "objects[0].radiuss",              "unknown field"),
    ("missing_field",                 None,                                 18, "objects[0].radius",               "missing field"),
    ("wrong_type",                    None,                                 6,  "camera.fov_y",                    "invalid type"),
    ("wrong_length",                  None,                                 3,  "camera.position",                 "invalid length"),
    ("nan_radius",                    None,                                 21, "objects[0].radius",               "greater than 0"),
    ("negative_power",                None,                                 12, "lights[0].power[1]",              ">= 0"),
    ("zero_power",                    None,                                 12, "lights[0].power",                 "emits nothing"),
    ("inf_position",                  None,                                 11, "lights[0].position[1]",           "not a finite number"),
    ("albedo_above_one",              None,                                 16, "materials.white.albedo[0]",       "not in [0, 1]"),
    ("ior_below_one",                 None,                                 20, "materials.glass.ior",             ">= 1"),
    ("fov_out_of_range",              None,                                 6,  "camera.fov_y",                    "(0, 180)"),
    ("camera_negative_lens_radius",   None,                                 7,  "camera.lens_radius",              "not a lens radius"),
    ("camera_crop_outside",           None,                                 7,  "camera.crop_window",              "not a fraction of the film"),
    ("camera_crop_empty",             None,                                 7,  "camera.crop_window",              "is empty"),
    ("camera_unknown_projection",     None,                                 6,  "camera.projection",               "unknown variant"),
    ("camera_orthographic_without_view_height", None,                       2,  "camera",                          "needs view_height"),
    ("camera_orthographic_with_fov",  None,                                 8,  "camera.fov_y",                    "has no fov_y"),
    ("zero_resolution",               None,                                 7,  "camera.resolution[1]",            "at least 1"),
    ("negative_resolution",           None,                                 7,  "camera.resolution[0]",            "invalid value"),
    ("up_parallel",                   None,                                 5,  "camera.up",                       "parallel"),
    ("look_at_is_position",           None,                                 4,  "camera.look_at",                  "equals camera.position"),
    ("unknown_material",              None,                                 22, "objects[0].material",             "unknown material `whit`"),
    ("unknown_light_type",            None,                                 10, "lights[0].type",                  "unknown type `goniometric`"),
    ("unknown_top_level",             None,                                 24, "render",                          "unknown field"),
    ("missing_camera",                None,                                 1,  "camera",                          "missing field"),
    ("no_lights",                     None,                                 2,  "lights",                          "at least one"),
    ("objects_not_array",             None,                                 18, "objects",                         "array of tables"),
    ("mirror_with_field",             None,                                 20, "materials.chrome.reflectance",    "unknown field"),
    ("parallel_edges",                None,                                 28, "objects[1].edge_v",               "parallel"),
    ("zero_edge",                     None,                                 17, "lights[1].edge_u",                "zero length"),
    ("negative_scale",                None,                                 28, "objects[1].scale[1]",             "greater than 0"),
    ("missing_obj",                   None,                                 26, "objects[1].file",                 "cannot be read"),
    ("mesh_is_directory",             None,                                 26, "objects[1].file",                 "is a directory"),
    ("empty_mesh",                    None,                                 26, "objects[1].file",                 "has no faces"),
    ("all_degenerate",                None,                                 26, "objects[1].file",                 "zero-area"),
    ("no_mesh_material",              None,                                 24, "objects[1].material",             "no MTL material"),
    ("nan_vertex",                    Some("meshes/nan-vertex.obj"),        4,  "objects[1].file",                 "not finite"),
    ("face_out_of_range",             Some("meshes/face-out-of-range.obj"), 6,  "objects[1].file",                 "out of bounds"),
    ("bad_number",                    Some("meshes/bad-number.obj"),        3,  "objects[1].file",                 "position parse error"),
    ("missing_mtl",                   Some("meshes/missing-mtl.obj"),       2,  "objects[1].file",                 "cannot be read"),
    ("kd_above_one",                  Some("meshes/bright.mtl"),            7,  "objects[1].file",                 "not in [0, 1]"),
    ("glass_without_ni",              Some("meshes/glass-no-ni.mtl"),       3,  "objects[1].file",                 "needs Ni"),
    ("not_utf8",                      None,                                 2,  "scene",                           "not UTF-8"),
    ("empty_file",                    None,                                 1,  "camera",                          "missing field"),
    ("negative_radius",               None,                                 21, "objects[0].radius",               "greater than 0"),
    ("power_overflows",               None,                                 12, "lights[0].power[0]",              "must be finite"),
    ("nan_camera",                    None,                                 3,  "camera.position[0]",              "not a finite number"),
    ("zero_light_radius",             None,                                 12, "lights[0].radius",                "greater than 0"),
    ("mesh_not_obj",                  None,                                 26, "objects[1].file",                 "has no faces"),
    ("string_resolution",             None,                                 7,  "camera.resolution[0]",            "invalid type"),
    ("spot_nan_direction",            None,                                 12, "lights[0].direction[0]",          "not a finite number"),
    ("spot_zero_direction",           None,                                 12, "lights[0].direction",             "zero length"),
    ("spot_cone_too_wide",            None,                                 13, "lights[0].cone_angle",            "not in (0, 180]"),
    ("spot_zero_cone",                None,                                 13, "lights[0].cone_angle",            "not in (0, 180]"),
    ("spot_falloff_past_cone",        None,                                 14, "lights[0].falloff_start",         "not in [0, 30]"),
    ("spot_negative_falloff_start",   None,                                 13, "lights[0].falloff_start",         "not in [0, 30]"),
    ("spot_unknown_falloff",          None,                                 13, "lights[0].falloff",               "unknown falloff `linear`"),
    ("spot_negative_power",           None,                                 13, "lights[0].power[2]",              "must be finite and >= 0"),
    ("distant_zero_direction",        None,                                 11, "lights[0].direction",             "zero length"),
    ("distant_nan_irradiance",        None,                                 12, "lights[0].irradiance[1]",         "W/m² must be finite"),
    ("distant_zero_irradiance",       None,                                 12, "lights[0].irradiance",            "zero in every channel"),
    ("environment_negative_radiance", None,                                 11, "lights[0].radiance[0]",           "W/(m² sr) must be finite"),
    ("environment_infinite_radiance", None,                                 11, "lights[0].radiance[2]",           "must be finite"),
    ("environment_zero_radiance",     None,                                 11, "lights[0].radiance",              "zero in every channel"),
    ("mesh_light_negative_power",     None,                                 12, "lights[0].power[0]",              "must be finite and >= 0"),
    ("mesh_light_zero_scale",         None,                                 12, "lights[0].scale",                 "greater than 0"),
    ("mesh_light_missing_file",       None,                                 11, "lights[0].file",                  "cannot be read"),
    ("mesh_light_with_material",      None,                                 12, "lights[0].material",              "unknown field"),
    ("mesh_light_two_sided_string",   None,                                 13, "lights[0].two_sided",             "expected a boolean"),
    ("mirror_tint_above_one",         None,                                 20, "materials.chrome.tint[0]",        "not in [0, 1]"),
    ("mirror_tint_nan",               None,                                 20, "materials.chrome.tint[1]",        "not in [0, 1]"),
    ("glass_reflect_tint_negative",   None,                                 21, "materials.glass.reflect_tint[2]", "not in [0, 1]"),
    ("glass_transmit_tint_above_one", None,                                 21, "materials.glass.transmit_tint[1]","not in [0, 1]"),
    ("ks_above_one",                  Some("meshes/bright-mirror.mtl"),     7,  "objects[1].file",                 "Ks channel 1.2"),
    ("mix_unknown_material",          None,                                 20, "materials.speckled.materials[1]", "unknown material `whit`"),
    ("mix_three_materials",           None,                                 20, "materials.speckled.materials",    "two material names, not 3"),
    ("mix_amount_nan",                None,                                 21, "materials.speckled.amount",       "NaN is not in [0, 1]"),
    ("mix_amount_above_one",          None,                                 21, "materials.speckled.amount",       "1.25 is not in [0, 1]"),
    ("mix_reaches_itself",            None,                                 20, "materials.flecked.materials",     "a mix reaches itself"),
];

#[test]
fn malformed_scenes_name_file_line_and_field() {
    let bad = repo("tests/fixtures/bad");
    let mut failures = Vec::new();
    for &(name, error_file, line, field, fragment) in MALFORMED {
        let scene_path = bad.join(format!("{name}.toml"));
        let want_file = error_file.map_or(scene_path.clone(), |f| bad.join(f));
        match scene::load(&scene_path) {
            Ok(_) => failures.push(format!("{name}: loaded, but it is malformed")),
            Err(e) => {
                let ok = e.file == want_file
                    && e.line == Some(line)
                    && e.field == field
                    && e.message.contains(fragment);
                if !ok {
                    failures.push(format!(
                        "{name}: want {}:{line}: {field}: …{fragment}…, got {e}",
                        want_file.display()
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));

    // Every fixture in bad/ is in the table.
    let fixtures = std::fs::read_dir(&bad)
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .path()
                .extension()
                .is_some_and(|x| x == "toml")
        })
        .count();
    assert_eq!(fixtures, MALFORMED.len());
}

#[test]
fn error_display_is_file_line_field_message() {
    let e = SceneError {
        file: PathBuf::from("scenes/x.toml"),
        line: Some(12),
        column: None,
        field: "objects[2].radius".into(),
        message: "-1 must be a finite number greater than 0".into(),
    };
    assert_eq!(
        e.to_string(),
        "scenes/x.toml:12: objects[2].radius: -1 must be a finite number greater than 0"
    );
}

#[test]
fn missing_scene_file_is_an_error() {
    let path = repo("tests/fixtures/no-such-scene.toml");
    let e = scene::load(&path).unwrap_err();
    assert_eq!(e.file, path);
    assert!(e.message.contains("cannot read"), "{e}");
}

/// Cutting a valid scene anywhere gives a located error (or a valid scene), never a panic.
#[test]
fn truncated_scenes_fail_cleanly() {
    let text = std::fs::read_to_string(repo("scenes/cornell-box.toml")).unwrap();
    let lines = text.lines().count();
    let source = repo("scenes/cornell-box.toml");
    for cut in (0..text.len()).filter(|&i| text.is_char_boundary(i)) {
        if let Err(e) = scene::parse(&text[..cut], &source) {
            let line = e
                .line
                .unwrap_or_else(|| panic!("cut at {cut}: no line in {e}"));
            assert!((1..=lines).contains(&line), "cut at {cut}: line {line}");
            assert!(!e.field.is_empty());
        }
    }
}

/// Cutting an OBJ anywhere gives an error naming a file and line, never a panic.
#[test]
fn truncated_obj_files_fail_cleanly() {
    let folder = tempfile::tempdir().unwrap();
    let obj = std::fs::read_to_string(repo("tests/fixtures/meshes/materials.obj")).unwrap();
    std::fs::copy(
        repo("tests/fixtures/meshes/materials.mtl"),
        folder.path().join("materials.mtl"),
    )
    .unwrap();
    let scene = fixture_scene("[[objects]]\ntype = \"mesh\"\nfile = \"cut.obj\"\n");
    let source = folder.path().join("scene.toml");
    for cut in 0..obj.len() {
        std::fs::write(folder.path().join("cut.obj"), &obj[..cut]).unwrap();
        if let Err(e) = scene::parse(&scene, &source) {
            assert!(e.line.is_some(), "cut at {cut}: {e}");
        }
    }
}

/// A vertex normal whose length squared leaves f32's range (the `obj` fuzz target found
/// `vn 0 5555555555555555555550 1`, which became zero and failed the mesh's own checks) keeps
/// its direction, as does one too short to square.
#[test]
fn vertex_normals_past_f32_range_keep_their_direction() {
    let folder = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo("tests/fixtures/meshes/materials.mtl"),
        folder.path().join("materials.mtl"),
    )
    .unwrap();
    let obj = "mtllib materials.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n\
               vn 0 5555555555555555555550 1\nvn 1e-30 0 0\nvn 0 0 1\n\
               usemtl paint\nf 1//1 2//2 3//3\n";
    std::fs::write(folder.path().join("big-normals.obj"), obj).unwrap();
    let scene = fixture_scene("[[objects]]\ntype = \"mesh\"\nfile = \"big-normals.obj\"\n");
    let (loaded, _) =
        scene::parse(&scene, &folder.path().join("scene.toml")).unwrap_or_else(|e| panic!("{e}"));
    let mesh = meshes(&loaded)
        .into_iter()
        .find(|m| m.normals.is_some())
        .expect("the mesh keeps its vertex normals");
    let normals = mesh.normals.as_ref().unwrap();
    assert_eq!(normals.len(), 3);
    for n in normals {
        assert!((n.length() - 1.0).abs() < 1e-5, "{n}");
    }
    assert!(normals[0].y > 0.999 && normals[1].x > 0.999, "{normals:?}");
}
