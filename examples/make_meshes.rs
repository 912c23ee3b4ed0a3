//! Writes the meshes the scenes in scenes/ use, deterministically, into scenes/meshes/:
//! `torus-knot.obj` + `torus-knot.mtl` (the glass (2,3) torus knot of the paper's Figures 1
//! and 3) and `metal-ring.obj` (the ring of Figure 2, whose inner wall focuses light into a
//! nephroid). Run with `cargo run --example make_meshes`; the outputs are committed, so run it
//! again only after changing this file. Owns mesh generation only; it does not read scenes.

use glam::Vec3;
use std::f32::consts::TAU;
use std::fmt::Write as _;
use std::path::Path;

/// Knot winding numbers: `P` times around the symmetry axis, `Q` times through the hole.
const P: f32 = 2.0;
const Q: f32 = 3.0;
/// Samples along the knot, and around its tube.
const KNOT_SEGMENTS: usize = 600;
const TUBE_SEGMENTS: usize = 24;
/// Tube radius; the strands' centre lines pass no closer than 0.55 to each other.
const TUBE_RADIUS: f32 = 0.15;

const RING_SEGMENTS: usize = 720;
const RING_INNER_RADIUS: f32 = 1.0;
const RING_OUTER_RADIUS: f32 = 1.04;
const RING_HEIGHT: f32 = 1.0;

struct Mesh {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    triangles: Vec<[usize; 3]>,
}

fn main() -> std::io::Result<()> {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes");
    std::fs::create_dir_all(&folder)?;

    let knot = torus_knot();
    check_orientation(&knot, "torus knot");
    let header = "# Glass (2,3) torus knot for scenes/torus-knot.toml, written by \
                  `cargo run --example make_meshes`.\nmtllib torus-knot.mtl\no torus_knot\nusemtl glass\n";
    std::fs::write(folder.join("torus-knot.obj"), obj_text(header, &knot))?;
    std::fs::write(
        folder.join("torus-knot.mtl"),
        "# Written by `cargo run --example make_meshes`.\n\
         # illum 7 (refraction) with Ni: dpm reads this as glass with ior 1.5.\n\
         newmtl glass\nNi 1.5\nillum 7\n",
    )?;

    let ring = metal_ring();
    check_orientation(&ring, "metal ring");
    let header = "# Open ring (inner wall, outer wall, top rim) for scenes/metal-ring.toml, written by \
                  `cargo run --example make_meshes`.\no metal_ring\n";
    std::fs::write(folder.join("metal-ring.obj"), obj_text(header, &ring))?;

    for (name, mesh) in [("torus-knot.obj", &knot), ("metal-ring.obj", &ring)] {
        println!(
            "{name}: {} vertices, {} triangles",
            mesh.positions.len(),
            mesh.triangles.len()
        );
    }
    Ok(())
}

/// The knot's centre line, scaled so it reaches radius 1 from the z axis.
fn knot_curve(t: f32) -> Vec3 {
    let r = 2.0 + (Q * t).cos();
    Vec3::new(r * (P * t).cos(), r * (P * t).sin(), -(Q * t).sin()) / 3.0
}

fn knot_tangent(t: f32) -> Vec3 {
    let r = 2.0 + (Q * t).cos();
    let dr = -Q * (Q * t).sin();
    Vec3::new(
        dr * (P * t).cos() - r * P * (P * t).sin(),
        dr * (P * t).sin() + r * P * (P * t).cos(),
        -Q * (Q * t).cos(),
    )
    .normalize()
}

/// A tube around the knot. Its cross-sections follow rotation-minimising frames (double
/// reflection), with the leftover twist at the seam spread evenly so the tube closes without
/// a kink. Normals are exact: the tube is a canal surface.
fn torus_knot() -> Mesh {
    let n = KNOT_SEGMENTS;
    let centres: Vec<Vec3> = (0..=n)
        .map(|i| knot_curve(TAU * i as f32 / n as f32))
        .collect();
    let tangents: Vec<Vec3> = (0..=n)
        .map(|i| knot_tangent(TAU * i as f32 / n as f32))
        .collect();

    let mut frame_normals = vec![tangents[0].any_orthonormal_vector()];
    for i in 0..n {
        let step = centres[i + 1] - centres[i];
        let reflect = |v: Vec3, axis: Vec3| v - axis * (2.0 * axis.dot(v) / axis.dot(axis));
        let r_mid = reflect(frame_normals[i], step);
        let t_mid = reflect(tangents[i], step);
        let fix = tangents[i + 1] - t_mid;
        let r_next = if fix.length_squared() > 1e-12 {
            reflect(r_mid, fix)
        } else {
            r_mid
        };
        frame_normals.push(r_next.normalize());
    }
    // Twist from the transported end frame back to the start frame, about the tangent.
    let (end, start, axis) = (frame_normals[n], frame_normals[0], tangents[0]);
    let twist = end.cross(start).dot(axis).atan2(end.dot(start));

    let mut mesh = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        triangles: Vec::new(),
    };
    for i in 0..n {
        let angle = twist * i as f32 / n as f32;
        let (t, r) = (tangents[i], frame_normals[i]);
        let normal = r * angle.cos() + t.cross(r) * angle.sin();
        let binormal = t.cross(normal);
        for j in 0..TUBE_SEGMENTS {
            let theta = TAU * j as f32 / TUBE_SEGMENTS as f32;
            let outward = normal * theta.cos() + binormal * theta.sin();
            mesh.positions.push(centres[i] + outward * TUBE_RADIUS);
            mesh.normals.push(outward);
        }
    }
    let index = |i: usize, j: usize| (i % n) * TUBE_SEGMENTS + j % TUBE_SEGMENTS;
    for i in 0..n {
        for j in 0..TUBE_SEGMENTS {
            // First around the tube, then along it: counter-clockwise seen from outside.
            mesh.triangles
                .push([index(i, j), index(i, j + 1), index(i + 1, j)]);
            mesh.triangles
                .push([index(i, j + 1), index(i + 1, j + 1), index(i + 1, j)]);
        }
    }
    mesh
}

/// An open thick ring standing on y = 0 around the y axis: inner wall (normals toward the
/// axis), outer wall, flat top rim. The bottom is left open; it rests on the floor.
fn metal_ring() -> Mesh {
    let mut mesh = Mesh {
        positions: Vec::new(),
        normals: Vec::new(),
        triangles: Vec::new(),
    };
    let around = |k: usize| {
        let a = TAU * (k % RING_SEGMENTS) as f32 / RING_SEGMENTS as f32;
        Vec3::new(a.cos(), 0.0, a.sin())
    };
    let up = Vec3::Y * RING_HEIGHT;
    let (inner, outer) = (RING_INNER_RADIUS, RING_OUTER_RADIUS);
    add_band(&mut mesh, |k| {
        (around(k) * inner, around(k) * inner + up, -around(k))
    });
    add_band(&mut mesh, |k| {
        (around(k) * outer, around(k) * outer + up, around(k))
    });
    add_band(&mut mesh, |k| {
        (around(k) * inner + up, around(k) * outer + up, Vec3::Y)
    });
    mesh
}

/// A closed band of quads between two loops of vertices; `loops(k)` gives the k-th vertex of
/// each loop and their shared normal. Each band has its own vertices, so the sharp edges
/// between walls and rim keep their own normals.
fn add_band(mesh: &mut Mesh, loops: impl Fn(usize) -> (Vec3, Vec3, Vec3)) {
    let first = mesh.positions.len();
    for k in 0..RING_SEGMENTS {
        let (a, b, normal) = loops(k);
        mesh.positions.extend([a, b]);
        mesh.normals.extend([normal, normal]);
    }
    let vertex = |k: usize, side: usize| first + 2 * (k % RING_SEGMENTS) + side;
    for k in 0..RING_SEGMENTS {
        let quad = [
            vertex(k, 0),
            vertex(k + 1, 0),
            vertex(k + 1, 1),
            vertex(k, 1),
        ];
        for triangle in [[quad[0], quad[1], quad[2]], [quad[0], quad[2], quad[3]]] {
            let triangle = facing_its_normals(mesh, triangle);
            mesh.triangles.push(triangle);
        }
    }
}

/// Reverses `triangle` if its winding disagrees with its vertex normals.
fn facing_its_normals(mesh: &Mesh, [a, b, c]: [usize; 3]) -> [usize; 3] {
    let p = &mesh.positions;
    let face = (p[b] - p[a]).cross(p[c] - p[a]);
    if face.dot(mesh.normals[a] + mesh.normals[b] + mesh.normals[c]) >= 0.0 {
        [a, b, c]
    } else {
        [a, c, b]
    }
}

/// Every triangle has area and agrees with its vertex normals; every normal is unit.
fn check_orientation(mesh: &Mesh, name: &str) {
    for &[a, b, c] in &mesh.triangles {
        let p = &mesh.positions;
        let face = (p[b] - p[a]).cross(p[c] - p[a]);
        assert!(
            face.length() > 1e-9,
            "{name}: zero-area triangle {a} {b} {c}"
        );
        for v in [a, b, c] {
            assert!(
                (mesh.normals[v].length() - 1.0).abs() < 1e-4,
                "{name}: normal {v} not unit"
            );
            assert!(
                face.dot(mesh.normals[v]) > 0.0,
                "{name}: triangle {a} {b} {c} faces inward"
            );
        }
    }
}

fn obj_text(header: &str, mesh: &Mesh) -> String {
    let mut text = String::from(header);
    for p in &mesh.positions {
        writeln!(text, "v {} {} {}", number(p.x), number(p.y), number(p.z)).unwrap();
    }
    for n in &mesh.normals {
        writeln!(text, "vn {} {} {}", number(n.x), number(n.y), number(n.z)).unwrap();
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(text, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
    }
    text
}

/// Six decimals, with no "-0.000000" (which would differ between platforms' rounding).
fn number(x: f32) -> String {
    let text = format!("{x:.6}");
    if text
        .trim_start_matches('-')
        .bytes()
        .all(|b| b == b'0' || b == b'.')
    {
        "0.000000".to_string()
    } else {
        text
    }
}
