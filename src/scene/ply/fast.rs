//! Binary bodies whose records all have one size, read in parallel: vertices whose properties
//! are all scalars, and faces that are all triangles of one list and nothing else. Each record
//! is decoded where it lies, its checks (finite values, indices in range, three corners) in the
//! same pass. Anything else, and any record a check refuses, is left to the sequential reader
//! ([`super::body`]), which names the first bad element: this path never reports an error.

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
