//! Loop subdivision of a manifold triangle mesh, as pbrt's `loopsubdiv` defines it: each
//! level splits every triangle in four, moving the old vertices by Loop's one-ring weights
//! (β = 3/16 at valence 3, 3/(8n) otherwise) and placing the new ones by the 3/8–1/8 edge
//! rule; boundary vertices and edges follow the 1-D boundary masks (3/4–1/8 and the
//! midpoint). After the last level every vertex moves to its limit position and gets the
//! limit surface's normal from its one-ring's tangents. Owns the subdivision; refuses
//! non-manifold input with a message, and must not know where the mesh came from.
//!
//! The normals follow pbrt's tangents: pbrt walks an inner vertex's ring clockwise (seen from
//! the side the counter-clockwise faces face), so its limit normal S × T points away from
//! that side, and a mesh given counter-clockwise seen from outside gets inward normals.
//! dpm keeps pbrt's normals, so a scene faces the way it does in pbrt.

use glam::{DVec3, Vec3};
use std::collections::HashMap;

/// More triangles than this after subdivision would not fit in memory sensibly.
pub(crate) const MAX_TRIANGLES: usize = 1 << 22;

/// A mesh during subdivision: positions and counter-clockwise triangles.
struct Level {
    positions: Vec<DVec3>,
    triangles: Vec<[u32; 3]>,
}

/// What each vertex's neighbourhood looks like, in pbrt's ring order.
struct Rings {
    /// Interior: the one-ring clockwise; boundary: from the neighbour across the boundary
    /// edge the vertex starts to the one across the edge it ends.
    ring: Vec<Vec<u32>>,
    boundary: Vec<bool>,
    /// The third corner of the triangle holding the directed edge (a, b).
    third: HashMap<(u32, u32), u32>,
}

/// The subdivided mesh: limit positions, limit normals (unit), triangles.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Subdivided {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
}

/// Subdivides `levels` times. Indices must lie within `positions` (the caller checks);
/// vertices no triangle uses are left out. Fails, saying why, on a triangle that repeats a
/// corner, an edge shared by more than two triangles or by two wound the same way, or a
/// vertex where two fans of triangles meet at a point.
pub(crate) fn subdivide(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    levels: u32,
) -> Result<Subdivided, String> {
    if triangles.is_empty() {
        return Err("has no triangles".into());
    }
    let final_count = (triangles.len() as u128) << (2 * levels.min(60));
    if final_count > MAX_TRIANGLES as u128 {
        return Err(format!(
            "{} triangles subdivided {levels} times would be {final_count}, more than {MAX_TRIANGLES}",
            triangles.len()
        ));
    }
    let (mut mesh, original) = compact(positions, triangles);
    // Subdividing a manifold gives a manifold: only the given mesh can fail.
    let mut rings = Rings::of(&mesh, &original)?;
    for _ in 0..levels {
        mesh = refine(&mesh, &rings);
        let identity: Vec<u32> = (0..mesh.positions.len() as u32).collect();
        rings = Rings::of(&mesh, &identity)?;
    }
    let limit: Vec<DVec3> = (0..mesh.positions.len())
        .map(|v| limit_position(&mesh.positions, &rings, v))
        .collect();
    let normals = (0..limit.len())
        .map(|v| limit_normal(&limit, &rings, v, &mesh.triangles))
        .collect();
    Ok(Subdivided {
        positions: limit.iter().map(|p| p.as_vec3()).collect(),
        normals,
        triangles: mesh.triangles,
    })
}

/// The used vertices only, renumbered in order of first use, and each one's index in
/// `positions`.
fn compact(positions: &[Vec3], triangles: &[[u32; 3]]) -> (Level, Vec<u32>) {
    let mut new_index = vec![u32::MAX; positions.len()];
    let mut original = Vec::new();
    let mut level = Level {
        positions: Vec::new(),
        triangles: Vec::with_capacity(triangles.len()),
    };
    for t in triangles {
        level.triangles.push(t.map(|i| {
            if new_index[i as usize] == u32::MAX {
                new_index[i as usize] = level.positions.len() as u32;
                level.positions.push(positions[i as usize].as_dvec3());
                original.push(i);
            }
            new_index[i as usize]
        }));
    }
    (level, original)
}

impl Rings {
    /// The rings of `mesh`, or why it is not a manifold; errors name point v as `names[v]`.
    fn of(mesh: &Level, names: &[u32]) -> Result<Rings, String> {
        let name = |v: u32| names[v as usize];
        let n = mesh.positions.len();
        let mut third = HashMap::with_capacity(3 * mesh.triangles.len());
        let mut faces_at = vec![0usize; n];
        let mut start = vec![u32::MAX; n];
        for (k, &[a, b, c]) in mesh.triangles.iter().enumerate() {
            if a == b || b == c || c == a {
                return Err(format!("triangle {k} repeats a corner"));
            }
            for (from, to, other) in [(a, b, c), (b, c, a), (c, a, b)] {
                if third.insert((from, to), other).is_some() {
                    return Err(format!(
                        "is not a manifold: the edge between points {} and {} is shared by more than two triangles or by two wound the same way (triangle {k})",
                        name(from),
                        name(to)
                    ));
                }
                faces_at[from as usize] += 1;
                start[from as usize] = to;
            }
        }
        let mut ring = Vec::with_capacity(n);
        let mut boundary = Vec::with_capacity(n);
        for v in 0..n as u32 {
            // A boundary vertex starts its ring at the neighbour whose edge has no triangle
            // on the far side.
            let mut first = start[v as usize];
            let mut steps = 0;
            while let Some(&back) = third.get(&(first, v)) {
                first = back;
                steps += 1;
                if first == start[v as usize] || steps > faces_at[v as usize] {
                    break;
                }
            }
            let is_boundary = !third.contains_key(&(first, v));
            let mut r = vec![first];
            if is_boundary {
                // Counter-clockwise from `first`, as pbrt orders a boundary ring.
                let mut x = first;
                while let Some(&next) = third.get(&(v, x)) {
                    r.push(next);
                    x = next;
                    if r.len() > faces_at[v as usize] + 1 {
                        break;
                    }
                }
            } else {
                // Clockwise, as pbrt orders an interior ring.
                let mut x = first;
                while let Some(&next) = third.get(&(x, v)) {
                    if next == first || r.len() > faces_at[v as usize] {
                        break;
                    }
                    r.push(next);
                    x = next;
                }
            }
            let fan = if is_boundary { r.len() - 1 } else { r.len() };
            if fan != faces_at[v as usize] {
                return Err(format!(
                    "is not a manifold: {} triangles meet at point {}, but only {fan} of them form one fan around it",
                    faces_at[v as usize],
                    name(v)
                ));
            }
            ring.push(r);
            boundary.push(is_boundary);
        }
        Ok(Rings {
            ring,
            boundary,
            third,
        })
    }

    /// The ends of a boundary vertex's ring: its two neighbours along the boundary.
    fn boundary_neighbours(&self, v: usize) -> (u32, u32) {
        let r = &self.ring[v];
        (r[0], r[r.len() - 1])
    }
}

fn beta(valence: usize) -> f64 {
    if valence == 3 {
        3.0 / 16.0
    } else {
        3.0 / (8.0 * valence as f64)
    }
}

/// `(1 − n w) v + w Σ ring` inside, `(1 − 2 w) v + w (ends)` on the boundary.
fn weigh(
    positions: &[DVec3],
    rings: &Rings,
    v: usize,
    interior_weight: f64,
    edge_weight: f64,
) -> DVec3 {
    let p = |i: u32| positions[i as usize];
    if rings.boundary[v] {
        let (a, b) = rings.boundary_neighbours(v);
        (1.0 - 2.0 * edge_weight) * positions[v] + edge_weight * (p(a) + p(b))
    } else {
        let ring = &rings.ring[v];
        let sum: DVec3 = ring.iter().map(|&i| p(i)).sum();
        (1.0 - ring.len() as f64 * interior_weight) * positions[v] + interior_weight * sum
    }
}

fn refine(mesh: &Level, rings: &Rings) -> Level {
    let mut positions: Vec<DVec3> = (0..mesh.positions.len())
        .map(|v| {
            weigh(
                &mesh.positions,
                rings,
                v,
                beta(rings.ring[v].len()),
                1.0 / 8.0,
            )
        })
        .collect();
    let mut edge_vertex: HashMap<(u32, u32), u32> =
        HashMap::with_capacity(3 * mesh.triangles.len() / 2);
    let p = |i: u32| mesh.positions[i as usize];
    let mut midpoint = |a: u32, b: u32, positions: &mut Vec<DVec3>| -> u32 {
        let key = (a.min(b), a.max(b));
        *edge_vertex.entry(key).or_insert_with(|| {
            let new = match (rings.third.get(&(a, b)), rings.third.get(&(b, a))) {
                (Some(&c), Some(&d)) => 0.375 * (p(a) + p(b)) + 0.125 * (p(c) + p(d)),
                _ => 0.5 * (p(a) + p(b)),
            };
            positions.push(new);
            (positions.len() - 1) as u32
        })
    };
    let mut triangles = Vec::with_capacity(4 * mesh.triangles.len());
    for &[a, b, c] in &mesh.triangles {
        let (ab, bc, ca) = (
            midpoint(a, b, &mut positions),
            midpoint(b, c, &mut positions),
            midpoint(c, a, &mut positions),
        );
        triangles.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
    }
    Level {
        positions,
        triangles,
    }
}

fn limit_position(positions: &[DVec3], rings: &Rings, v: usize) -> DVec3 {
    let n = rings.ring[v].len();
    let gamma = 1.0 / (n as f64 + 3.0 / (8.0 * beta(n)));
    weigh(positions, rings, v, gamma, 1.0 / 5.0)
}

/// The limit surface's unit normal at `v` from its ring's two tangents, as pbrt forms them;
/// where they are parallel, the faces' normal turned as pbrt's would be.
fn limit_normal(limit: &[DVec3], rings: &Rings, v: usize, triangles: &[[u32; 3]]) -> Vec3 {
    let ring: Vec<DVec3> = rings.ring[v].iter().map(|&i| limit[i as usize]).collect();
    let n = ring.len();
    let centre = limit[v];
    let (s, t) = if !rings.boundary[v] {
        let angle = |j: usize| std::f64::consts::TAU * j as f64 / n as f64;
        (
            (0..n).map(|j| angle(j).cos() * ring[j]).sum::<DVec3>(),
            (0..n).map(|j| angle(j).sin() * ring[j]).sum::<DVec3>(),
        )
    } else {
        let s = ring[n - 1] - ring[0];
        let t = match n {
            2 => ring[0] + ring[1] - 2.0 * centre,
            3 => ring[1] - centre,
            4 => -ring[0] + 2.0 * ring[1] + 2.0 * ring[2] - ring[3] - 2.0 * centre,
            _ => {
                let theta = std::f64::consts::PI / (n - 1) as f64;
                let mut t = theta.sin() * (ring[0] + ring[n - 1]);
                for (k, q) in ring.iter().enumerate().take(n - 1).skip(1) {
                    t += (2.0 * theta.cos() - 2.0) * (k as f64 * theta).sin() * *q;
                }
                -t
            }
        };
        (s, t)
    };
    let normal = s.cross(t).normalize_or_zero();
    if normal != DVec3::ZERO && normal.is_finite() {
        return normal.as_vec3();
    }
    // pbrt's limit normals face away from the counter-clockwise side.
    let faces: DVec3 = triangles
        .iter()
        .filter(|t| t.contains(&(v as u32)))
        .map(|&[a, b, c]| {
            let q = |i: u32| limit[i as usize];
            (q(b) - q(a)).cross(q(c) - q(a))
        })
        .sum();
    (-faces).normalize_or(DVec3::Z).as_vec3()
}
