//! OBJ `mtllib` naming several material libraries on one line (the format allows it): each is
//! read; one that cannot be read is a warning, and an error only when a material the faces use
//! is in none of those that could; a single file name with spaces still reads whole.

mod support;

use dpm::scene::{self, Material};
use glam::Vec3;
use support::write_scene;

const SCENE: &str = include_str!("fixtures/one-mesh.toml");

fn obj(mtllib: &str, materials: [&str; 2]) -> String {
    format!(
        "mtllib {mtllib}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl {}\nf 1 2 3\nusemtl {}\nf 2 4 3\n",
        materials[0], materials[1]
    )
}

fn dir_with(obj_text: &str) -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    write_scene(dir.path(), "red.mtl", "newmtl red\nKd 0.8 0.1 0.1\n");
    write_scene(
        dir.path(),
        "blue glass.mtl",
        "newmtl blue\nKd 0.1 0.1 0.8\n",
    );
    write_scene(dir.path(), "mirror.mtl", "newmtl chrome\nillum 3\n");
    write_scene(dir.path(), "mesh.obj", obj_text);
    dir
}

#[test]
fn every_library_on_an_mtllib_line_is_read() {
    let dir = dir_with(&obj("red.mtl mirror.mtl", ["red", "chrome"]));
    let (scene, report) =
        scene::load_with_report(&write_scene(dir.path(), "s.toml", SCENE)).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert!(scene.materials.contains(&Material::Diffuse {
        albedo: Vec3::new(0.8, 0.1, 0.1)
    }));
    assert!(
        scene
            .materials
            .iter()
            .any(|m| matches!(m, Material::Mirror { .. })),
        "{:?}",
        scene.materials
    );
}

#[test]
fn an_unreadable_library_is_a_warning_while_the_faces_find_their_materials() {
    let dir = dir_with(&obj("missing.mtl red.mtl mirror.mtl", ["red", "chrome"]));
    let (scene, report) =
        scene::load_with_report(&write_scene(dir.path(), "s.toml", SCENE)).unwrap();
    assert_eq!(scene.materials.len(), 2);
    assert_eq!(report.warnings.len(), 1, "{:?}", report.warnings);
    assert!(
        report.warnings[0].contains("missing.mtl"),
        "{:?}",
        report.warnings
    );
}

#[test]
fn a_material_in_none_of_the_readable_libraries_is_an_error_naming_the_unreadable_one() {
    let dir = dir_with(&obj("red.mtl missing.mtl", ["red", "chrome"]));
    let e = scene::load(&write_scene(dir.path(), "s.toml", SCENE)).unwrap_err();
    assert!(e.to_string().contains("missing.mtl"), "{e}");
    assert!(
        e.to_string().contains("mesh.obj:1"),
        "the mtllib line is blamed: {e}"
    );
}

#[test]
fn a_library_whose_name_has_spaces_reads_whole() {
    let dir = dir_with(&obj("blue glass.mtl", ["blue", "blue"]));
    let (scene, report) =
        scene::load_with_report(&write_scene(dir.path(), "s.toml", SCENE)).unwrap();
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    assert_eq!(
        scene.materials,
        vec![Material::Diffuse {
            albedo: Vec3::new(0.1, 0.1, 0.8)
        }]
    );
}
