//! Curved and implicit surfaces turned into object-space triangles: the quadrics of
//! revolution to a stated error bound ([`quadrics`]), Loop subdivision surfaces
//! ([`loop_subdivision`]) and height fields over the unit square ([`heightfield`]). Owns the
//! geometry alone: parameters arrive checked (the scene format's mapping names the parameter
//! a bad value came from), and nothing here knows a file format, a transform or a material.
//! Results are in the shape's own space; placing them in the world is the caller's.

pub(crate) mod loop_subdivision;
pub(crate) mod quadrics;
#[cfg(test)]
mod tests;

use glam::Vec3;

/// The largest distance allowed between a quadric and its triangles, as a fraction of the
/// quadric's radius (its largest distance from its axis), in its own space. At 5e-4 a shape
/// spanning 2000 pixels has its silhouette within half a pixel of the true one, and the
/// per-vertex normals are exact, so images do not change where it matters (see
/// docs/scene-format.md, "Shapes").
pub(crate) const RELATIVE_ERROR_BOUND: f64 = 5e-4;

/// Object-space triangles with a unit normal per vertex (when the surface defines one) and
/// each vertex's (u, v) surface parameters, as pbrt defines them for the shape (the texture
/// coordinates of the mesh it becomes).
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Tessellation {
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    pub triangles: Vec<[u32; 3]>,
    pub uv: Vec<[f32; 2]>,
}

/// pbrt's height field: an `nu` × `nv` grid of points over [0, 1]², point (i, j) at
/// (i/(nu−1), j/(nv−1), heights[i + j·nu]), two triangles per cell wound counter-clockwise
/// seen from +z. Needs nu, nv ≥ 2 and `heights.len() == nu·nv` (the caller checks both).
pub(crate) fn heightfield(nu: usize, nv: usize, heights: &[f32]) -> Tessellation {
    debug_assert!(nu >= 2 && nv >= 2 && heights.len() == nu * nv);
    let mut out = Tessellation::default();
    for j in 0..nv {
        for i in 0..nu {
            let (u, v) = (i as f32 / (nu - 1) as f32, j as f32 / (nv - 1) as f32);
            out.positions.push(Vec3::new(u, v, heights[i + j * nu]));
            out.uv.push([u, v]);
        }
    }
    let at = |i: usize, j: usize| (i + j * nu) as u32;
    for j in 0..nv - 1 {
        for i in 0..nu - 1 {
            out.triangles
                .push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            out.triangles
                .push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    out
}
