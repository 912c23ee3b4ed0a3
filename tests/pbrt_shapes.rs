//! pbrt's tessellated shapes through the loader: each becomes triangles (a full sphere stays
//! a sphere), faces the way pbrt's normals point (ReverseOrientation and a mirroring
//! transform flip a quadric's), is placed by its transform, and can carry an area light.

use dpm::scene::{self, Light, Shape, TriangleMesh};
use glam::Vec3;
use std::f32::consts::PI;

/// Loads a pbrt scene whose world is `world` (a point light and a floor are added, so the
/// scene is complete) and returns its shapes and lights, the floor left out.
fn load(world: &str) -> (Vec<Shape>, Vec<Light>) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("shapes.pbrt");
    let text = format!(
        "LookAt 0 1 4  0 1 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\nWorldBegin\n\
         LightSource \"point\" \"point from\" [0 2 0] \"rgb I\" [10 10 10]\n{world}\n\
         Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point3 P\" [-9 -9 -9  9 -9 -9  0 -9 9]\nWorldEnd\n"
    );
    std::fs::write(&path, text).unwrap();
    let (description, report) = scene::load_with_report(&path).unwrap();
    assert_eq!(report.degenerate_triangles_dropped, 0, "{report:?}");
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    let mut shapes = description.shapes;
    shapes.pop();
    (shapes, description.lights)
}

fn only_mesh(world: &str) -> TriangleMesh {
    match &load(world).0[..] {
        [Shape::Triangles(mesh)] => (**mesh).clone(),
        other => panic!("{world}: {other:?}"),
    }
}

/// Each triangle's geometric normal (its winding) times its area, and its centroid.
fn faces(mesh: &TriangleMesh) -> Vec<(Vec3, Vec3)> {
    mesh.triangles
        .iter()
        .map(|&[a, b, c]| {
            let p = |i: u32| mesh.positions[i as usize];
            (
                0.5 * (p(b) - p(a)).cross(p(c) - p(a)),
                (p(a) + p(b) + p(c)) / 3.0,
            )
        })
        .collect()
}

fn area(mesh: &TriangleMesh) -> f32 {
    faces(mesh).iter().map(|(n, _)| n.length()).sum()
}

#[test]
fn every_tessellated_shape_loads_and_a_full_sphere_stays_a_sphere() {
    for shape in [
        r#"Shape "disk" "float radius" 2 "float innerradius" 1 "float phimax" 270"#,
        r#"Shape "cylinder" "float zmin" 0 "float zmax" 2"#,
        r#"Shape "cone" "float height" 2"#,
        r#"Shape "paraboloid" "float zmin" 0.5"#,
        r#"Shape "hyperboloid" "point3 p1" [1 0 -1] "point3 p2" [0 1 1]"#,
        r#"Shape "sphere" "float zmax" 0.5"#,
        r#"Shape "sphere" "float phimax" 90"#,
        r#"Shape "heightfield" "integer nu" 3 "integer nv" 2 "float Pz" [0 1 0 1 0 1]"#,
        r#"Shape "loopsubdiv" "integer nlevels" 1 "point3 P" [1 1 1  1 -1 -1  -1 1 -1  -1 -1 1] "integer indices" [0 1 2 0 3 1 0 2 3 1 3 2]"#,
    ] {
        let mesh = only_mesh(shape);
        assert!(!mesh.triangles.is_empty(), "{shape}");
    }
    let (shapes, _) = load(
        r#"Shape "sphere" "float radius" 2 "float zmin" -5 "float zmax" 5 "float phimax" 360"#,
    );
    assert!(
        matches!(shapes[..], [Shape::Sphere { radius: 2.0, .. }]),
        "{shapes:?}"
    );
}

#[test]
fn quadrics_face_outward_unless_reversed_or_mirrored() {
    let disk = r#"Shape "disk" "float height" 1"#;
    let up = |mesh: &TriangleMesh| faces(mesh).iter().all(|(n, _)| n.z > 0.0);
    let down = |mesh: &TriangleMesh| faces(mesh).iter().all(|(n, _)| n.z < 0.0);
    assert!(up(&only_mesh(disk)));
    assert!(down(&only_mesh(&format!("ReverseOrientation\n{disk}"))));
    // pbrt-v3 flips a quadric's normal in its own space when the transform swaps
    // handedness; the mirror then turns the disk (now at z = -1) the other way again.
    let mirrored = only_mesh(&format!("Scale 1 1 -1\n{disk}"));
    assert!(mirrored.positions.iter().all(|p| (p.z + 1.0).abs() < 1e-6));
    assert!(up(&mirrored));
    assert!(down(&only_mesh(&format!(
        "Scale 1 1 -1\nReverseOrientation\n{disk}"
    ))));

    // A hemisphere placed off the origin: wound and shaded outwards.
    let cap = only_mesh(r#"Translate 3 0 0 Shape "sphere" "float radius" 2 "float zmin" 0"#);
    let centre = Vec3::new(3.0, 0.0, 0.0);
    assert!(faces(&cap).iter().all(|(n, c)| n.dot(*c - centre) > 0.0));
    let normals = cap.normals.as_ref().unwrap();
    for (p, n) in cap.positions.iter().zip(normals) {
        assert!((*n - (*p - centre) / 2.0).length() < 1e-4, "{n} at {p}");
        assert!(((*p - centre).length() - 2.0).abs() < 1e-5);
    }
    let inside = only_mesh(r#"ReverseOrientation Shape "sphere" "float zmin" 0"#);
    assert!(faces(&inside).iter().all(|(n, c)| n.dot(*c) < 0.0));
    let hemisphere_area = 2.0 * PI * 4.0;
    assert!((area(&cap) - hemisphere_area).abs() < 1e-3 * hemisphere_area);
}

#[test]
fn a_heightfield_is_scaled_by_its_transform() {
    let mesh = only_mesh(
        r#"Scale 2 3 1 Shape "heightfield" "integer nu" 4 "integer nv" 5 "float Pz" [0 0 0 0  0 0 0 0  0 0 0 0  0 0 0 0  0 0 0 0]"#,
    );
    assert_eq!(mesh.triangles.len(), 2 * 3 * 4);
    assert!((area(&mesh) - 6.0).abs() < 1e-5);
    assert!(faces(&mesh).iter().all(|(n, _)| n.z > 0.0));
    assert!(mesh.normals.is_none());
}

#[test]
fn loop_subdivision_keeps_pbrt_s_limit_normals() {
    // A tetrahedron wound counter-clockwise seen from outside: pbrt's limit normals, and so
    // its faces, point inwards.
    let mesh = only_mesh(
        r#"Shape "loopsubdiv" "integer levels" 2 "point3 P" [1 1 1  1 -1 -1  -1 1 -1  -1 -1 1] "integer indices" [0 1 2 0 3 1 0 2 3 1 3 2]"#,
    );
    assert_eq!((mesh.positions.len(), mesh.triangles.len()), (34, 64));
    assert!(faces(&mesh).iter().all(|(n, c)| n.dot(*c) < 0.0));
    let normals = mesh.normals.as_ref().unwrap();
    assert!(
        mesh.positions
            .iter()
            .zip(normals)
            .all(|(p, n)| n.dot(*p) < 0.0)
    );
}

#[test]
fn a_disk_can_emit() {
    let (_, lights) = load(
        r#"AttributeBegin AreaLightSource "diffuse" "rgb L" [1 1 1] Shape "disk" "float radius" 0.5 AttributeEnd"#,
    );
    let Some(Light::Mesh {
        mesh,
        power,
        two_sided: false,
    }) = lights.last()
    else {
        panic!("{lights:?}");
    };
    let disk_area = PI * 0.25;
    assert!(
        (power.x - PI * disk_area).abs() < 1e-3 * PI * disk_area,
        "{power}"
    );
    assert!(faces(mesh).iter().all(|(n, _)| n.z > 0.0));
}

#[test]
fn the_world_reads_loaded_meshes_in_place_and_shades_them_from_the_same_buffers() {
    // A textured quad with vertex normals and (u, v), over the floor `load` adds.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("smooth.pbrt");
    let text = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\nWorldBegin\n\
        LightSource \"point\" \"point from\" [0 0 4] \"rgb I\" [10 10 10]\n\
        Texture \"checks\" \"spectrum\" \"checkerboard\"\n\
        Material \"matte\" \"texture Kd\" \"checks\"\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2 0 2 3]\n\
          \"point3 P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0]\n\
          \"normal N\" [0 0 1  0.6 0 0.8  0 0.6 0.8  0 0 1]\n\
          \"float uv\" [0 0  1 0  1 1  0 1]\n\
        Shape \"trianglemesh\" \"integer indices\" [0 1 2] \"point3 P\" [-9 -9 -9  9 -9 -9  0 -9 9]\n\
        WorldEnd\n";
    std::fs::write(&path, text).unwrap();
    let description = scene::load(&path).unwrap();
    let meshes = (description.shapes.iter())
        .filter(|s| matches!(s, Shape::Triangles(_)))
        .count();
    assert_eq!(meshes, 2);
    let world = dpm::world::World::new(description).unwrap();
    assert_eq!(world.meshes_read_in_place(), meshes);

    // (0.2, −0.3) lies in the first triangle at barycentrics (u, v) = (0.25, 0.35).
    let origin = Vec3::new(0.2, -0.3, 5.0);
    let hit = world
        .intersect(origin, -Vec3::Z, 0.0, f32::INFINITY)
        .unwrap();
    assert!((hit.t - 5.0).abs() < 1e-5, "{}", hit.t);
    assert!(hit.geometric_normal.abs_diff_eq(Vec3::Z, 1e-6));
    let shading =
        (0.4 * Vec3::Z + 0.25 * Vec3::new(0.6, 0.0, 0.8) + 0.35 * Vec3::new(0.0, 0.6, 0.8))
            .normalize();
    assert!(
        hit.shading_normal.abs_diff_eq(shading, 1e-5),
        "{} against {shading}",
        hit.shading_normal
    );
    let uv = world.uv_at(&hit);
    assert!(uv.abs_diff_eq(glam::Vec2::new(0.6, 0.35), 1e-5), "{uv}");
}
