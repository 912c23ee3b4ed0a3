use super::*;

fn plastic() -> Model {
    Model::Plastic {
        kd: Vec3::splat(0.5),
        ks: Vec3::splat(0.25),
        alpha: Vec2::splat(0.2),
    }
}

fn coated_conductor() -> Model {
    Model::CoatedConductor {
        interface_alpha: Vec2::ZERO,
        interface_eta: 1.5,
        thickness: 0.01,
        albedo: Vec3::ZERO,
        g: 0.0,
        conductor_eta: Vec3::ONE,
        conductor_k: Vec3::ONE,
        conductor_alpha: Vec2::ZERO,
    }
}

#[test]
fn colours_are_clamped_to_the_unit_range_and_only_the_named_one_changes() {
    let mut m = plastic();
    m.set(ModelParameter::Specular, Vec3::new(2.0, 0.5, -1.0));
    assert_eq!(
        m,
        Model::Plastic {
            kd: Vec3::splat(0.5),
            ks: Vec3::new(1.0, 0.5, 0.0),
            alpha: Vec2::splat(0.2),
        }
    );
    m.set(ModelParameter::Diffuse, Vec3::splat(-3.0));
    assert!(matches!(m, Model::Plastic { kd, .. } if kd == Vec3::ZERO));
}

#[test]
fn indices_stay_at_least_one_and_conductor_constants_in_their_ranges() {
    let mut glass = Model::Dielectric {
        eta: 1.5,
        alpha: Vec2::ZERO,
        reflect_tint: Vec3::ONE,
        transmit_tint: Vec3::ONE,
    };
    glass.set(ModelParameter::Eta, Vec3::splat(0.5));
    assert!(matches!(glass, Model::Dielectric { eta, .. } if eta == 1.0));
    let mut metal = Model::Conductor {
        eta: Vec3::ONE,
        k: Vec3::ONE,
        alpha: Vec2::ZERO,
    };
    metal.set(ModelParameter::ConductorEta, Vec3::new(-1.0, 0.0, 2.0));
    metal.set(ModelParameter::ConductorK, Vec3::new(-1.0, 3.0, 0.0));
    assert_eq!(
        metal,
        Model::Conductor {
            eta: Vec3::new(1e-3, 1e-3, 2.0),
            k: Vec3::new(0.0, 3.0, 0.0),
            alpha: Vec2::ZERO,
        }
    );
    let mut coated = coated_conductor();
    coated.set(ModelParameter::Thickness, Vec3::splat(-1.0));
    assert!(matches!(coated, Model::CoatedConductor { thickness, .. } if thickness == 0.0));
}

#[test]
fn a_conductor_reflectance_gives_that_normal_incidence_fresnel_reflectance() {
    for r in [0.0f32, 0.3, 0.5, 0.9, 1.5] {
        let mut metal = Model::Conductor {
            eta: Vec3::splat(0.2),
            k: Vec3::splat(3.0),
            alpha: Vec2::ZERO,
        };
        metal.set(ModelParameter::ConductorReflectance, Vec3::splat(r));
        let Model::Conductor { eta, k, .. } = metal else {
            unreachable!()
        };
        assert!(eta.is_finite() && k.is_finite());
        // F0 = ((η − 1)² + k²) / ((η + 1)² + k²), with η = 1: k² / (4 + k²).
        let f0 = ((eta - 1.0) * (eta - 1.0) + k * k) / ((eta + 1.0) * (eta + 1.0) + k * k);
        let expected = r.clamp(0.0, 0.9999);
        assert!((f0.x - expected).abs() < 1e-4, "r {r}: F0 {f0}");
    }
}

#[test]
fn a_roughness_is_remapped_and_set_along_its_axes() {
    let roughness = |axes, remap| ModelParameter::Roughness {
        axes,
        remap,
        conductor: false,
    };
    let alpha = |m: Model| match m {
        Model::Plastic { alpha, .. } => alpha,
        _ => unreachable!(),
    };
    let mut m = plastic();
    m.set(roughness(Axes::U, Remap::PbrtV3), Vec3::splat(0.1));
    let v3 = crate::bsdf::pbrt_v3_roughness_to_alpha(0.1);
    assert_eq!(alpha(m), Vec2::new(v3, 0.2));
    m.set(roughness(Axes::V, Remap::PbrtV4), Vec3::splat(0.25));
    assert_eq!(alpha(m), Vec2::new(v3, 0.5));
    m.set(roughness(Axes::Both, Remap::None), Vec3::splat(0.3));
    assert_eq!(alpha(m), Vec2::splat(0.3));
    // A negative roughness is smooth, under any remap.
    m.set(roughness(Axes::Both, Remap::PbrtV3), Vec3::splat(-0.5));
    assert_eq!(alpha(m), Vec2::ZERO);
    // A coated conductor's flag picks which of its two roughnesses.
    let mut c = coated_conductor();
    c.set(
        ModelParameter::Roughness {
            axes: Axes::Both,
            remap: Remap::None,
            conductor: true,
        },
        Vec3::splat(0.4),
    );
    let Model::CoatedConductor {
        interface_alpha,
        conductor_alpha,
        ..
    } = c
    else {
        unreachable!()
    };
    assert_eq!(
        (interface_alpha, conductor_alpha),
        (Vec2::ZERO, Vec2::splat(0.4))
    );
}

#[test]
fn a_parameter_the_model_lacks_leaves_it_alone() {
    let thin = Model::ThinDielectric { eta: 1.5 };
    for parameter in [
        ModelParameter::Specular,
        ModelParameter::Diffuse,
        ModelParameter::ConductorK,
        ModelParameter::Roughness {
            axes: Axes::Both,
            remap: Remap::None,
            conductor: false,
        },
    ] {
        let mut m = thin;
        m.set(parameter, Vec3::splat(0.7));
        assert_eq!(m, thin, "{parameter:?}");
    }
}
