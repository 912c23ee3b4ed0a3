//! The pilots' decisions on hand-made pilots: which pixels flag their emission, which hold an
//! edge, and the shape hashes those compare.

use super::pilot::*;
use glam::Vec3;

/// A pilot whose last rays are `(branch, angle about y from +z, gap to a light)`.
fn pilot(rays: &[(BranchCode, f32, f32)]) -> Pilot {
    Pilot {
        last_rays: (rays.iter())
            .map(|&(code, a, gap)| LastRay {
                code,
                origin: Vec3::ZERO,
                direction: Vec3::new(a.sin(), 0.0, a.cos()),
                light_gap: gap,
                light: 0,
            })
            .collect(),
        ..Pilot::default()
    }
}

fn five(p: &[Pilot]) -> [&Pilot; 5] {
    [&p[0], &p[1], &p[2], &p[3], &p[4]]
}

const FAN: [f32; 5] = [-0.01, -0.005, 0.0, 0.005, 0.01];

#[test]
fn a_light_within_the_pilots_spread_flags_the_pixel() {
    // Five pilots whose last rays fan over 0.02 rad: a light 0.025 rad from the nearest
    // lies within 1.5 × the spread, one 0.05 rad away does not.
    let root = BranchCode::ROOT;
    let fan = |gap: f32| -> Vec<Pilot> {
        FAN.iter()
            .map(|&a| pilot(&[(root, a, gap + (a + 0.01).abs())]))
            .collect()
    };
    assert!(sees_emission(&five(&fan(0.025))));
    assert!(!sees_emission(&five(&fan(0.05))));
}

#[test]
fn each_branch_is_compared_with_the_same_branch_of_the_other_pilots() {
    // Every pilot splits at glass: a reflected fan near 0 rad and a refracted fan near
    // 1 rad, each 0.02 rad wide; a light 0.1 rad from both is outside either branch's
    // spread. Where one pilot has no refracted branch (a total reflection's edge inside
    // the pixel) the spread is the pixel's widest, about a radian, and the light flags.
    let (r, t) = (BranchCode::ROOT.then(0), BranchCode::ROOT.then(1));
    let split: Vec<Pilot> = FAN
        .iter()
        .map(|&a| pilot(&[(r, a, 0.1), (t, 1.0 + a, 0.1)]))
        .collect();
    assert!(!sees_emission(&five(&split)));
    let mut partial = split.clone();
    partial[2] = pilot(&[(r, 0.0, 0.1)]);
    assert!(sees_emission(&five(&partial)));
}

#[test]
fn a_pixel_inside_a_lights_image_takes_no_emission_samples() {
    let root = BranchCode::ROOT;
    let lit = |emitting: u32| -> Vec<Pilot> {
        FAN.iter()
            .map(|&a| Pilot {
                emitting,
                ..pilot(&[(root, a, -1.0)])
            })
            .collect()
    };
    assert!(!sees_emission(&five(&lit(1))));
    let mut edge = lit(1);
    edge[4].emitting = 0;
    assert!(sees_emission(&five(&edge)));
}

#[test]
fn pilots_that_agree_hold_no_edge_and_any_difference_makes_one() {
    let base = Pilot {
        normal: Some(Vec3::Y),
        visible: 0b101,
        ..Pilot::default()
    };
    assert!(!holds_edge(&[&base; 5]));
    let mut shadowed = base.clone();
    shadowed.visible = 0b001;
    let mut other_object = base.clone();
    other_object.shape.add(7);
    let mut turned = base.clone();
    turned.normal = Some(Vec3::new(0.6, 0.8, 0.0));
    let mut slightly = base.clone();
    slightly.normal = Some(Vec3::new(0.3, 0.954, 0.0).normalize());
    for (odd, edge) in [
        (shadowed, true),
        (other_object, true),
        (turned, true),
        (slightly, false),
    ] {
        assert_eq!(holds_edge(&[&base, &base, &odd, &base, &base]), edge);
    }
}

#[test]
fn shape_hashes_tell_orders_and_objects_apart() {
    let hash = |objects: &[u64]| {
        let mut h = Pilot::default().shape;
        objects.iter().for_each(|&o| h.add(o));
        h
    };
    assert_eq!(hash(&[1, 2]), hash(&[1, 2]));
    assert_ne!(hash(&[1, 2]), hash(&[2, 1]));
    assert_ne!(hash(&[1]), hash(&[1, 1]));
}
