use super::*;
use crate::scene::SpotFalloff;

fn spot(cone: f32, start: f32) -> Light {
    Light::Spot {
        position: Vec3::ZERO,
        direction: -Vec3::Y,
        cone_angle_degrees: cone,
        falloff_start_degrees: start,
        falloff: SpotFalloff::Quartic,
        power: Vec3::ONE,
    }
}

fn field_of(light: &Light) -> String {
    check_light(light).unwrap_err().field
}

#[test]
fn lights_built_in_code_are_checked_field_by_field() {
    assert_eq!(check_light(&spot(30.0, 25.0)), Ok(()));
    assert_eq!(check_light(&spot(180.0, 0.0)), Ok(()));
    assert_eq!(field_of(&spot(0.0, 0.0)), "cone_angle_degrees");
    assert_eq!(field_of(&spot(190.0, 0.0)), "cone_angle_degrees");
    assert_eq!(field_of(&spot(f32::NAN, 0.0)), "cone_angle_degrees");
    assert_eq!(field_of(&spot(30.0, 31.0)), "falloff_start_degrees");
    assert_eq!(field_of(&spot(30.0, -1.0)), "falloff_start_degrees");
    let not_unit = Light::Distant {
        direction: Vec3::new(0.0, -2.0, 0.0),
        irradiance: Vec3::ONE,
    };
    let e = check_light(&not_unit).unwrap_err();
    assert_eq!(e.field, "direction");
    assert!(e.message.contains("unit"), "{e}");
    let dark = Light::Environment {
        radiance: Vec3::new(0.0, -1.0, 0.0),
    };
    assert_eq!(field_of(&dark), "radiance[1]");
    let flat = Light::Mesh {
        mesh: TriangleMesh {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
            triangles: vec![[0, 1, 2]],
            ..Default::default()
        },
        power: Vec3::ONE,
        two_sided: false,
    };
    assert_eq!(field_of(&flat), "mesh.triangles[0]");
    let e: String = check_light(&flat).unwrap_err().into();
    assert_eq!(e, "mesh.triangles[0]: has zero area");
}

#[test]
fn tints_above_one_are_refused() {
    let mirror = Material::Mirror {
        tint: Vec3::new(0.5, 1.5, 1.0),
    };
    assert_eq!(check_material(&mirror).unwrap_err().field, "tint[1]");
    let glass = Material::Glass {
        ior: 1.5,
        reflect_tint: Vec3::ONE,
        transmit_tint: Vec3::new(1.0, 1.0, f32::NAN),
    };
    assert_eq!(
        check_material(&glass).unwrap_err().field,
        "transmit_tint[2]"
    );
    assert_eq!(check_material(&Material::clear_glass(1.5)), Ok(()));
    assert_eq!(check_material(&Material::MIRROR), Ok(()));
}

#[test]
fn a_material_table_refuses_mixes_that_reach_themselves_nest_too_deep_or_name_nothing() {
    let white = Material::Diffuse { albedo: Vec3::ONE };
    let mix = |a: u32, b: u32| Material::Mix {
        materials: [a, b],
        amount: 0.5,
    };
    assert_eq!(check_materials(&[white, mix(0, 0)]), Ok(()));
    // Material i mixes i − 1 and 0: a chain as deep as the table allows.
    let chain = |depth: usize| {
        let mut table = vec![white];
        table.extend((1..=depth as u32).map(|i| mix(i - 1, 0)));
        table
    };
    assert_eq!(check_materials(&chain(crate::scene::MAX_MIX_DEPTH)), Ok(()));
    let e = check_materials(&chain(crate::scene::MAX_MIX_DEPTH + 1)).unwrap_err();
    assert!(e.message.contains("nest"), "{e}");
    let e = check_materials(&[white, mix(0, 2), mix(1, 0)]).unwrap_err();
    assert_eq!(e.field, "materials[1].materials");
    assert!(e.message.contains("reaches itself"), "{e}");
    let e = check_materials(&[white, mix(0, 7)]).unwrap_err();
    assert!(
        e.field == "materials[1].materials" && e.message.contains("7"),
        "{e}"
    );
    let e = check_materials(&[
        white,
        Material::Mix {
            materials: [0, 0],
            amount: f32::NAN,
        },
    ])
    .unwrap_err();
    assert_eq!(e.field, "materials[1].amount");
}
