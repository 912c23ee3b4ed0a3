use super::*;
use crate::scene::Material;

/// A 2×2 image: bottom row 0, 1; top row 2, 3 (as grey values).
fn two_by_two() -> Arc<TextureImage> {
    Arc::new(TextureImage {
        width: 2,
        height: 2,
        // Stored top row first.
        texels: [2.0, 3.0, 0.0, 1.0].map(Vec3::splat).to_vec(),
    })
}

fn image(wrap: Wrap) -> Texture {
    Texture::Image {
        image: two_by_two(),
        mapping: UvMapping::default(),
        wrap,
        scale: 1.0,
        invert: false,
    }
}

fn at(t: &Texture, s: f32, u: f32) -> f32 {
    t.evaluate(Vec2::new(s, u)).x
}

#[test]
fn texel_centres_read_their_texel_and_bilinear_blends_between_them() {
    let t = image(Wrap::Clamp);
    // Texel centres lie at (0.25, 0.25), (0.75, 0.25), (0.25, 0.75), (0.75, 0.75).
    assert_eq!(at(&t, 0.25, 0.25), 0.0);
    assert_eq!(at(&t, 0.75, 0.25), 1.0);
    assert_eq!(at(&t, 0.25, 0.75), 2.0);
    assert_eq!(at(&t, 0.75, 0.75), 3.0);
    // Halfway between all four: their mean.
    assert_eq!(at(&t, 0.5, 0.5), 1.5);
    // A quarter of the way from texel 0 to texel 1 along s.
    assert!((at(&t, 0.375, 0.25) - 0.25).abs() < 1e-6);
}

#[test]
fn wrap_modes_read_outside_the_image_as_pbrt_defines_them() {
    // At s = 0 (the left edge) bilinear reads the texel left of column 0.
    let repeat = image(Wrap::Repeat);
    let clamp = image(Wrap::Clamp);
    let black = image(Wrap::Black);
    // Row centre t = 0.25 (the bottom row: 0 then 1).
    // Repeat: halfway between column 1 (value 1) and column 0 (value 0).
    assert!((at(&repeat, 0.0, 0.25) - 0.5).abs() < 1e-6);
    // Clamp: column −1 is column 0.
    assert!((at(&clamp, 0.0, 0.25) - 0.0).abs() < 1e-6);
    // At the right edge column 2 is black (halfway between 1 and 0) or column 1 again.
    assert!((at(&black, 1.0, 0.25) - 0.5).abs() < 1e-6);
    assert!((at(&clamp, 1.0, 0.25) - 1.0).abs() < 1e-6);
    // Repeat tiles: (s + 1, t − 3) reads what (s, t) does.
    assert!((at(&repeat, 1.3, -2.6) - at(&repeat, 0.3, 0.4)).abs() < 1e-5);
    // Far outside, black is black and clamp is a corner.
    assert_eq!(at(&black, 7.0, 7.0), 0.0);
    assert_eq!(at(&clamp, 7.0, 7.0), 3.0);
    assert_eq!(at(&clamp, -7.0, -7.0), 0.0);
}

#[test]
fn uv_mapping_scales_then_shifts() {
    let m = UvMapping {
        scale: Vec2::new(2.0, 4.0),
        delta: Vec2::new(0.5, -1.0),
    };
    assert_eq!(m.map(Vec2::new(0.25, 0.5)), Vec2::new(1.0, 1.0));
}

#[test]
fn scale_and_invert_apply_to_the_looked_up_value() {
    let Texture::Image { image, .. } = image(Wrap::Clamp) else {
        unreachable!()
    };
    let scaled = Texture::Image {
        image: image.clone(),
        mapping: UvMapping::default(),
        wrap: Wrap::Clamp,
        scale: 0.25,
        invert: true,
    };
    // 1 − 0.25 × 2 at the top-left texel; 1 − 0.25 × 3 at the top-right.
    assert!((at(&scaled, 0.25, 0.75) - 0.5).abs() < 1e-6);
    assert!((at(&scaled, 0.75, 0.75) - 0.25).abs() < 1e-6);
}

#[test]
fn checkerboard_alternates_and_its_mean_is_the_squares_mean() {
    let (a, b) = (Vec3::new(0.9, 0.5, 0.1), Vec3::new(0.1, 0.2, 0.3));
    let board = Texture::Checkerboard {
        mapping: UvMapping {
            scale: Vec2::splat(8.0),
            delta: Vec2::ZERO,
        },
        even: Box::new(Texture::Constant(a)),
        odd: Box::new(Texture::Constant(b)),
    };
    assert_eq!(board.evaluate(Vec2::new(0.01, 0.01)), a);
    assert_eq!(board.evaluate(Vec2::new(0.135, 0.01)), b);
    assert_eq!(board.evaluate(Vec2::new(0.135, 0.135)), a);
    // Negative coordinates keep alternating (⌊−0.1⌋ = −1).
    assert_eq!(board.evaluate(Vec2::new(-0.01, 0.01)), b);
    let n = 400;
    let mut sum = glam::DVec3::ZERO;
    for i in 0..n {
        for j in 0..n {
            let uv = (Vec2::new(i as f32, j as f32) + 0.5) / n as f32;
            sum += board.evaluate(uv).as_dvec3();
        }
    }
    let mean = (sum / (n * n) as f64).as_vec3();
    assert!((mean - 0.5 * (a + b)).abs().max_element() < 1e-4, "{mean}");
    assert_eq!(board.typical(), 0.5 * (a + b));
}

#[test]
fn scale_multiplies_and_mix_blends_by_amount() {
    let c = |v: f32| Box::new(Texture::Constant(Vec3::splat(v)));
    assert_eq!(at(&Texture::Scale(c(0.5), c(0.6)), 0.0, 0.0), 0.3);
    let mix = Texture::Mix {
        first: c(0.2),
        second: c(1.0),
        amount: c(0.25),
    };
    assert!((at(&mix, 0.0, 0.0) - 0.4).abs() < 1e-6);
}

#[test]
fn textured_material_replaces_only_its_textured_parameters_and_clamps_them() {
    let glass = Material::Glass {
        ior: 1.5,
        reflect_tint: Vec3::splat(0.7),
        transmit_tint: Vec3::splat(0.8),
    };
    let textured = TexturedMaterial {
        material: 0,
        textures: vec![
            (
                TexturedParameter::TransmitTint,
                Texture::Constant(Vec3::new(2.0, 0.5, -1.0)),
            ),
            (TexturedParameter::Ior, Texture::Constant(Vec3::splat(0.5))),
        ],
    };
    assert_eq!(
        textured.evaluate(&glass, Vec2::ZERO),
        Material::Glass {
            ior: 1.0,
            reflect_tint: Vec3::splat(0.7),
            transmit_tint: Vec3::new(1.0, 0.5, 0.0),
        }
    );
}

#[test]
fn a_textured_roughness_is_remapped_at_each_hit() {
    use crate::bsdf::{Axes, Model, ModelParameter, Remap};
    let plastic = Material::Bsdf(Model::Plastic {
        kd: Vec3::splat(0.5),
        ks: Vec3::splat(0.25),
        alpha: Vec2::splat(0.5),
    });
    // 0.1 on the even squares of a checkerboard, 0.4 on the odd ones.
    let textured = TexturedMaterial {
        material: 0,
        textures: vec![(
            TexturedParameter::Model(ModelParameter::Roughness {
                axes: Axes::Both,
                remap: Remap::PbrtV3,
                conductor: false,
            }),
            Texture::Checkerboard {
                mapping: UvMapping {
                    scale: Vec2::splat(2.0),
                    delta: Vec2::ZERO,
                },
                even: Box::new(Texture::Constant(Vec3::splat(0.1))),
                odd: Box::new(Texture::Constant(Vec3::splat(0.4))),
            },
        )],
    };
    let alpha_at = |u: f32, v: f32| match textured.evaluate(&plastic, Vec2::new(u, v)) {
        Material::Bsdf(Model::Plastic { alpha, .. }) => alpha,
        other => panic!("{other:?}"),
    };
    let v3 = crate::bsdf::pbrt_v3_roughness_to_alpha;
    assert_eq!(alpha_at(0.25, 0.25), Vec2::splat(v3(0.1)));
    assert_eq!(alpha_at(0.75, 0.25), Vec2::splat(v3(0.4)));
    assert_ne!(v3(0.1), 0.1);
}
