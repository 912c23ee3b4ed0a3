//! The tessellations against the surfaces they stand for: closed-form areas, vertices and
//! centroids on the surface, the surface within the bound of the triangles, outward normals;
//! Loop subdivision's counts, closedness, masks and limit; the height field's grid.

use super::loop_subdivision::subdivide;
use super::quadrics::{Quadric, distance_to_triangle};
use super::{RELATIVE_ERROR_BOUND, heightfield};
use glam::{DVec3, Vec3};
use std::collections::HashSet;
use std::f64::consts::{PI, TAU};

fn mesh_area(positions: &[Vec3], triangles: &[[u32; 3]]) -> f64 {
    triangles
        .iter()
        .map(|&[a, b, c]| {
            let p = |i: u32| positions[i as usize].as_dvec3();
            0.5 * (p(b) - p(a)).cross(p(c) - p(a)).length()
        })
        .sum()
}

/// Quadrics of every kind, cut and whole, with the implicit function (value and gradient)
/// whose zero set holds each, and the way out at a point.
fn cases() -> Vec<(Quadric, &'static str)> {
    let p1 = DVec3::new(1.0, 0.0, -1.0);
    let p2 = DVec3::new(0.0, 1.5, 1.0);
    vec![
        (
            Quadric::Disk {
                height: 0.5,
                radius: 2.0,
                inner_radius: 0.0,
                phi_max: TAU,
            },
            "disk",
        ),
        (
            Quadric::Disk {
                height: -1.0,
                radius: 2.0,
                inner_radius: 0.7,
                phi_max: 1.5 * PI,
            },
            "annulus",
        ),
        (
            Quadric::Cylinder {
                radius: 0.5,
                z_min: -1.0,
                z_max: 3.0,
                phi_max: TAU,
            },
            "cylinder",
        ),
        (
            Quadric::Cylinder {
                radius: 3.0,
                z_min: 0.0,
                z_max: 0.1,
                phi_max: 0.5 * PI,
            },
            "cylinder cut",
        ),
        (
            Quadric::Cone {
                height: 2.0,
                radius: 1.0,
                phi_max: TAU,
            },
            "cone",
        ),
        (
            Quadric::Cone {
                height: -0.5,
                radius: 2.0,
                phi_max: PI,
            },
            "cone downwards",
        ),
        (
            Quadric::Paraboloid {
                radius: 1.0,
                z_min: 0.0,
                z_max: 2.0,
                phi_max: TAU,
            },
            "paraboloid",
        ),
        (
            Quadric::Paraboloid {
                radius: 2.0,
                z_min: 0.3,
                z_max: 0.5,
                phi_max: 1.2 * PI,
            },
            "paraboloid cut",
        ),
        (
            Quadric::Hyperboloid {
                p1,
                p2,
                phi_max: TAU,
            },
            "hyperboloid",
        ),
        (
            Quadric::Hyperboloid {
                p1: DVec3::ZERO,
                p2: DVec3::ONE,
                phi_max: TAU,
            },
            "hyperboloid from the axis",
        ),
        (
            Quadric::Sphere {
                radius: 1.5,
                z_min: -1.5,
                z_max: 1.5,
                phi_max: PI,
            },
            "half sphere",
        ),
        (
            Quadric::Sphere {
                radius: 1.0,
                z_min: -0.3,
                z_max: 0.9,
                phi_max: TAU,
            },
            "sphere band",
        ),
        (
            Quadric::Sphere {
                radius: 2.0,
                z_min: 0.0,
                z_max: 2.0,
                phi_max: TAU,
            },
            "hemisphere",
        ),
    ]
}

/// The signed implicit function of the quadric's whole surface, to first order a distance.
fn distance_to_surface(q: &Quadric, p: DVec3) -> f64 {
    let rho = p.truncate().length();
    match *q {
        Quadric::Disk {
            height,
            radius,
            inner_radius,
            ..
        } => {
            let outside = (rho - radius).max(inner_radius - rho).max(0.0);
            ((p.z - height).powi(2) + outside * outside).sqrt()
        }
        Quadric::Cylinder { radius, .. } => (rho - radius).abs(),
        Quadric::Cone { height, radius, .. } => {
            // The line from (radius, 0) to (0, height) in the meridian plane.
            let (a, b) = (glam::DVec2::new(radius, 0.0), glam::DVec2::new(0.0, height));
            let q = glam::DVec2::new(rho, p.z);
            let e = b - a;
            ((q - a).perp_dot(e) / e.length()).abs()
        }
        Quadric::Paraboloid { radius, z_max, .. } => {
            let k = z_max / (radius * radius);
            let f = p.z - k * rho * rho;
            f.abs() / DVec3::new(-2.0 * k * p.x, -2.0 * k * p.y, 1.0).length()
        }
        Quadric::Hyperboloid { p1, p2, .. } => {
            let t = (p.z - p1.z) / (p2.z - p1.z);
            let at = p1.truncate() + t * (p2 - p1).truncate();
            let d_rho2_dz = 2.0 * at.dot((p2 - p1).truncate()) / (p2.z - p1.z);
            let f = rho * rho - at.length_squared();
            let gradient = DVec3::new(2.0 * p.x, 2.0 * p.y, -d_rho2_dz).length();
            if gradient == 0.0 {
                f.abs()
            } else {
                f.abs() / gradient
            }
        }
        Quadric::Sphere { radius, .. } => (p.length() - radius).abs(),
    }
}

/// Whether `n` at `p` points the way pbrt's normal does: outward.
fn points_outward(q: &Quadric, p: DVec3, n: DVec3) -> bool {
    let radial = DVec3::new(p.x, p.y, 0.0);
    match *q {
        Quadric::Disk { .. } => n.z > 0.99,
        Quadric::Cylinder { .. } => n.dot(radial) > 0.0 && n.z.abs() < 1e-6,
        // pbrt's ∂p/∂u × ∂p/∂v: radially out and up for an upright cone, in and up for one
        // hanging down.
        Quadric::Cone { height, .. } => n.dot(radial) * height >= 0.0 && n.z > 0.0,
        Quadric::Paraboloid { .. } => n.z < 0.0 && n.dot(radial) >= 0.0,
        Quadric::Hyperboloid { .. } => n.dot(radial) >= -1e-9,
        Quadric::Sphere { .. } => n.dot(p) > 0.0,
    }
}

#[test]
fn quadric_areas_match_their_closed_forms_within_the_bound() {
    for (q, name) in cases() {
        let t = q.tessellate().unwrap();
        let (mesh, exact) = (mesh_area(&t.positions, &t.triangles), q.area());
        let relative = (mesh - exact).abs() / exact;
        assert!(
            relative <= 2.0 * RELATIVE_ERROR_BOUND,
            "{name}: area {mesh} against {exact} ({relative:e})"
        );
    }
    // The closed forms themselves, against the textbook values.
    let cylinder = Quadric::Cylinder {
        radius: 2.0,
        z_min: -1.0,
        z_max: 2.0,
        phi_max: TAU,
    };
    assert!((cylinder.area() - TAU * 2.0 * 3.0).abs() < 1e-12);
    let cone_like = Quadric::Hyperboloid {
        p1: DVec3::new(1.0, 0.0, 0.0),
        p2: DVec3::new(0.0, 0.0, 1.0),
        phi_max: TAU,
    };
    let cone = Quadric::Cone {
        height: 1.0,
        radius: 1.0,
        phi_max: TAU,
    };
    assert!((cone_like.area() - cone.area()).abs() < 1e-6 * cone.area());
}

#[test]
fn vertices_lie_on_the_surface_and_centroids_within_the_bound() {
    for (q, name) in cases() {
        let t = q.tessellate().unwrap();
        let bound = RELATIVE_ERROR_BOUND * q.radius();
        for p in &t.positions {
            let d = distance_to_surface(&q, p.as_dvec3());
            assert!(
                d <= 1e-6 * q.radius().max(1.0) * 4.0,
                "{name}: vertex {p} is {d} off"
            );
        }
        for tri in &t.triangles {
            let c = tri
                .iter()
                .map(|&i| t.positions[i as usize].as_dvec3())
                .sum::<DVec3>()
                / 3.0;
            let d = distance_to_surface(&q, c);
            assert!(
                d <= bound * 1.01,
                "{name}: centroid {c} is {d} off, bound {bound}"
            );
        }
    }
}

#[test]
fn the_surface_stays_within_the_bound_of_the_triangles() {
    // Points of the true surface, spread over every column (the grid is only measured on
    // its first): each lies within the bound of some triangle.
    for (q, name) in cases() {
        let t = q.tessellate().unwrap();
        let bound = RELATIVE_ERROR_BOUND * q.radius();
        let triangles: Vec<[DVec3; 3]> = t
            .triangles
            .iter()
            .map(|tri| tri.map(|i| t.positions[i as usize].as_dvec3()))
            .collect();
        let mut worst: f64 = 0.0;
        for k in 0..120 {
            let (s, v) = (
                (k as f64 * 0.618_034).fract(),
                (k as f64 * 0.754_877 + 0.01).fract(),
            );
            let p = sample(&q, s, v);
            let d = triangles
                .iter()
                .map(|tri| distance_to_triangle(p, *tri))
                .fold(f64::INFINITY, f64::min);
            worst = worst.max(d);
        }
        assert!(
            worst <= bound * 1.01,
            "{name}: surface {worst} from its triangles, bound {bound}"
        );
    }
}

/// A point of the quadric at (s, v) ∈ [0, 1]², from its definition rather than the grid.
fn sample(q: &Quadric, s: f64, v: f64) -> DVec3 {
    let turn = |phi: f64, p: DVec3| {
        DVec3::new(
            p.x * phi.cos() - p.y * phi.sin(),
            p.x * phi.sin() + p.y * phi.cos(),
            p.z,
        )
    };
    match *q {
        Quadric::Disk {
            height,
            radius,
            inner_radius,
            phi_max,
        } => turn(
            s * phi_max,
            DVec3::new(radius + v * (inner_radius - radius), 0.0, height),
        ),
        Quadric::Cylinder {
            radius,
            z_min,
            z_max,
            phi_max,
        } => turn(
            s * phi_max,
            DVec3::new(radius, 0.0, z_min + v * (z_max - z_min)),
        ),
        Quadric::Cone {
            height,
            radius,
            phi_max,
        } => turn(s * phi_max, DVec3::new(radius * (1.0 - v), 0.0, v * height)),
        Quadric::Paraboloid {
            radius,
            z_min,
            z_max,
            phi_max,
        } => {
            let z = z_min + v * (z_max - z_min);
            turn(s * phi_max, DVec3::new(radius * (z / z_max).sqrt(), 0.0, z))
        }
        Quadric::Hyperboloid { p1, p2, phi_max } => turn(s * phi_max, p1 + v * (p2 - p1)),
        Quadric::Sphere {
            radius,
            z_min,
            z_max,
            phi_max,
        } => {
            let z = z_min + v * (z_max - z_min);
            turn(
                s * phi_max,
                DVec3::new((radius * radius - z * z).max(0.0).sqrt(), 0.0, z),
            )
        }
    }
}

#[test]
fn normals_are_unit_and_point_outward() {
    for (q, name) in cases() {
        let t = q.tessellate().unwrap();
        let normals = t.normals.as_ref().unwrap();
        for (p, n) in t.positions.iter().zip(normals) {
            assert!((n.length() - 1.0).abs() < 1e-5, "{name}: normal {n}");
            assert!(
                points_outward(&q, p.as_dvec3(), n.as_dvec3()),
                "{name}: normal {n} at {p}"
            );
        }
    }
}

#[test]
fn tessellations_carry_pbrt_uv_and_no_zero_area_triangles() {
    for (q, name) in cases() {
        let t = q.tessellate().unwrap();
        assert_eq!(t.uv.len(), t.positions.len(), "{name}");
        assert!(
            t.uv.iter()
                .all(|&[u, v]| (0.0..=1.0).contains(&u) && (-1e-6..=1.0 + 1e-6).contains(&v)),
            "{name}"
        );
        assert!(mesh_area(&t.positions, &t.triangles) > 0.0);
        for &[a, b, c] in &t.triangles {
            assert!(a != b && b != c && a != c, "{name}");
            let p = |i: u32| t.positions[i as usize];
            assert!(
                (p(b) - p(a)).cross(p(c) - p(a)).length() > 0.0,
                "{name}: a zero-area triangle"
            );
        }
    }
}

#[test]
fn a_tighter_shape_takes_more_triangles_and_a_flat_one_few() {
    let disk = Quadric::Disk {
        height: 0.0,
        radius: 1.0,
        inner_radius: 0.0,
        phi_max: TAU,
    };
    let sphere = Quadric::Sphere {
        radius: 1.0,
        z_min: -1.0,
        z_max: 0.999,
        phi_max: TAU,
    };
    let (d, s) = (disk.tessellate().unwrap(), sphere.tessellate().unwrap());
    // A disk is only cut along its rim; a sphere in both directions.
    assert!(d.triangles.len() < 400, "{}", d.triangles.len());
    assert!(
        s.triangles.len() > 20 * d.triangles.len(),
        "{}",
        s.triangles.len()
    );
    assert!(s.triangles.len() < 100_000, "{}", s.triangles.len());
}

fn tetrahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![
        Vec3::new(1.0, 1.0, 1.0),
        Vec3::new(1.0, -1.0, -1.0),
        Vec3::new(-1.0, 1.0, -1.0),
        Vec3::new(-1.0, -1.0, 1.0),
    ];
    // Counter-clockwise seen from outside.
    (p, vec![[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]])
}

fn octahedron() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = vec![Vec3::X, Vec3::Y, -Vec3::X, -Vec3::Y, Vec3::Z, -Vec3::Z];
    let mut t = Vec::new();
    for k in 0..4u32 {
        let (a, b) = (k, (k + 1) % 4);
        t.push([a, b, 4]);
        t.push([b, a, 5]);
    }
    (p, t)
}

fn edges(triangles: &[[u32; 3]]) -> HashSet<(u32, u32)> {
    triangles
        .iter()
        .flat_map(|&[a, b, c]| [(a, b), (b, c), (c, a)])
        .collect()
}

#[test]
fn closed_meshes_stay_closed_with_the_euler_counts() {
    for (name, (p, t)) in [("tetrahedron", tetrahedron()), ("octahedron", octahedron())] {
        let (mut v, mut e, mut f) = (p.len(), edges(&t).len() / 2, t.len());
        for level in 0..=4 {
            let s = subdivide(&p, &t, level).unwrap();
            assert_eq!(
                (s.positions.len(), s.triangles.len()),
                (v, f),
                "{name} level {level}"
            );
            let directed = edges(&s.triangles);
            assert_eq!(
                directed.len(),
                3 * f,
                "{name}: an edge used twice the same way"
            );
            assert!(
                directed.iter().all(|&(a, b)| directed.contains(&(b, a))),
                "{name}: a hole"
            );
            assert_eq!(v + f - e, 2, "Euler");
            (v, e, f) = (v + e, 2 * e + 3 * f, 4 * f);
        }
    }
}

#[test]
fn limit_points_do_not_depend_on_the_level_and_normals_follow_pbrt() {
    // Every level's limit surface is the same surface, so the original vertices' limit
    // positions agree; a regular octahedron's converge towards a sphere-like surface.
    let (p, t) = octahedron();
    let limits: Vec<Vec<Vec3>> = (0..5)
        .map(|l| subdivide(&p, &t, l).unwrap().positions[..6].to_vec())
        .collect();
    for l in &limits[1..] {
        for (a, b) in l.iter().zip(&limits[0]) {
            assert!((*a - *b).length() < 1e-5, "{a} against {b}");
        }
    }
    let s = subdivide(&p, &t, 4).unwrap();
    let radii: Vec<f32> = s.positions.iter().map(|q| q.length()).collect();
    let (low, high) = radii
        .iter()
        .fold((f32::MAX, 0.0f32), |(l, h), &r| (l.min(r), h.max(r)));
    assert!(high / low < 1.25, "{low}..{high}");
    // pbrt's limit normals face away from the counter-clockwise side: inwards here.
    for (q, n) in s.positions.iter().zip(&s.normals) {
        assert!(n.dot(*q) < -0.9 * q.length(), "normal {n} at {q}");
    }
}

#[test]
fn a_flat_patch_stays_flat_and_boundaries_use_the_curve_masks() {
    // A 3 × 3 grid of points in z = 0, the middle of the bottom edge pulled up in y.
    let mut p: Vec<Vec3> = (0..9)
        .map(|k| Vec3::new((k % 3) as f32, (k / 3) as f32, 0.0))
        .collect();
    p[1].y = 0.3;
    let mut t = Vec::new();
    for (i, j) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
        let at = |i: u32, j: u32| i + 3 * j;
        t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
        t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
    }
    let limit = subdivide(&p, &t, 0).unwrap();
    // Boundary: 3/5 of the point and 1/5 of each boundary neighbour.
    assert!(
        (limit.positions[1] - Vec3::new(1.0, 0.18, 0.0)).length() < 1e-6,
        "{}",
        limit.positions[1]
    );
    let s = subdivide(&p, &t, 3).unwrap();
    assert_eq!(s.triangles.len(), t.len() * 64);
    assert!(s.positions.iter().all(|q| q.z == 0.0));
    assert!(
        s.normals.iter().all(|n| (n.z.abs() - 1.0).abs() < 1e-5),
        "planar normals"
    );
    // The faces run counter-clockwise seen from +z, so pbrt's normals point to -z.
    assert!(s.normals.iter().all(|n| n.z < 0.0));
}

#[test]
fn non_manifold_meshes_are_refused() {
    let p = vec![
        Vec3::ZERO,
        Vec3::X,
        Vec3::Y,
        Vec3::Z,
        -Vec3::Y,
        Vec3::ONE,
        -Vec3::X,
    ];
    let fin = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4]];
    assert!(
        subdivide(&p, &fin, 1)
            .unwrap_err()
            .contains("more than two triangles")
    );
    let flipped = vec![[0, 1, 2], [0, 1, 4]];
    assert!(
        subdivide(&p, &flipped, 1)
            .unwrap_err()
            .contains("wound the same way")
    );
    let bowtie = vec![[0, 1, 2], [0, 5, 6]];
    assert!(subdivide(&p, &bowtie, 1).unwrap_err().contains("one fan"));
    // Errors name the points as given, though unused ones are left out.
    let bowtie_late = vec![[3, 1, 2], [3, 5, 6]];
    assert!(
        subdivide(&p, &bowtie_late, 1)
            .unwrap_err()
            .contains("point 3,")
    );
    assert!(
        subdivide(&p, &[[0, 0, 1]], 1)
            .unwrap_err()
            .contains("repeats")
    );
    assert!(
        subdivide(&p, &[[0, 1, 2]], 40)
            .unwrap_err()
            .contains("more than")
    );
}

#[test]
fn a_heightfield_is_a_grid_over_the_unit_square() {
    let t = heightfield(4, 3, &[0.0; 12]);
    assert_eq!(t.triangles.len(), 2 * 3 * 2);
    assert!((mesh_area(&t.positions, &t.triangles) - 1.0).abs() < 1e-6);
    for &[a, b, c] in &t.triangles {
        let p = |i: u32| t.positions[i as usize];
        assert!(
            (p(b) - p(a)).cross(p(c) - p(a)).z > 0.0,
            "counter-clockwise from +z"
        );
    }
    let bumpy = heightfield(2, 2, &[0.0, 1.0, 2.0, 3.0]);
    assert_eq!(bumpy.positions[3], Vec3::new(1.0, 1.0, 3.0));
    assert_eq!(bumpy.uv[1], [1.0, 0.0]);
}
