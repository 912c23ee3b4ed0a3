//! Triangle meshes in the wrapper: [`SceneBuilder::add_triangles`] copies a small mesh into
//! buffers Embree owns; [`SceneBuilder::add_shared_triangles`] lets Embree read a big one in
//! place (`rtcSetSharedGeometryBuffer`), so a mesh is held once, by its owner, for shading and
//! tracing alike. Both check every vertex and index before Embree sees them (finite, in range),
//! which is what makes reading them safe. Like the rest of this folder it knows nothing of
//! materials or scene files, and must not.

use super::filters::{FilterSlot, HitFilter};
use super::{
    DeviceInner, EmbreeError, GeometryId, SceneBuilder, backend, new_buffer, shim, sys,
    wrapper_error,
};
use glam::Vec3;
use rayon::prelude::*;
use std::ffi::c_void;
use std::sync::Arc;

/// A triangle mesh that Embree may read where it lies. The scene keeps the owner (an `Arc`)
/// alive, and through the `Arc` nobody can change it, for as long as the scene lives.
pub trait SharedTriangles: Send + Sync + 'static {
    /// The vertices. Embree reads each one with a 16-byte load, so it reads 4 bytes past the
    /// last: the positions are shared only when the vector's allocation has room for one more
    /// vertex (see [`pad_for_embree`]), and copied otherwise.
    fn positions(&self) -> &Vec<Vec3>;
    /// Three vertex indices a triangle.
    fn triangles(&self) -> &[[u32; 3]];
}

/// Makes room for one vertex past the last (zeroed, then dropped from the length), so that
/// Embree can read `positions` in place. Free when the vector already has spare capacity;
/// loaders that reserve one more vertex than they read never pay for a copy here.
pub fn pad_for_embree(positions: &mut Vec<Vec3>) {
    positions.reserve_exact(1);
    positions.push(Vec3::ZERO);
    positions.pop();
}

/// Whether Embree can read `positions` in place (see [`SharedTriangles::positions`]).
pub fn padded_for_embree(positions: &Vec<Vec3>) -> bool {
    positions.capacity() > positions.len()
}

/// The checks every mesh gets before Embree reads it, in one parallel pass over each buffer:
/// at least one triangle, finite vertices, indices below the vertex count.
fn check_mesh(positions: &[Vec3], triangles: &[[u32; 3]]) -> Result<(), EmbreeError> {
    if triangles.is_empty() {
        return Err(wrapper_error("a triangle mesh needs at least one triangle"));
    }
    if positions.par_iter().any(|p| !p.is_finite()) {
        return Err(wrapper_error("a mesh vertex is not finite"));
    }
    let n = positions.len();
    let past = |t: &&[u32; 3]| t.iter().any(|&i| i as usize >= n);
    if let Some(t) = triangles.par_iter().find_first(past) {
        return Err(wrapper_error(format!(
            "triangle {t:?} indexes past {n} vertices"
        )));
    }
    Ok(())
}

impl SceneBuilder {
    /// Adds a triangle mesh, copied into Embree's own buffers. Indices must be in range and
    /// positions finite.
    pub fn add_triangles(
        &mut self,
        positions: &[Vec3],
        triangles: &[[u32; 3]],
    ) -> Result<GeometryId, EmbreeError> {
        check_mesh(positions, triangles)?;
        let device = self.device.clone();
        self.attach(backend::TRIANGLE, |g| {
            copy_vertices(&device, g, positions)?;
            let count = triangles.len();
            let indices =
                new_buffer::<[u32; 3]>(&device, g, backend::INDEX, backend::UINT3, count)?;
            indices.copy_from_slice(triangles);
            Ok(())
        })
    }

    /// Adds a triangle mesh that Embree reads in place (its positions copied only when they
    /// lack the padding Embree needs), optionally with a filter that may turn down any hit on
    /// it, for closest hits and occlusion alike (an alpha cut-out). Embree may ask about the
    /// same hit more than once, so `filter` answers the same candidate the same way.
    pub fn add_shared_triangles(
        &mut self,
        mesh: Arc<dyn SharedTriangles>,
        filter: Option<Arc<dyn HitFilter>>,
    ) -> Result<GeometryId, EmbreeError> {
        let (positions, triangles) = (mesh.positions(), mesh.triangles());
        check_mesh(positions, triangles)?;
        let device = self.device.clone();
        let slot = filter.map(FilterSlot::boxed);
        let in_place = padded_for_embree(positions);
        let id = self.attach(backend::TRIANGLE, |g| {
            if in_place {
                // SAFETY: live geometry; `positions` is finite, 4-byte aligned, readable 4 bytes
                // past its last vertex (spare capacity), and the scene keeps `mesh` alive and
                // unchanged (it is behind an `Arc`) until Embree is done with it.
                unsafe { share(g, backend::VERTEX, backend::FLOAT3, positions.as_slice()) };
                device.check()?;
            } else {
                copy_vertices(&device, g, positions)?;
            }
            // SAFETY: as above; every index is below the vertex count (checked).
            unsafe { share(g, backend::INDEX, backend::UINT3, triangles) };
            device.check()?;
            if let Some((_, user)) = &slot {
                // SAFETY: live, uncommitted geometry; `user` points at the boxed
                // `#[repr(C)]` slot, a `dpm_hit_filter`, which the scene keeps in place.
                unsafe { shim::dpm_rtc_set_hit_filter(g, *user) };
            }
            Ok(())
        })?;
        self.filters.extend(slot.map(|(slot, _)| slot));
        if in_place {
            self.meshes_read_in_place += 1;
        }
        self.shared.push(mesh);
        Ok(id)
    }
}

/// Copies `positions` into a vertex buffer Embree owns.
fn copy_vertices(
    device: &DeviceInner,
    geometry: sys::RTCGeometry,
    positions: &[Vec3],
) -> Result<(), EmbreeError> {
    let n = positions.len();
    let vertices = new_buffer::<[f32; 3]>(device, geometry, backend::VERTEX, backend::FLOAT3, n)?;
    for (dst, p) in vertices.iter_mut().zip(positions) {
        *dst = p.to_array();
    }
    Ok(())
}

/// Hands Embree the elements of `items` as buffer `kind`, read where they lie.
///
/// # Safety
/// `geometry` is live and uncommitted; `items` stays valid and unchanged for the geometry's
/// life and is readable as Embree needs for `kind` (a vertex buffer 4 bytes past its end).
unsafe fn share<T>(
    geometry: sys::RTCGeometry,
    kind: sys::RTCBufferType,
    format: sys::RTCFormat,
    items: &[T],
) {
    let stride = std::mem::size_of::<T>();
    // SAFETY: the caller's promise; Embree keeps the pointer, not a copy.
    unsafe {
        sys::rtcSetSharedGeometryBuffer(
            geometry,
            kind,
            0,
            format,
            items.as_ptr() as *const c_void,
            0,
            stride,
            items.len(),
        )
    };
}
