//! pbrt's shapes that dpm renders as triangles it makes itself: the quadrics (`disk`,
//! `cylinder`, `cone`, `paraboloid`, `hyperboloid`, a `sphere` cut by `zmin`, `zmax` or
//! `phimax`), `loopsubdiv` and `heightfield`. Owns reading and checking their parameters
//! (with pbrt's names and defaults) and orienting the result as pbrt does; the geometry is
//! [`crate::scene::tessellate`]'s and the placing [`Mapper::mesh`]'s. Must not choose materials.

use super::super::parser::{Item, ShapeItem};
use super::shapes::{Geometry, MeshData, corner_triples};
use super::{Mapper, param_error, require, value_error};
use crate::scene::SceneError;
use crate::scene::tessellate::{self, Tessellation, loop_subdivision, quadrics::Quadric};
use glam::{DVec3, Mat3, Vec2, Vec3};

/// More subdivision levels than this multiplies even one triangle past memory.
const MAX_LEVELS: i64 = 12;

/// What a partial sphere's parameters say: the full sphere (dpm's analytic sphere) or a
/// quadric to tessellate.
pub(super) enum SphereCut {
    Full,
    Partial(Quadric),
}

impl Mapper<'_> {
    /// A `disk`, `cylinder`, `cone`, `paraboloid` or `hyperboloid`'s triangles, with pbrt's orientation: its normals point outward (along
    /// ∂p/∂u × ∂p/∂v), flipped by `ReverseOrientation` and by a transform that swaps
    /// handedness, as pbrt-v3 flips a quadric's normal in its own space.
    pub(super) fn quadric(&mut self, shape: &ShapeItem) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let quadric = match item.kind.as_str() {
            "disk" => {
                let radius = positive(item, "radius", 1.0)?;
                let inner_radius = float(item, "innerradius", 0.0)?;
                if !(0.0..radius).contains(&inner_radius) {
                    return Err(value_error(
                        item,
                        "Shape",
                        "innerradius",
                        format!("innerradius {inner_radius} is not in [0, radius {radius})"),
                    ));
                }
                Quadric::Disk {
                    height: float(item, "height", 0.0)?,
                    radius,
                    inner_radius,
                    phi_max: phi_max(item)?,
                }
            }
            "cylinder" => {
                let radius = positive(item, "radius", 1.0)?;
                let (z_min, z_max) = z_range(item, -1.0, 1.0)?;
                Quadric::Cylinder {
                    radius,
                    z_min,
                    z_max,
                    phi_max: phi_max(item)?,
                }
            }
            "cone" => {
                let radius = positive(item, "radius", 1.0)?;
                let height = float(item, "height", 1.0)?;
                if height == 0.0 {
                    return Err(value_error(
                        item,
                        "Shape",
                        "height",
                        "height 0: the cone is flat (a disk is)".into(),
                    ));
                }
                Quadric::Cone {
                    height,
                    radius,
                    phi_max: phi_max(item)?,
                }
            }
            "paraboloid" => {
                let radius = positive(item, "radius", 1.0)?;
                let (z_min, z_max) = z_range(item, 0.0, 1.0)?;
                if z_min < 0.0 {
                    return Err(value_error(
                        item,
                        "Shape",
                        "zmin",
                        format!("zmin {z_min} is below 0, where the paraboloid has no points"),
                    ));
                }
                Quadric::Paraboloid {
                    radius,
                    z_min,
                    z_max,
                    phi_max: phi_max(item)?,
                }
            }
            "hyperboloid" => {
                let (p1, p2) = (
                    point(item, "p1", Vec3::ZERO)?,
                    point(item, "p2", Vec3::ONE)?,
                );
                let quadric = Quadric::Hyperboloid {
                    p1,
                    p2,
                    phi_max: phi_max(item)?,
                };
                if p1 == p2 || quadric.radius() == 0.0 {
                    return Err(value_error(
                        item,
                        "Shape",
                        "p2",
                        "p1 and p2 sweep no area (they are equal, or both on the z axis)".into(),
                    ));
                }
                quadric
            }
            other => unreachable!("{other} is not a quadric the caller sends"),
        };
        self.placed_quadric(shape, quadric)
    }

    /// A checked quadric's triangles, turned as pbrt turns its normals.
    pub(super) fn placed_quadric(
        &mut self,
        shape: &ShapeItem,
        quadric: Quadric,
    ) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let mut t = quadric
            .tessellate()
            .map_err(|why| item.at.error("Shape", format!("{}: {why}", item.kind)))?;
        let swaps_handedness = Mat3::from_mat4(shape.ctm).determinant() < 0.0;
        if shape.reverse_orientation ^ swaps_handedness {
            for n in t.normals.iter_mut().flatten() {
                *n = -*n;
            }
        }
        self.tessellated(shape, t)
    }

    /// Whether a `sphere`'s `radius` (checked here), `zmin`, `zmax` and `phimax` leave the
    /// whole sphere. pbrt clamps z to ±radius, and so does dpm.
    pub(super) fn sphere_cut(&self, item: &Item) -> Result<SphereCut, SceneError> {
        let radius = positive(item, "radius", 1.0)?;
        let (z_min, z_max) = z_range(item, -radius, radius)?;
        let (z_min, z_max) = (z_min.max(-radius), z_max.min(radius));
        if z_min >= z_max {
            return Err(value_error(
                item,
                "Shape",
                "zmin",
                format!("zmin and zmax leave nothing of a sphere of radius {radius}"),
            ));
        }
        let phi_max = phi_max(item)?;
        if z_min == -radius && z_max == radius && phi_max == std::f64::consts::TAU {
            return Ok(SphereCut::Full);
        }
        Ok(SphereCut::Partial(Quadric::Sphere {
            radius,
            z_min,
            z_max,
            phi_max,
        }))
    }

    /// `loopsubdiv`: `levels` (or pbrt-v3's older `nlevels`, default 3), `indices`, `P`.
    /// The limit normals come with it, so the mesh faces the way they point, as in pbrt.
    pub(super) fn loop_subdivision(&mut self, shape: &ShapeItem) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let p = |e| param_error("Shape", e);
        let (levels, levels_name) = match item.params.integer("levels").map_err(p)? {
            Some(n) => (n, "levels"),
            None => (
                item.params.integer("nlevels").map_err(p)?.unwrap_or(3),
                "nlevels",
            ),
        };
        if !(0..=MAX_LEVELS).contains(&levels) {
            return Err(value_error(
                item,
                "Shape",
                levels_name,
                format!("{levels_name} {levels} is not from 0 to {MAX_LEVELS}"),
            ));
        }
        let positions = require(item.params.vec3s("P"), item, "P", "Shape")?;
        let indices = require(item.params.integers("indices"), item, "indices", "Shape")?;
        if indices.len() % 3 != 0 {
            return Err(value_error(
                item,
                "Shape",
                "indices",
                format!("has {} indices, not a multiple of 3", indices.len()),
            ));
        }
        // pbrt reads the scheme and always subdivides by Loop's rules.
        item.params.mark_used("scheme");
        let triangles = corner_triples(item, &indices, positions.len())?;
        let s =
            loop_subdivision::subdivide(&positions, &triangles, levels as u32).map_err(|why| {
                value_error(
                    item,
                    "Shape",
                    "indices",
                    format!("loopsubdiv: the mesh {why}"),
                )
            })?;
        // pbrt's loopsubdiv makes no (u, v): its triangles take the default ones.
        let mesh = MeshData {
            positions: s.positions,
            normals: Some(s.normals),
            uvs: None,
            triangles: s.triangles,
        };
        self.mesh(shape, mesh)
    }

    /// `heightfield`: `nu` × `nv` heights `Pz` over the unit square; wound as pbrt winds it,
    /// without normals, so `ReverseOrientation` turns it as it turns a `trianglemesh`.
    pub(super) fn heightfield(&mut self, shape: &ShapeItem) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let mut counts = [0usize; 2];
        for (count, name) in counts.iter_mut().zip(["nu", "nv"]) {
            let n = require(item.params.integer(name), item, name, "Shape")?;
            if !(2..=1 << 16).contains(&n) {
                return Err(value_error(
                    item,
                    "Shape",
                    name,
                    format!("{name} {n} is not from 2 to 65536"),
                ));
            }
            *count = n as usize;
        }
        let heights = require(item.params.floats("Pz"), item, "Pz", "Shape")?;
        let [nu, nv] = counts;
        if heights.len() != nu * nv {
            return Err(value_error(
                item,
                "Shape",
                "Pz",
                format!(
                    "has {} heights, not nu × nv = {nu} × {nv} = {}",
                    heights.len(),
                    nu * nv
                ),
            ));
        }
        let t = tessellate::heightfield(nu, nv, &heights);
        self.tessellated(shape, t)
    }

    fn tessellated(&mut self, shape: &ShapeItem, t: Tessellation) -> Result<Geometry, SceneError> {
        let mesh = MeshData {
            positions: t.positions,
            normals: t.normals,
            uvs: Some(t.uv.into_iter().map(Vec2::from_array).collect()),
            triangles: t.triangles,
        };
        self.mesh(shape, mesh)
    }
}

fn float(item: &Item, name: &str, default: f64) -> Result<f64, SceneError> {
    let value = item
        .params
        .float(name)
        .map_err(|e| param_error("Shape", e))?;
    Ok(value.map_or(default, f64::from))
}

fn point(item: &Item, name: &str, default: Vec3) -> Result<DVec3, SceneError> {
    let value = item
        .params
        .vec3(name)
        .map_err(|e| param_error("Shape", e))?;
    Ok(value.unwrap_or(default).as_dvec3())
}

fn positive(item: &Item, name: &str, default: f64) -> Result<f64, SceneError> {
    let value = float(item, name, default)?;
    if value.is_nan() || value <= 0.0 {
        return Err(value_error(
            item,
            "Shape",
            name,
            format!("{name} {value} is not > 0"),
        ));
    }
    Ok(value)
}

/// `zmin` and `zmax` with their defaults; `zmin` must lie below `zmax`.
fn z_range(item: &Item, min_default: f64, max_default: f64) -> Result<(f64, f64), SceneError> {
    let (z_min, z_max) = (
        float(item, "zmin", min_default)?,
        float(item, "zmax", max_default)?,
    );
    if z_min >= z_max {
        let name = if item.params.at("zmin").is_some() {
            "zmin"
        } else {
            "zmax"
        };
        return Err(value_error(
            item,
            "Shape",
            name,
            format!("zmin {z_min} is not below zmax {z_max}"),
        ));
    }
    Ok((z_min, z_max))
}

/// `phimax` in radians; pbrt's degrees must lie in (0, 360].
fn phi_max(item: &Item) -> Result<f64, SceneError> {
    let degrees = float(item, "phimax", 360.0)?;
    if !(degrees > 0.0 && degrees <= 360.0) {
        return Err(value_error(
            item,
            "Shape",
            "phimax",
            format!("phimax {degrees} is not in (0, 360] degrees"),
        ));
    }
    Ok(if degrees == 360.0 {
        std::f64::consts::TAU
    } else {
        degrees.to_radians()
    })
}
