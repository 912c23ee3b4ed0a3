//! The lights' sampling checked against itself and against closed forms: photons and
//! shadow-ray samples agree on irradiance for every kind of light, aiming keeps the flux into
//! each target, unaimed photons carry the light's power, and a mesh light's radiance is
//! Φ / (π A).

use super::area::light_to_target_cone;
use super::*;
use crate::sampling::{Stream, uniform_sphere};
use crate::scene::{EnvironmentMap, SphereMapping, SpotFalloff, TriangleMesh};
use std::f32::consts::PI;

/// Where the test lights are: every light and target lies well inside it.
const SCENE: BoundingSphere = BoundingSphere {
    center: Vec3::ZERO,
    radius: 3.0,
};

/// A 1 × 1 square at z = 2, facing down (or up), of two triangles.
fn square_mesh(facing_down: bool) -> TriangleMesh {
    let triangles = if facing_down {
        vec![[0, 1, 2], [0, 2, 3]]
    } else {
        vec![[0, 2, 1], [0, 3, 2]]
    };
    TriangleMesh {
        positions: vec![
            Vec3::new(-0.5, -0.5, 2.0),
            Vec3::new(-0.5, 0.5, 2.0),
            Vec3::new(0.5, 0.5, 2.0),
            Vec3::new(0.5, -0.5, 2.0),
        ],
        normals: None,
        uvs: None,
        triangles,
        material: 0,
        cutout: None,
    }
}

fn lights() -> Vec<Light> {
    vec![
        Light::Point {
            position: Vec3::new(0.0, 0.0, 2.0),
            power: Vec3::new(4.0, 2.0, 1.0),
        },
        Light::Sphere {
            center: Vec3::new(0.3, 0.0, 2.0),
            radius: 0.25,
            power: Vec3::splat(3.0),
        },
        Light::Quad {
            corner: Vec3::new(-0.5, -0.5, 2.0),
            edge_u: Vec3::new(0.0, 1.0, 0.0),
            edge_v: Vec3::new(1.0, 0.0, 0.0),
            power: Vec3::splat(5.0),
        },
        Light::Spot {
            position: Vec3::new(0.0, 0.0, 2.0),
            direction: Vec3::new(0.1, 0.0, -1.0).normalize(),
            cone_angle_degrees: 50.0,
            falloff_start_degrees: 30.0,
            falloff: SpotFalloff::Smoothstep,
            power: Vec3::new(6.0, 3.0, 2.0),
        },
        Light::Mesh {
            mesh: square_mesh(true),
            power: Vec3::splat(5.0),
            two_sided: false,
        },
        Light::Mesh {
            mesh: square_mesh(false),
            power: Vec3::splat(10.0),
            two_sided: true,
        },
        Light::Distant {
            direction: Vec3::new(0.3, 0.1, -1.0).normalize(),
            irradiance: Vec3::new(2.0, 1.0, 0.5),
        },
        Light::Environment {
            radiance: Vec3::new(0.5, 0.25, 1.0),
        },
        Light::EnvironmentMap(test_map(16, 8, SphereMapping::LatLong)),
        Light::EnvironmentMap(test_map(8, 8, SphereMapping::EqualAreaOctahedral)),
    ]
}

/// A coloured, uneven sky with one texel 200 times the others, turned off the axes.
fn test_map(width: u32, height: u32, mapping: SphereMapping) -> EnvironmentMap {
    let turn = glam::Mat3::from_rotation_x(-1.2) * glam::Mat3::from_rotation_z(0.4);
    EnvironmentMap::from_fn(width, height, mapping, turn, |i| {
        let (column, row) = (i % width, i / width);
        let level = if i == width * height / 3 { 200.0 } else { 1.0 };
        let colour = Vec3::new(
            0.1 + 0.05 * row as f32,
            0.2,
            0.1 + 0.03 * (column % 5) as f32,
        );
        level * colour
    })
}

fn at_infinity(light: &Light) -> bool {
    matches!(
        light,
        Light::Distant { .. } | Light::Environment { .. } | Light::EnvironmentMap(_)
    )
}

fn source(light: &Light) -> LightSource {
    LightSource::new(light, SCENE)
}

/// Irradiance at the origin on a +z surface: photon flux through a small disc vs sampling.
#[test]
fn emission_and_incident_sampling_agree_on_irradiance() {
    for light in lights() {
        let n = 400_000;
        let mut direct = Vec3::ZERO;
        let source = source(&light);
        for i in 0..n {
            let mut rng = Rng::for_index(1, Stream::Pixels, i);
            if let Some(s) = source.sample_incident(Vec3::ZERO, Vec3::Z, rng.next_2d()) {
                direct += s.irradiance * s.direction.z.max(0.0);
            }
        }
        direct /= n as f32;
        // Flux through the disc of radius 0.2 at z = 0 from photons (plane z = 0 facing +z);
        // 1 for the lights at infinity, whose irradiance is the same everywhere.
        let r = if at_infinity(&light) { 1.0 } else { 0.2f32 };
        let mut flux = Vec3::ZERO;
        let m = 2_000_000;
        let emitter = LightEmitter::new(&source, &[]);
        for i in 0..m {
            let mut rng = Rng::for_index(2, Stream::CausticPhotons, i);
            let e = emitter.emit(&mut rng);
            if e.direction.z < 0.0 {
                let t = -e.origin.z / e.direction.z;
                let p = e.origin + t * e.direction;
                if p.truncate().length() < r {
                    flux += e.flux;
                }
            }
        }
        let photon_e = flux / (m as f32 * PI * r * r);
        let rel = (photon_e - direct).abs().max_element() / direct.max_element();
        assert!(
            rel < 0.03,
            "{light:?}: photons {photon_e} vs sampling {direct}"
        );
    }
}

/// Aiming photons at spheres keeps the flux that reaches each of them unbiased, for one
/// target and for two (the second apart from the first, as the Cornell box's are).
#[test]
fn aimed_emission_preserves_the_flux_into_the_targets() {
    let sphere = |x: f32, y: f32, z: f32, radius: f32| BoundingSphere {
        center: Vec3::new(x, y, z),
        radius,
    };
    // Far from the lights (a sphere light's cone has sin θ = 0.27), near them (0.79), and
    // a far target with a second one off to the side.
    let aims = [
        vec![sphere(0.0, 0.0, 0.0, 0.3)],
        vec![sphere(0.0, 0.2, 1.4, 0.3)],
        vec![sphere(0.0, 0.0, 0.0, 0.3), sphere(1.2, 0.3, 0.4, 0.25)],
    ];
    for light in lights() {
        for aim in &aims {
            // Flux per photon into each target, along rays that enter it.
            let into = |aim: &[BoundingSphere], seed: u64| {
                let m = 1_000_000;
                let mut flux = vec![Vec3::ZERO; aim.len()];
                let emitter = LightEmitter::new(&source(&light), aim);
                for i in 0..m {
                    let mut rng = Rng::for_index(seed, Stream::CausticPhotons, i);
                    let e = emitter.emit(&mut rng);
                    for (target, flux) in aim.iter().zip(&mut flux) {
                        let oc = e.origin - target.center;
                        let b = oc.dot(e.direction);
                        let c = oc.length_squared() - target.radius * target.radius;
                        if b < 0.0 && b * b - c > 0.0 {
                            *flux += e.flux / m as f32;
                        }
                    }
                }
                flux
            };
            let aimed = into(aim, 3);
            // Unaimed photons, counted against the same targets.
            let plain = {
                let mut flux = vec![Vec3::ZERO; aim.len()];
                let emitter = LightEmitter::new(&source(&light), &[]);
                // Few unaimed photons from the sky meet a target: more of them.
                let m = if at_infinity(&light) {
                    4_000_000
                } else {
                    1_000_000
                };
                for (k, target) in aim.iter().enumerate() {
                    for i in 0..m {
                        let mut rng = Rng::for_index(4, Stream::CausticPhotons, i);
                        let e = emitter.emit(&mut rng);
                        let oc = e.origin - target.center;
                        let b = oc.dot(e.direction);
                        let c = oc.length_squared() - target.radius * target.radius;
                        if b < 0.0 && b * b - c > 0.0 {
                            flux[k] += e.flux / m as f32;
                        }
                    }
                }
                flux
            };
            for (aimed, plain) in aimed.iter().zip(&plain) {
                let rel = (*aimed - *plain).abs().max_element() / plain.max_element();
                assert!(
                    rel < 0.03,
                    "{light:?}, {} targets: aimed {aimed} vs plain {plain}",
                    aim.len()
                );
            }
        }
    }
}

/// Every segment from a sphere light to the aimed sphere lies in the cone that aimed sphere
/// lights draw their directions from.
#[test]
fn the_cone_from_a_sphere_light_holds_every_segment_to_the_aim() {
    let (center, radius) = (Vec3::new(0.3, -0.2, 2.0), 0.25);
    let mut rng = Rng::for_index(9, Stream::CausticPhotons, 0);
    let mut tested = 0;
    for k in 0..200 {
        let aim = BoundingSphere {
            center: uniform_sphere(rng.next_2d()) * (0.3 + 0.02 * k as f32),
            radius: 0.05 + 0.002 * k as f32,
        };
        let Some((axis, cos_max)) = light_to_target_cone(&aim, center, radius) else {
            assert!(radius + aim.radius >= (aim.center - center).length());
            continue;
        };
        for _ in 0..500 {
            // Points on both surfaces, where the segments lean furthest from the axis.
            let x = center + radius * uniform_sphere(rng.next_2d());
            let y = aim.center + aim.radius * uniform_sphere(rng.next_2d());
            let d = (y - x).normalize();
            assert!(d.dot(axis) >= cos_max - 1e-5, "{x} -> {y} leaves the cone");
            tested += 1;
        }
    }
    assert!(tested > 50_000, "only {tested} segments tested");
}

/// Aimed photons of a sphere light leave from its surface, outwards, and carry equal flux.
#[test]
fn aimed_sphere_light_photons_leave_its_surface_outwards() {
    let light = lights()[1].clone();
    let Light::Sphere { center, radius, .. } = light else {
        unreachable!()
    };
    let aim = [BoundingSphere {
        center: Vec3::ZERO,
        radius: 0.3,
    }];
    let mut flux = None;
    let emitter = LightEmitter::new(&source(&light), &aim);
    for i in 0..10_000 {
        let mut rng = Rng::for_index(5, Stream::CausticPhotons, i);
        let e = emitter.emit(&mut rng);
        let n = (e.origin - center) / radius;
        assert!((n.length() - 1.0).abs() < 1e-5, "origin off the sphere");
        assert!(e.direction.dot(n) >= -1e-6, "leaves inwards");
        assert_eq!(*flux.get_or_insert(e.flux), e.flux);
    }
}

/// Unaimed, every photon of every light carries the light's whole power (so a map of N paths
/// holds Φ, whatever the light; an image environment's photons by their mean channel, which
/// its texels are drawn by), and the powers of the lights at infinity are what crosses the
/// scene's disc: E·πR², L·4π·πR² and ∫L dω·πR².
#[test]
fn unaimed_photons_carry_the_light_power() {
    for light in lights() {
        let source = source(&light);
        let emitter = LightEmitter::new(&source, &[]);
        let power = source.power();
        for i in 0..10_000 {
            let mut rng = Rng::for_index(6, Stream::GlobalPhotons, i);
            let e = emitter.emit(&mut rng);
            let rel = if let Light::EnvironmentMap(_) = light {
                (e.flux.element_sum() - power.element_sum()).abs() / power.element_sum()
            } else {
                (e.flux - power).abs().max_element() / power.max_element()
            };
            assert!(rel < 1e-5, "{light:?}: {} vs {power}", e.flux);
            assert!((e.direction.length() - 1.0).abs() < 1e-4);
            if at_infinity(&light) {
                assert!(e.origin.length() > SCENE.radius, "starts inside the scene");
            }
        }
    }
    let r2 = SCENE.radius * SCENE.radius;
    let distant = Light::Distant {
        direction: Vec3::NEG_Z,
        irradiance: Vec3::new(2.0, 1.0, 0.5),
    };
    assert_eq!(source(&distant).power(), Vec3::new(2.0, 1.0, 0.5) * PI * r2);
    let environment = Light::Environment {
        radiance: Vec3::ONE,
    };
    let want = 4.0 * PI * PI * r2;
    assert!((source(&environment).power().x - want).abs() < 1e-4 * want);
}

/// A mesh light's radiance is Φ / (π A) on its emitting side and nothing behind; two-sided it
/// is Φ / (2π A) on both sides.
#[test]
fn mesh_light_radiance_is_power_over_pi_area() {
    let one_sided = source(&Light::Mesh {
        mesh: square_mesh(true),
        power: Vec3::new(3.0, 2.0, 1.0),
        two_sided: false,
    });
    assert_eq!(
        one_sided.emitted_radiance(0.5),
        Vec3::new(3.0, 2.0, 1.0) / PI
    );
    assert_eq!(one_sided.emitted_radiance(-0.5), Vec3::ZERO);
    let two_sided = source(&Light::Mesh {
        mesh: square_mesh(true),
        power: Vec3::new(3.0, 2.0, 1.0),
        two_sided: true,
    });
    let half = Vec3::new(3.0, 2.0, 1.0) / (2.0 * PI);
    assert_eq!(two_sided.emitted_radiance(0.5), half);
    assert_eq!(two_sided.emitted_radiance(-0.5), half);
    assert!(!one_sided.is_delta());
}

/// Mesh points are drawn by area: two triangles of areas 1 and 3 get a quarter and three
/// quarters of the samples, and a stratified sequence stays inside the mesh.
#[test]
fn mesh_points_are_drawn_by_area() {
    let mesh = TriangleMesh {
        positions: vec![
            Vec3::ZERO,
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(13.0, 0.0, 0.0),
            Vec3::new(10.0, 2.0, 0.0),
        ],
        normals: None,
        uvs: None,
        triangles: vec![[0, 1, 2], [3, 4, 5]],
        material: 0,
        cutout: None,
    };
    let light = source(&Light::Mesh {
        mesh,
        power: Vec3::ONE,
        two_sided: true,
    });
    let n = 100_000;
    let mut in_second = 0;
    let mut rng = Rng::for_index(8, Stream::Pixels, 0);
    for _ in 0..n {
        let s = light
            .sample_incident(Vec3::new(5.0, 0.5, 4.0), Vec3::NEG_Z, rng.next_2d())
            .expect("two-sided: always lit");
        let p = Vec3::new(5.0, 0.5, 4.0) + s.direction * s.distance;
        assert!(p.z.abs() < 1e-4);
        if p.x >= 10.0 {
            in_second += 1;
            assert!(p.y <= 2.0 * (1.0 - (p.x - 10.0) / 3.0) + 1e-4);
        } else {
            assert!(p.y <= 1.0 - p.x / 2.0 + 1e-4);
        }
    }
    let share = in_second as f64 / n as f64;
    assert!((share - 0.75).abs() < 0.01, "{share}");
}

/// The environment sampled by cosine-weighted shadow rays gives irradiance π L with every
/// sample (no noise on an open surface), and an escaping ray sees L.
#[test]
fn environment_samples_give_pi_radiance() {
    let light = source(&Light::Environment {
        radiance: Vec3::new(0.5, 0.25, 1.0),
    });
    let n = Vec3::new(0.2, 0.9, -0.1).normalize();
    let mut rng = Rng::for_index(9, Stream::Pixels, 0);
    for _ in 0..1000 {
        let s = light.sample_incident(Vec3::ONE, n, rng.next_2d()).unwrap();
        let e = s.irradiance * s.direction.dot(n);
        assert!((e - PI * Vec3::new(0.5, 0.25, 1.0)).abs().max_element() < 1e-5 * PI);
        assert_eq!(s.distance, f32::INFINITY);
    }
    assert_eq!(light.radiance_at_infinity(), Vec3::new(0.5, 0.25, 1.0));
    assert_eq!(light.emitted_radiance(1.0), Vec3::ZERO);
}

/// A uniform sky seen by a receiver whose shading normal lies in its face (x, on the plane
/// z = 0): ∫ over z > 0 of |ωx| dω is π, so the weighted mean is π L. The wide samples bring
/// at most 4π L each; the cosine's alone, near the horizon, far more.
#[test]
fn a_sky_sampled_wide_keeps_its_expectation_and_bounds_every_weight() {
    let radiance = Vec3::new(0.5, 1.0, 2.0);
    let source = source(&Light::Environment { radiance });
    let (n, ns) = (Vec3::Z, Vec3::X);
    let (samples, mut sum, mut widest, mut narrow_widest) = (400_000, Vec3::ZERO, 0.0f32, 0.0f32);
    for i in 0..samples {
        let mut rng = Rng::for_index(4, Stream::Pixels, i);
        let u = rng.next_2d();
        if let Some(s) = source.sample_incident_wide(Vec3::ZERO, n, u) {
            sum += s.irradiance * s.direction.dot(ns).abs();
            widest = widest.max(s.irradiance.y * s.direction.dot(ns).abs());
        }
        if let Some(s) = source.sample_incident(Vec3::ZERO, n, u) {
            narrow_widest = narrow_widest.max(s.irradiance.y * s.direction.dot(ns).abs());
        }
    }
    let mean = sum / samples as f32;
    for (got, l) in mean.to_array().into_iter().zip(radiance.to_array()) {
        assert!((got / (PI * l) - 1.0).abs() < 0.01, "{mean}");
    }
    assert!(widest <= 4.0 * PI * 1.0001, "{widest}");
    assert!(narrow_widest > 100.0 * PI, "{narrow_widest}");
}

#[test]
fn a_mesh_lights_triangles_drawn_one_by_one_sum_to_the_whole_light() {
    let light = source(&Light::Mesh {
        mesh: square_mesh(true),
        power: Vec3::splat(5.0),
        two_sided: false,
    });
    assert!(light.drawn_by_triangle());
    assert_eq!(light.tree_entries().len(), 2);
    let (x, n) = (Vec3::new(0.2, -0.1, 0.0), Vec3::Z);
    let count = 64u32;
    let irradiance = |part: Option<u32>| {
        let mut sum = 0.0f64;
        for i in 0..count * count {
            let u = (
                ((i % count) as f32 + 0.5) / count as f32,
                ((i / count) as f32 + 0.5) / count as f32,
            );
            let s = light.sample_incident_part(x, n, u, part).unwrap();
            let back = light.incident_pdf_part(x, n, (s.direction, s.distance), Vec3::NEG_Z, part);
            assert!(
                (back / s.pdf - 1.0).abs() < 1e-3,
                "pdf {} against {back}",
                s.pdf
            );
            sum += f64::from(s.irradiance.x * n.dot(s.direction));
        }
        sum / f64::from(count * count)
    };
    let whole = irradiance(None);
    let parts = irradiance(Some(0)) + irradiance(Some(1));
    assert!(
        (parts / whole - 1.0).abs() < 2e-3,
        "{parts} against {whole}"
    );
    // Past the limit a mesh is one entry of the tree, drawn by area.
    let many = TREE_TRIANGLES_MAX as u32 + 1;
    let big = TriangleMesh {
        positions: (0..many + 2)
            .map(|i| Vec3::new(i as f32 * 1e-3, (i % 2) as f32 * 1e-3, 2.0))
            .collect(),
        triangles: (0..many).map(|i| [i, i + 1, i + 2]).collect(),
        ..square_mesh(true)
    };
    let light = source(&Light::Mesh {
        mesh: big,
        power: Vec3::splat(5.0),
        two_sided: true,
    });
    assert!(!light.drawn_by_triangle());
    assert_eq!(light.tree_entries().len(), 1);
}
