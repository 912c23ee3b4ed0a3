//! Bodies read in parallel. Binary: records all of one size, vertices whose properties are all
//! scalars and faces that are all triangles of one list and nothing else, each record decoded
//! where it lies. ASCII: a line an element, vertices of scalars only and faces of one list of
//! three or four corners. Each element's checks (finite values, indices in range, corner
//! counts) run in the same pass. Anything else, and any element a check refuses, is left to
//! the sequential reader ([`super::body`]), which names the first bad element: this path never
//! reports an error.

use super::{Element, MAX_VERTICES, PlyMesh, Property, Scalar, vertex_layout};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// The byte offset and type of each scalar property in a record, and the record's size;
/// `None` if a property is a list.
fn fixed_record(element: &Element) -> Option<(Vec<(usize, Scalar)>, usize)> {
    let mut fields = Vec::with_capacity(element.properties.len());
    let mut size = 0;
    for p in &element.properties {
        let Property::Scalar { ty, .. } = p else {
            return None;
        };
        fields.push((size, *ty));
        size += ty.size();
    }
    Some((fields, size))
}

/// Reads `element` (the vertices) from the start of `bytes` into `mesh`, returning the bytes
/// used, or `None` (nothing written) where the sequential reader must.
pub(super) fn vertices(
    bytes: &[u8],
    element: &Element,
    big: bool,
    mesh: &mut PlyMesh,
) -> Option<usize> {
    if element.count > MAX_VERTICES {
        return None;
    }
    let layout = vertex_layout(element).ok()?;
    let (fields, size) = fixed_record(element)?;
    let used = element.count.checked_mul(size)?;
    let records = bytes.get(..used)?;
    let value = |record: &[u8], slot: usize| {
        let (at, ty) = fields[slot];
        ty.decode(&record[at..at + ty.size()], big) as f32
    };
    // Collected whole (an indexed collect writes in place), then checked.
    let vec3s = |[a, b, c]: [usize; 3]| -> Option<Vec<Vec3>> {
        let v: Vec<Vec3> = (records.par_chunks_exact(size))
            .map(|r| Vec3::new(value(r, a), value(r, b), value(r, c)))
            .collect();
        v.par_iter().all(|v| v.is_finite()).then_some(v)
    };
    let positions = vec3s(layout.position)?;
    let normals = match layout.normal {
        Some(slots) => Some(vec3s(slots)?),
        None => None,
    };
    let uvs = match layout.uv {
        Some([a, b]) => {
            let v: Vec<Vec2> = (records.par_chunks_exact(size))
                .map(|r| Vec2::new(value(r, a), value(r, b)))
                .collect();
            Some(v.par_iter().all(|v| v.is_finite()).then_some(v)?)
        }
        None => None,
    };
    (mesh.positions, mesh.normals, mesh.uvs) = (positions, normals, uvs);
    Some(used)
}

/// Reads `element` (the faces, every one a triangle) from the start of `bytes` into `mesh`,
/// returning the bytes used, or `None` (nothing written) where the sequential reader must.
pub(super) fn triangles(
    bytes: &[u8],
    element: &Element,
    vertex_count: usize,
    big: bool,
    mesh: &mut PlyMesh,
) -> Option<usize> {
    let [Property::List { name, count, item }] = &element.properties[..] else {
        return None;
    };
    if name != "vertex_indices" && name != "vertex_index" {
        return None;
    }
    let (count, item) = (*count, *item);
    let size = count.size() + 3 * item.size();
    let used = element.count.checked_mul(size)?;
    let records = bytes.get(..used)?;
    // A refused record is marked by an index no mesh has, then looked for.
    const REFUSED: u32 = u32::MAX;
    let corner = |raw: &[u8]| {
        let v = item.decode(raw, big);
        match v >= 0.0 && v.fract() == 0.0 && (v as usize) < vertex_count {
            true => v as u32,
            false => REFUSED,
        }
    };
    let triangles: Vec<[u32; 3]> = (records.par_chunks_exact(size))
        .map(|r| {
            if count.decode(&r[..count.size()], big) != 3.0 {
                return [REFUSED; 3];
            }
            let at = |k: usize| count.size() + k * item.size();
            [0, 1, 2].map(|k| corner(&r[at(k)..at(k) + item.size()]))
        })
        .collect();
    if triangles.par_iter().any(|t| t.contains(&REFUSED)) {
        return None;
    }
    mesh.triangles = triangles;
    Some(used)
}

/// One ASCII word as the sequential reader reads a `ty` value.
fn ascii_value(word: &str, ty: Scalar) -> Option<f64> {
    match ty.is_integer() {
        true => word.parse::<i64>().ok().map(|v| v as f64),
        false => word.parse::<f64>().ok(),
    }
}

/// Reads `element` (the vertices, a line each) from `lines` into `mesh`, or `None` (nothing
/// written) where the sequential reader must.
pub(super) fn ascii_vertices(lines: &[&str], element: &Element, mesh: &mut PlyMesh) -> Option<()> {
    if element.count > MAX_VERTICES || lines.len() != element.count {
        return None;
    }
    let layout = vertex_layout(element).ok()?;
    let types: Vec<Scalar> = (element.properties.iter())
        .map(|p| match p {
            Property::Scalar { ty, .. } => Some(*ty),
            Property::List { .. } => None,
        })
        .collect::<Option<_>>()?;
    // Each line's values, all of them, as the sequential reader would hold them.
    let record = |line: &str| -> Option<Vec<f32>> {
        let mut values = Vec::with_capacity(types.len());
        let mut words = line.split_whitespace();
        for ty in &types {
            values.push(ascii_value(words.next()?, *ty)? as f32);
        }
        (words.next().is_none() && values.iter().all(|v| v.is_finite())).then_some(values)
    };
    let pick3 = |v: &[f32], [a, b, c]: [usize; 3]| Vec3::new(v[a], v[b], v[c]);
    let rows: Vec<(Vec3, Vec3, Vec2)> = (lines.par_iter())
        .map(|line| {
            let v = record(line)?;
            let n = layout.normal.map_or(Vec3::ZERO, |slots| pick3(&v, slots));
            let t = layout.uv.map_or(Vec2::ZERO, |[a, b]| Vec2::new(v[a], v[b]));
            Some((pick3(&v, layout.position), n, t))
        })
        .collect::<Option<_>>()?;
    mesh.positions = rows.par_iter().map(|r| r.0).collect();
    mesh.normals = layout
        .normal
        .map(|_| rows.par_iter().map(|r| r.1).collect());
    mesh.uvs = layout.uv.map(|_| rows.par_iter().map(|r| r.2).collect());
    Some(())
}

/// Reads `element` (faces of three or four corners, a line each, one list and nothing else)
/// from `lines` into `mesh`, or `None` (nothing written) where the sequential reader must.
pub(super) fn ascii_triangles(
    lines: &[&str],
    element: &Element,
    vertex_count: usize,
    mesh: &mut PlyMesh,
) -> Option<()> {
    let [Property::List { name, count, item }] = &element.properties[..] else {
        return None;
    };
    if (name != "vertex_indices" && name != "vertex_index") || lines.len() != element.count {
        return None;
    }
    let corner = |word: &str| {
        let v = ascii_value(word, *item)?;
        (v >= 0.0 && v.fract() == 0.0 && (v as usize) < vertex_count).then_some(v as u32)
    };
    // A quad is two triangles, [a, b, c] and [a, c, d], as the sequential reader splits it.
    let faces: Vec<([u32; 3], Option<[u32; 3]>)> = (lines.par_iter())
        .map(|line| {
            let mut words = line.split_whitespace();
            let n = ascii_value(words.next()?, *count)?;
            let corners: Vec<u32> = words.map(corner).collect::<Option<_>>()?;
            match corners[..] {
                [a, b, c] if n == 3.0 => Some(([a, b, c], None)),
                [a, b, c, d] if n == 4.0 => Some(([a, b, c], Some([a, c, d]))),
                _ => None,
            }
        })
        .collect::<Option<_>>()?;
    let quads = faces.iter().filter(|f| f.1.is_some()).count();
    mesh.triangles = Vec::with_capacity(faces.len() + quads);
    for (first, second) in faces {
        mesh.triangles.push(first);
        mesh.triangles.extend(second);
    }
    Some(())
}
