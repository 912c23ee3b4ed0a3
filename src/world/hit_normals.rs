//! How a hit on one Embree geometry finds its normals: one [`HitNormals`] per geometry id,
//! everything resolving a hit reads in one place (not a kind, then the scene's shape or light,
//! then its normals). Owns the normals' layout and their evaluation at a hit; must not decide
//! what a surface is.
//!
//! A ribbon keeps its control normals ([`super::ribbon`]); a flat curve's normal (Embree
//! reports its tangent) is the band's that faces the ray. A tube keeps its segments' control
//! points and radii, for pbrt's normal and ray offset ([`HitNormals::Tube`]). A curve has no
//! inside (a tube's is open at its ends), and like any open surface it is lit and seen on
//! whichever side a ray meets it ([`super::Interaction::facing`]).

use crate::embree;
use crate::scene::TriangleMesh;
use glam::Vec3;
use std::sync::Arc;

/// How a hit on one Embree geometry finds its normals: everything resolving a hit reads, in
/// one place per geometry id (not a kind, then the scene's shape or light, then its normals).
pub(super) enum HitNormals {
    /// A sphere, object or light: outward, (position − centre) / radius.
    Sphere {
        center: Vec3,
        inverse_radius: f32,
    },
    /// One normal for the whole geometry (a quad light's).
    Fixed(Vec3),
    Triangles(TriangleNormals),
    /// pbrt's ribbon, a flat band narrowed by its filter ([`super::ribbon`]): Embree reports
    /// the tangent; the normal is the ribbon's, made perpendicular to it.
    Ribbon(std::sync::Arc<super::ribbon::Ribbon>),
    /// A tube (pbrt's cylinder curve): each segment's four Bézier control points and radii.
    /// pbrt draws it as a band facing the ray whose normal turns about the tangent linearly
    /// across the band, 90° at its edges, away from the edge it is near (pbrt-v3's
    /// `Rotate(-theta, dpduPlane)`: lit from one side, pbrt's tube is bright on the other),
    /// and starts rays off it 2 widths along that normal, clear of the band: dpm shades and
    /// leaves its tubes so ([`tube_offset`]), to render pbrt's image.
    Tube(Vec<([Vec3; 4], [f32; 4])>),
    /// A flat curve, which faces every ray: its normal is the ray's direction made
    /// perpendicular to the curve's tangent (which Embree reports as the hit's normal).
    FlatCurve,
}

/// A mesh's normals at a hit, read from the mesh itself, which Embree reads too (no table
/// per triangle: a mesh is held once). The geometric normal is worked out from the corners,
/// the same way every time, so a triangle's normal does not depend on who asks.
pub(super) struct TriangleNormals {
    mesh: Arc<TriangleMesh>,
    /// Interpolate the mesh's vertex normals (an emitter shades flat even when it has them).
    smooth: bool,
}

impl TriangleNormals {
    /// Smooth where the mesh has vertex normals, flat elsewhere.
    pub(super) fn new(mesh: Arc<TriangleMesh>) -> Self {
        let smooth = mesh.normals.is_some();
        Self { mesh, smooth }
    }

    /// Flat whatever the mesh holds.
    pub(super) fn flat(mesh: Arc<TriangleMesh>) -> Self {
        Self {
            mesh,
            smooth: false,
        }
    }

    /// The unit geometric and shading normals of triangle `primitive` at barycentrics (u, v).
    #[inline]
    fn at(&self, primitive: u32, u: f32, v: f32) -> (Vec3, Vec3) {
        let corners = self.mesh.triangles[primitive as usize];
        let [p0, p1, p2] = corners.map(|i| self.mesh.positions[i as usize]);
        let ng = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Z);
        match &self.mesh.normals {
            Some(n) if self.smooth => {
                let [n0, n1, n2] = corners.map(|i| n[i as usize]);
                let s = ((1.0 - u - v) * n0 + u * n1 + v * n2).normalize_or(ng);
                (ng, if s.dot(ng) < 0.0 { -s } else { s })
            }
            _ => (ng, ng),
        }
    }
}

pub(super) fn sphere_normals(center: Vec3, radius: f32) -> HitNormals {
    HitNormals::Sphere {
        center,
        inverse_radius: 1.0 / radius,
    }
}

/// `v` brought to unit length by one Newton step on 1/|v|, for a `v` already close to it (a
/// point on a sphere over its radius: off by Embree's hit error, up to about 2e-5, tested):
/// the step squares that error, without the square root and division of normalising.
#[inline(always)]
fn unit_within_rounding(v: Vec3) -> Vec3 {
    v * (1.5 - 0.5 * v.length_squared())
}

/// The geometric and shading normals of `hit` at `position` of a ray along `dir` (all in the
/// geometry's own space).
#[inline(always)]
pub(super) fn normals_at(
    normals: &HitNormals,
    hit: &embree::Hit,
    position: Vec3,
    dir: Vec3,
) -> (Vec3, Vec3) {
    match normals {
        HitNormals::Sphere {
            center,
            inverse_radius,
        } => {
            let n = unit_within_rounding((position - *center) * *inverse_radius);
            (n, n)
        }
        HitNormals::Fixed(n) => (*n, *n),
        HitNormals::Triangles(mesh) => mesh.at(hit.primitive, hit.u, hit.v),
        HitNormals::Ribbon(ribbon) => {
            let tangent = hit.normal.normalize_or_zero();
            let n = ribbon.shading_normal(hit.primitive, hit.u, tangent, dir);
            (n, n)
        }
        HitNormals::Tube(segments) => {
            let n = hit.normal.normalize_or(-dir);
            let n = pbrt_tube_normal(&segments[hit.primitive as usize].0, hit.u, n, dir);
            (n, n)
        }
        HitNormals::FlatCurve => {
            let t = hit.normal.normalize_or_zero();
            let n = (t * dir.dot(t) - dir).normalize_or(-dir);
            (n, n)
        }
    }
}

/// pbrt's shading normal on a cylinder curve (segment `p`, parameter `u`), given the true
/// tube's unit normal `n` at the hit of a ray along `dir`: the offset across the band facing
/// the ray is s = n · a, with a = tangent × dir, pbrt's v is (s + 1)/2, and its normal is the
/// band's ray-facing normal turned by θ = 90° · s away from a.
fn pbrt_tube_normal(p: &[Vec3; 4], u: f32, n: Vec3, dir: Vec3) -> Vec3 {
    let across = tube_across(p, u, dir);
    if across == Vec3::ZERO {
        return n;
    }
    let s = n.dot(across).clamp(-1.0, 1.0);
    let facing = (n - s * across).normalize_or(-dir);
    let (sin, cos) = (std::f32::consts::FRAC_PI_2 * s).sin_cos();
    (cos * facing - sin * across).normalize_or(n)
}

/// The unit direction across the band pbrt draws for a cylinder curve's segment `p` at
/// parameter `u`, seen along `dir`: the tangent × `dir` (zero where they are parallel).
pub(super) fn tube_across(p: &[Vec3; 4], u: f32, dir: Vec3) -> Vec3 {
    let w = 1.0 - u;
    let tangent = w * w * (p[1] - p[0]) + 2.0 * w * u * (p[2] - p[1]) + u * u * (p[3] - p[2]);
    tangent.cross(dir).normalize_or_zero()
}

/// How far pbrt starts a ray off a tube hit (segment `primitive`, parameter `u`) with normal
/// `n`: its error bound of twice the width at the hit in every axis, along the normal
/// (2 w (|nx| + |ny| + |nz|)); `None` off tubes.
#[inline(always)]
pub(super) fn tube_offset(normals: &HitNormals, primitive: u32, u: f32, n: Vec3) -> Option<f32> {
    let HitNormals::Tube(segments) = normals else {
        return None;
    };
    let r = segments[primitive as usize].1;
    let w = 1.0 - u;
    let radius =
        w * w * w * r[0] + 3.0 * w * w * u * r[1] + 3.0 * w * u * u * r[2] + u * u * u * r[3];
    Some(4.0 * radius * n.abs().element_sum())
}
