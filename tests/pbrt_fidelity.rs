//! What pbrt's own renders need of a pbrt scene, each checked against pbrt's definitions: the
//! `Integrator` line's depth cap on photon paths (a closed diffuse room's stored power against
//! the sum of the albedo's powers), `directlighting` building no photon maps, the environment
//! light's texel under a chain of rotations against pbrt-v3's `InfiniteAreaLight::Le`, and a
//! floor under a sphere standing on it lit where pbrt lights it however large the floor.

mod support;

use dpm::photon::tracer::{MapKind, trace_map};
use dpm::render::pipeline;
use dpm::scene::{EnvironmentMap, Light, Transport};
use dpm::world::World;
use glam::{DVec3, Mat3, Vec3};
use indicatif::ProgressBar;
use std::f32::consts::{PI, TAU};
use support::eye::{radiance_along, whitted};
use support::pbrt::loads;
use support::*;

/// A closed matte sphere of albedo `rho` around a point light of intensity 1 (Φ = 4π), under
/// the `integrator` line.
fn closed_room(integrator: &str, rho: f32) -> String {
    format!(
        "{integrator}\nLookAt 0 0 0  0 0 -1  0 1 0\nCamera \"perspective\"\n\
         Film \"image\" \"integer xresolution\" 16 \"integer yresolution\" 16\nWorldBegin\n\
         LightSource \"point\" \"rgb I\" [1 1 1]\n\
         Material \"matte\" \"rgb Kd\" [{rho} {rho} {rho}]\nShape \"sphere\" \"float radius\" 2\n\
         WorldEnd\n"
    )
}

fn stored_power(text: &str) -> f64 {
    let (description, _) = loads(text);
    let world = World::new(description).unwrap();
    let kind = MapKind::Global { with_direct: false };
    let (map, _) = trace_map(&world, kind, 40_000, 5, &ProgressBar::hidden());
    map.total_power().x as f64
}

#[test]
fn the_integrators_maxdepth_caps_the_bounces_photons_are_stored_after() {
    // A photon stored on its k-th surface has bounced k − 1 times, each keeping ρ of its
    // power: the global map (photons past a diffuse bounce) holds Φ Σ ρ^j for j from 1 to
    // maxdepth − 1 (pbrt's SPPM deposits at photon depths 1 to maxdepth − 1), and Φ ρ/(1 − ρ)
    // without a cap.
    let (phi, rho) = (4.0 * std::f64::consts::PI, 0.5f64);
    for (line, depths) in [
        ("Integrator \"path\" \"integer maxdepth\" 3", 2),
        ("Integrator \"sppm\" \"integer maxdepth\" 2", 1),
        ("Integrator \"bdpt\"", 4),
    ] {
        let want = phi * (1..=depths).map(|j| rho.powi(j)).sum::<f64>();
        let got = stored_power(&closed_room(line, rho as f32));
        assert!(
            (got / want - 1.0).abs() < 0.03,
            "{line}: {got} against {want}"
        );
    }
    let full = stored_power(&closed_room("", rho as f32));
    let want = phi * rho / (1.0 - rho);
    assert!((full / want - 1.0).abs() < 0.03, "{full} against {want}");
}

#[test]
fn direct_lighting_builds_no_photon_maps_and_full_transport_restores_them() {
    let dir = tempfile::tempdir().unwrap();
    // A ball beside the light: two diffuse objects, which dpm's own transport lights by a
    // global map.
    let text = closed_room("Integrator \"directlighting\"", 0.5).replace(
        "WorldEnd",
        "Translate 0.8 0 0\nShape \"sphere\" \"float radius\" 0.3\nWorldEnd",
    );
    let scene = write_scene(dir.path(), "room.pbrt", &text);
    let out = dir.path().join("room.pfm");
    let render = |extra: &[&str]| {
        let mut args = vec![path_str(&scene), "-o", path_str(&out), "--passes", "1"];
        args.extend_from_slice(extra);
        pipeline::run(&render_args(&args)).unwrap()
    };
    let direct = render(&[]);
    assert!(direct.global.is_none() && direct.caustic.is_none());
    let full = render(&["--full-transport"]);
    assert!(full.global.is_some_and(|g| g.stored > 0));
    let (description, report) = loads(&text);
    assert_eq!(description.transport, Transport::Direct { max_depth: 5 });
    assert!(
        report.notes.iter().any(|n| n.contains("directlighting")),
        "{:?}",
        report.notes
    );
}

#[test]
fn an_escaping_ray_sees_the_texel_pbrt_v3s_infinite_light_gives_under_two_rotations() {
    // pbrt-v3's InfiniteAreaLight::Le: w = WorldToLight(d), (s, t) = (φ/2π, θ/π) with
    // φ = atan2(w.y, w.x) in [0, 2π) and θ = acos w.z, texel (⌊s·W⌋, ⌊t·H⌋), row 0 at t = 0.
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (16usize, 8usize);
    let values: Vec<f32> = (0..w * h).map(|i| 1.0 + i as f32).collect();
    let mut pfm = format!("PF\n{w} {h}\n-1.0\n").into_bytes();
    for row in (0..h).rev() {
        for column in 0..w {
            for _ in 0..3 {
                pfm.extend_from_slice(&values[row * w + column].to_le_bytes());
            }
        }
    }
    std::fs::write(dir.path().join("sky.pfm"), pfm).unwrap();
    let text = "LookAt 0 0 0  0 0 -1  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
                AttributeBegin\nRotate 180 1 0 0\nRotate 90 0 1 0\n\
                LightSource \"infinite\" \"string mapname\" \"sky.pfm\"\nAttributeEnd\n\
                Shape \"sphere\" \"float radius\" 0.01\nWorldEnd\n";
    let (description, _) = support::pbrt::load_text(dir.path(), text).unwrap();
    let map: &EnvironmentMap = description
        .lights
        .iter()
        .find_map(|l| match l {
            Light::EnvironmentMap(m) => Some(m),
            _ => None,
        })
        .unwrap();
    let light_to_world =
        Mat3::from_axis_angle(Vec3::X, PI) * Mat3::from_axis_angle(Vec3::Y, PI / 2.0);
    let mut rng = dpm::sampling::Rng::for_index(3, dpm::sampling::Stream::Distribution, 0);
    for _ in 0..500 {
        let d = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        )
        .normalize();
        let l = light_to_world.transpose() * d;
        let phi = (l.y.atan2(l.x) + TAU) % TAU;
        let theta = l.z.clamp(-1.0, 1.0).acos();
        let (s, t) = (phi / TAU, theta / PI);
        // Directions within rounding of a texel edge may fall either way.
        let (fs, ft) = ((s * w as f32).fract(), (t * h as f32).fract());
        if fs.min(1.0 - fs) < 1e-3 || ft.min(1.0 - ft) < 1e-3 {
            continue;
        }
        let texel = (t * h as f32) as usize * w + (s * w as f32) as usize;
        assert_eq!(map.radiance(d).x, values[texel], "{d}");
    }
}

#[test]
fn a_floor_beside_where_a_sphere_stands_is_lit_however_large_the_floor() {
    // A unit sphere rests on a floor 8,000 wide; a distant light low from +x lights the floor
    // just beside the sphere's foot on the light's side, where nothing stands between them:
    // L = ρ/π · E cos θ. A ray offset relative to the whole floor's size would start those
    // shadow rays inside the sphere.
    let text = "LookAt 0 3 3  0 -1 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n\
                LightSource \"distant\" \"point from\" [5 1 0] \"point to\" [0 0 0] \"rgb L\" [2 2 2]\n\
                Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
                Shape \"trianglemesh\" \"point P\" [-4000 -1 -4000  4000 -1 -4000  4000 -1 4000  -4000 -1 4000]\n\
                \"integer indices\" [0 1 2  2 3 0]\nShape \"sphere\"\nWorldEnd\n";
    let (description, _) = loads(text);
    let world = World::new(description).unwrap();
    let cos = 1.0 / 26f64.sqrt();
    let want = 0.5 / std::f64::consts::PI * 2.0 * cos;
    for x in [0.2, 0.4, 0.7] {
        // Seen from just above the floor, beneath the sphere.
        let seen = radiance_along(
            &whitted(&world, 1),
            DVec3::new(x, -0.99, 0.5),
            DVec3::new(0.0, -0.01, -0.5).normalize(),
        );
        assert!(
            (seen.x / want - 1.0).abs() < 1e-3,
            "floor at x = {x}: {seen} against {want}"
        );
    }
}

#[test]
fn a_shading_normal_lying_in_its_face_still_reflects_that_sides_light() {
    // buddha-fractal's floor is the plane z = 0 with every "normal N" (0, 1, 0). pbrt reflects
    // the light of the geometric side the eye is on, weighed by |ωi · ns|: under a uniform sky
    // of radiance L that is ∫ over z > 0 of |ωy| dω = π, so a matte floor shows Kd·L, as it
    // would with its true normal (pbrt-v3 13d871f renders 0.7339 for Kd·L = 0.7339).
    let text = "LookAt 0 -5 3  0 0 0  0 0 1\nCamera \"perspective\"\nWorldBegin\n\
                LightSource \"infinite\" \"rgb L\" [1 1 1]\n\
                Material \"matte\" \"rgb Kd\" [0.5 0.5 0.5]\n\
                Shape \"trianglemesh\" \"point P\" [-9 -9 0  9 -9 0  9 9 0  -9 9 0]\n\
                \"integer indices\" [0 1 2  2 3 0] \"normal N\" [0 1 0  0 1 0  0 1 0  0 1 0]\n\
                WorldEnd\n";
    let (description, _) = loads(text);
    let world = World::new(description).unwrap();
    let integrator = dpm::render::integrator::Integrator {
        light_samples: 4096,
        ..whitted(&world, 1)
    };
    for (x, y) in [(0.0, 0.0), (1.0, -2.0)] {
        let seen = radiance_along(
            &integrator,
            DVec3::new(x, y - 1.0, 1.0),
            DVec3::new(0.0, 1.0, -1.0).normalize(),
        );
        assert!((seen.x / 0.5 - 1.0).abs() < 0.01, "({x}, {y}): {seen}");
    }
}

#[test]
fn a_point_light_behind_rough_glass_is_seen_through_it() {
    // pbrt samples a light through a rough dielectric from the far side; no sample of the
    // lobe can find a point light. Seen through a rough glass pane (α 0.3, the light below
    // it), the eye receives f(ωo, ωi) · I/d² · |cos θi| from one shadow ray.
    let text = "LookAt 0 3 0  0 0 0  0 0 1\nCamera \"perspective\"\nWorldBegin\n\
                LightSource \"point\" \"point from\" [0.3 -1 0.1] \"rgb I\" [2 2 2]\n\
                Material \"glass\" \"float index\" 1.5 \"float roughness\" 0.3 \
                \"bool remaproughness\" \"false\"\n\
                Shape \"trianglemesh\" \"point P\" [-2 0 -2  2 0 -2  2 0 2  -2 0 2]\n\
                \"integer indices\" [0 1 2  0 2 3]\nWorldEnd\n";
    let (description, _) = loads(text);
    let world = World::new(description).unwrap();
    let light = Vec3::new(0.3, -1.0, 0.1);
    let bsdf = dpm::bsdf::Bsdf::new(&dpm::bsdf::Model::Dielectric {
        eta: 1.5,
        alpha: glam::Vec2::splat(0.3),
        reflect_tint: Vec3::ONE,
        transmit_tint: Vec3::ONE,
    });
    for (x, z) in [(0.0f32, 0.0f32), (0.4, -0.3), (-0.5, 0.2)] {
        let (eye, at) = (Vec3::new(x, 1.0, z + 0.2), Vec3::new(x + 0.1, 0.0, z));
        let dir = (at - eye).normalize();
        let hit = world.intersect(eye, dir, 0.0, 10.0).unwrap();
        let frame = dpm::sampling::Frame::new(hit.shading_normal);
        let to_light = light - hit.position;
        let (wo, wi) = (frame.to_local(-dir), frame.to_local(to_light.normalize()));
        let want = bsdf.f(wo, wi, dpm::bsdf::Part::All).x as f64 * 2.0
            / to_light.length_squared() as f64
            * wi.z.abs() as f64;
        let seen = radiance_along(&whitted(&world, 1), eye.as_dvec3(), dir.as_dvec3());
        assert!(
            want > 0.0 && (seen.x / want - 1.0).abs() < 1e-3,
            "({x}, {z}): {seen} against {want}"
        );
    }
}
