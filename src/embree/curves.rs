//! Embree's native cubic Bézier curves in the wrapper: [`SceneBuilder::add_curves`] checks a
//! curve geometry's control points, radii, segment indices and normals, and hands them to
//! Embree as one flat (ray-facing), round (swept circle) or normal-oriented (ribbon) Bézier
//! curve geometry. Owns the curve buffers' layout and the curve kinds' Embree types; like the
//! rest of this folder it knows nothing of materials or scene files, and must not.

use super::filters::{FilterSlot, HitFilter};
use super::{EmbreeError, GeometryId, SceneBuilder, backend, new_buffer, shim, sys, wrapper_error};
use glam::Vec3;
use std::sync::Arc;

/// Ray-facing quads Embree cuts each flat curve segment into (its default is 4, meant for
/// sub-pixel hair; a curve seen close up shows the bends between them).
pub const FLAT_CURVE_QUADS: f32 = 16.0;

/// How Embree draws a curve's cross-section, each a cubic Bézier curve geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// `RTC_GEOMETRY_TYPE_FLAT_BEZIER_CURVE`: a band that always faces the ray, as wide as
    /// twice the radius. A hit's [`super::Hit::normal`] is the curve's tangent there (not a
    /// surface normal) and its `v` runs from −1 to 1 across the band.
    Flat,
    /// `RTC_GEOMETRY_TYPE_ROUND_BEZIER_CURVE`: the surface a circle of the radius sweeps along
    /// the curve (a tube); a hit's normal is the surface's, outward. The radius must stay
    /// below the curve's radius of curvature.
    Round,
    /// `RTC_GEOMETRY_TYPE_NORMAL_ORIENTED_BEZIER_CURVE`: a band across the normal spline (its
    /// width along normal × tangent); a hit's normal is the band's and `v` runs from 0 to 1
    /// across it. Needs one normal per control point, not along the curve.
    NormalOriented,
}

impl CurveKind {
    fn geometry_type(self) -> sys::RTCGeometryType {
        match self {
            CurveKind::Flat => backend::FLAT_BEZIER_CURVE,
            CurveKind::Round => backend::ROUND_BEZIER_CURVE,
            CurveKind::NormalOriented => backend::NORMAL_ORIENTED_BEZIER_CURVE,
        }
    }
}

impl SceneBuilder {
    /// Adds cubic Bézier curve segments of `kind`: `control_points` are (x, y, z, radius),
    /// segment `i` (primitive `i` of the geometry) is the four points from
    /// `first_indices[i]` on. `normals` are per control point and only, and always, given
    /// for [`CurveKind::NormalOriented`]. Points and normals must be finite, radii finite and
    /// non-negative with some radius above zero in every segment (a curve may taper to a
    /// point), normals non-zero, and every segment's four points in range.
    pub fn add_curves(
        &mut self,
        kind: CurveKind,
        control_points: &[[f32; 4]],
        first_indices: &[u32],
        normals: Option<&[Vec3]>,
    ) -> Result<GeometryId, EmbreeError> {
        self.add_curves_then(kind, control_points, first_indices, normals, |_| {})
    }

    /// [`Self::add_curves`] with a filter that may turn down any hit on them, for closest
    /// hits and occlusion alike (pbrt's ribbon: a band facing the ray, only as wide there as
    /// its normal faces the ray). Embree may ask about the same hit more than once, so
    /// `filter` answers the same candidate the same way.
    pub fn add_filtered_curves(
        &mut self,
        kind: CurveKind,
        control_points: &[[f32; 4]],
        first_indices: &[u32],
        filter: Arc<dyn HitFilter>,
    ) -> Result<GeometryId, EmbreeError> {
        let (slot, user) = FilterSlot::boxed(filter);
        let id = self.add_curves_then(kind, control_points, first_indices, None, |g| {
            // SAFETY: live, uncommitted geometry; `user` points at the boxed `#[repr(C)]` slot,
            // a `dpm_hit_filter`, which the scene keeps in place for as long as it lives.
            unsafe { shim::dpm_rtc_set_hit_filter(g, user) };
        })?;
        self.filters.push(slot);
        Ok(id)
    }

    fn add_curves_then(
        &mut self,
        kind: CurveKind,
        control_points: &[[f32; 4]],
        first_indices: &[u32],
        normals: Option<&[Vec3]>,
        finish: impl FnOnce(sys::RTCGeometry),
    ) -> Result<GeometryId, EmbreeError> {
        check_curves(kind, control_points, first_indices, normals)?;
        let device = self.device.clone();
        self.attach(kind.geometry_type(), |g| {
            let n = control_points.len();
            let vertices = new_buffer::<[f32; 4]>(&device, g, backend::VERTEX, backend::FLOAT4, n)?;
            vertices.copy_from_slice(control_points);
            let count = first_indices.len();
            let indices = new_buffer::<u32>(&device, g, backend::INDEX, backend::UINT, count)?;
            indices.copy_from_slice(first_indices);
            if let Some(normals) = normals {
                let out = new_buffer::<[f32; 3]>(&device, g, backend::NORMAL, backend::FLOAT3, n)?;
                for (dst, n) in out.iter_mut().zip(normals) {
                    *dst = n.to_array();
                }
            }
            if kind == CurveKind::Flat {
                // SAFETY: a live flat curve geometry, not yet committed.
                unsafe { sys::rtcSetGeometryTessellationRate(g, FLAT_CURVE_QUADS) };
                device.check()?;
            }
            finish(g);
            Ok(())
        })
    }
}

/// What [`SceneBuilder::add_curves`] refuses before Embree sees it.
fn check_curves(
    kind: CurveKind,
    control_points: &[[f32; 4]],
    first_indices: &[u32],
    normals: Option<&[Vec3]>,
) -> Result<(), EmbreeError> {
    if first_indices.is_empty() {
        return Err(wrapper_error("a curve geometry needs at least one segment"));
    }
    if let Some(p) = control_points
        .iter()
        .find(|p| !p.iter().all(|x| x.is_finite()) || p[3] < 0.0)
    {
        return Err(wrapper_error(format!(
            "curve control point {p:?} is not finite or has a negative radius"
        )));
    }
    let n = control_points.len();
    for (segment, &first) in first_indices.iter().enumerate() {
        let Some(points) = control_points.get(first as usize..first as usize + 4) else {
            return Err(wrapper_error(format!(
                "curve segment {segment} starts at point {first}, and its four points run past {n}"
            )));
        };
        if points.iter().all(|p| p[3] == 0.0) {
            return Err(wrapper_error(format!(
                "curve segment {segment} has no radius"
            )));
        }
    }
    match (kind, normals) {
        (CurveKind::NormalOriented, None) => Err(wrapper_error(
            "a normal-oriented curve needs a normal per control point",
        )),
        (CurveKind::NormalOriented, Some(normals)) if normals.len() != n => Err(wrapper_error(
            format!("{} curve normals for {n} control points", normals.len()),
        )),
        (CurveKind::NormalOriented, Some(normals)) => {
            match normals.iter().find(|v| !v.is_finite() || *v == &Vec3::ZERO) {
                Some(v) => Err(wrapper_error(format!(
                    "curve normal {v} is zero or not finite"
                ))),
                None => Ok(()),
            }
        }
        (_, Some(_)) => Err(wrapper_error("only normal-oriented curves take normals")),
        (_, None) => Ok(()),
    }
}
