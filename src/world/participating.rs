//! Where the media are: the surfaces that only bound them (pbrt's `Material ""`), kept in an
//! Embree scene of their own so that the surfaces light bounces off never see them, the
//! media on the two sides of every surface that separates two, and the media the camera and
//! the lights sit in. A ray's medium is carried by whoever traces it; this module says how it
//! changes along a segment (the boundaries crossed) and at a surface (its interface), and what
//! a segment lets through. Must not sample paths or store photons.

use super::BoundingSphere;
use super::hit_normals::{HitNormals, normals_at};
use crate::bsdf::Model;
use crate::embree::{self, EmbreeError};
use crate::media::{FreeFlight, Medium};
use crate::sampling::Rng;
use crate::scene::{Material, MediumId, MediumInterface, SceneMedia, Shape};
use glam::Vec3;
use std::collections::HashMap;

/// Boundaries crossed along one ray past which the walk stops (coplanar boundaries must not
/// loop it).
const MAX_CROSSINGS: usize = 256;

pub struct Participating {
    media: Vec<Medium>,
    /// By medium: under a subsurface material's surface.
    subsurface: Vec<bool>,
    /// By medium: the refractive index of the glass it fills (1 where it fills none).
    index: Vec<f32>,
    /// The boundary surfaces; `None` when every medium is bounded by surfaces that scatter.
    boundaries: Option<embree::Scene>,
    boundary_normals: Vec<HitNormals>,
    boundary_sides: Vec<MediumInterface>,
    /// Surfaces with a material that separate two media, by Embree geometry id.
    surface_sides: HashMap<u32, MediumInterface>,
    camera: Option<MediumId>,
    /// By light, in the scene's order.
    light_media: Vec<Option<MediumId>>,
    /// How far past a boundary the walk goes on.
    epsilon: f32,
    /// Around the boundaries and the surfaces between media, when there are any.
    bounds: Option<BoundingSphere>,
}

/// A stretch of a ray inside one medium: t from `t0` to `t1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MediumSegment {
    pub medium: MediumId,
    pub t0: f32,
    pub t1: f32,
    /// The unit normal of the boundary the segment starts on, if it entered this medium
    /// there (not at the ray's origin); either side.
    pub entered_through: Option<Vec3>,
    /// The unit normal of the boundary the segment ends on, if the medium ends there (not at
    /// `t_max`); either side.
    pub left_through: Option<Vec3>,
}

impl Participating {
    /// The media of a scene, or `None` when it has none (and renders as before media existed).
    pub(super) fn new(
        device: &embree::Device,
        description: &SceneMedia,
        shapes: &[Shape],
        materials: &[Material],
        lights: usize,
        epsilon: f32,
    ) -> Result<Option<Self>, EmbreeError> {
        if description.is_empty() {
            return Ok(None);
        }
        let media = (description.media.iter())
            .map(|m| {
                Medium::new(m).ok_or_else(|| EmbreeError {
                    code: embree::ErrorCode::InvalidArgument,
                    message: format!("medium \"{}\" cannot be built", m.name),
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for &(shape, _) in &description.shape_interfaces {
            let (a, b) = shapes[shape].bounds();
            (lo, hi) = (lo.min(a), hi.max(b));
        }
        let mut boundary_normals = Vec::new();
        let mut boundary_sides = Vec::new();
        let boundaries = if description.boundaries.is_empty() {
            None
        } else {
            let mut builder = device.scene_builder()?;
            for boundary in &description.boundaries {
                let (normals, (a, b), _) = super::add_shape(&mut builder, &boundary.shape)?;
                (lo, hi) = (lo.min(a), hi.max(b));
                boundary_normals.push(normals);
                boundary_sides.push(boundary.interface);
            }
            Some(builder.commit()?)
        };
        // A medium inside a dielectric shape is as dense as its glass.
        let mut index = vec![1.0f32; media.len()];
        for &(shape, sides) in &description.shape_interfaces {
            let glass = match materials[shapes[shape].material() as usize] {
                Material::Glass { ior, .. } => Some(ior),
                Material::Bsdf(Model::Dielectric { eta, .. }) => Some(eta),
                _ => None,
            };
            if let (Some(ior), Some(inside)) = (glass, sides.inside) {
                index[inside as usize] = ior;
            }
        }
        let mut light_media = vec![None; lights];
        for &(light, medium) in &description.light_media {
            light_media[light] = Some(medium);
        }
        Ok(Some(Self {
            media,
            subsurface: description.media.iter().map(|m| m.subsurface).collect(),
            index,
            boundaries,
            boundary_normals,
            boundary_sides,
            surface_sides: (description.shape_interfaces.iter())
                .map(|&(shape, sides)| (shape as u32, sides))
                .collect(),
            camera: description.camera,
            light_media,
            epsilon,
            bounds: (lo.x <= hi.x).then(|| BoundingSphere::around_box(lo, hi)),
        }))
    }

    pub fn medium(&self, id: MediumId) -> &Medium {
        &self.media[id as usize]
    }

    /// The refractive index of the glass medium `id` fills (1 where none): radiance inside
    /// is that squared times what it is once it has left through the glass, so an eye in
    /// vacuum reads the light scattered there divided by it squared.
    pub fn index(&self, id: MediumId) -> f32 {
        self.index[id as usize]
    }

    /// Whether some medium lies outside every subsurface surface (fog, smoke, a liquid in
    /// glass): where volumetric caustics form.
    pub fn has_free_media(&self) -> bool {
        self.subsurface.iter().any(|&under| !under)
    }

    /// Whether medium `id` lies under a subsurface material's surface, where a path's events
    /// are one walk and not bounces.
    pub fn is_subsurface(&self, id: MediumId) -> bool {
        self.subsurface[id as usize]
    }

    /// A sphere around the surfaces that bound media, where photons from lights at infinity
    /// are sent more often than the scene's size alone would send them; `None` where the
    /// media have no bounding surface.
    pub fn bounds(&self) -> Option<BoundingSphere> {
        self.bounds
    }

    pub fn camera(&self) -> Option<MediumId> {
        self.camera
    }

    pub fn light(&self, light: usize) -> Option<MediumId> {
        self.light_media[light]
    }

    /// Bytes the media keep (grids and majorants).
    pub fn bytes(&self) -> usize {
        self.media.iter().map(Medium::bytes).sum()
    }

    /// The medium a ray is in after meeting the scattering surface `geometry` (a top-level
    /// Embree geometry; `instance` the one it was hit through, or `u32::MAX`) and leaving it
    /// along `dir`, `normal` the surface's geometric normal as oriented: its interface's side
    /// where it has one, else the medium the ray had.
    pub fn after_surface(
        &self,
        geometry: u32,
        instance: u32,
        normal: Vec3,
        dir: Vec3,
        medium: Option<MediumId>,
    ) -> Option<MediumId> {
        if instance != u32::MAX {
            return medium;
        }
        match self.surface_sides.get(&geometry) {
            Some(sides) => sides.after_crossing(dir, normal),
            None => medium,
        }
    }

    /// Walks `origin + t·dir` (unit `dir`) from t = 0 to `t_max`, starting in `medium`,
    /// across the boundaries: `visit` sees each stretch inside a medium in order and returns
    /// false to stop the walk. Returns the medium at `t_max` (`None` once stopped).
    pub fn walk(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_max: f32,
        mut medium: Option<MediumId>,
        mut visit: impl FnMut(MediumSegment) -> bool,
    ) -> Option<Option<MediumId>> {
        let mut t = 0.0f32;
        let mut entered_through = None;
        for _ in 0..MAX_CROSSINGS {
            let crossing =
                (self.boundaries.as_ref()).and_then(|scene| scene.intersect(origin, dir, t, t_max));
            // Where the ray crosses, the normal there and the medium past it.
            let across = crossing.as_ref().map(|hit| {
                let position = origin + hit.t * dir;
                let normals = &self.boundary_normals[hit.geometry as usize];
                let (normal, _) = normals_at(normals, hit, position, dir);
                let after = self.boundary_sides[hit.geometry as usize].after_crossing(dir, normal);
                (
                    hit.t + self.epsilon * position.abs().max_element().max(1.0),
                    normal,
                    after,
                )
            });
            let t1 = crossing.as_ref().map_or(t_max, |hit| hit.t);
            let left_through = across.and_then(|(_, n, after)| (after != medium).then_some(n));
            if let Some(m) = medium
                && !visit(MediumSegment {
                    medium: m,
                    t0: t,
                    t1,
                    entered_through,
                    left_through,
                })
            {
                return None;
            }
            let Some((next, normal, after)) = across else {
                return Some(medium);
            };
            entered_through = (after != medium).then_some(normal);
            (t, medium) = (next, after);
        }
        Some(medium)
    }

    /// What the media let through along the ray `origin + t·dir` from 0 to `t_max` (surfaces
    /// that scatter are the caller's to test).
    pub fn transmittance(
        &self,
        ray: (Vec3, Vec3),
        t_max: f32,
        medium: Option<MediumId>,
        rng: &mut Rng,
    ) -> Vec3 {
        self.attenuate(ray, t_max, medium, rng, true).0
    }

    /// [`Participating::transmittance`], and the medium at `t_max`.
    pub fn across(
        &self,
        ray: (Vec3, Vec3),
        t_max: f32,
        medium: Option<MediumId>,
        rng: &mut Rng,
    ) -> (Vec3, Option<MediumId>) {
        let (tr, end) = self.attenuate(ray, t_max, medium, rng, false);
        (tr, end.flatten())
    }

    /// The transmittance along the ray and, unless the walk stopped where it went dark
    /// (`stop_when_dark`), the medium at `t_max`. Past a dark stretch nothing more is tracked.
    fn attenuate(
        &self,
        (origin, dir): (Vec3, Vec3),
        t_max: f32,
        medium: Option<MediumId>,
        rng: &mut Rng,
        stop_when_dark: bool,
    ) -> (Vec3, Option<Option<MediumId>>) {
        let mut tr = Vec3::ONE;
        let end = self.walk(origin, dir, t_max, medium, |s| {
            if tr.max_element() > 0.0 {
                tr *= (self.medium(s.medium)).transmittance(origin, dir, s.t0, s.t1, rng);
            }
            !stop_when_dark || tr.max_element() > 0.0
        });
        (tr, end)
    }

    /// A flight along `origin + t·dir` up to `t_max`: the first scattering event in any
    /// medium crossed (its t, medium and weight) or the weight of passing them all, and the
    /// medium at `t_max`.
    pub fn free_flight(
        &self,
        ray: (Vec3, Vec3),
        t_max: f32,
        medium: Option<MediumId>,
        rng: &mut Rng,
    ) -> Flight {
        let (origin, dir) = ray;
        let mut weight = Vec3::ONE;
        let mut event = None;
        let end = self.walk(origin, dir, t_max, medium, |s| {
            match self
                .medium(s.medium)
                .free_flight(origin, dir, s.t0, s.t1, rng)
            {
                FreeFlight::Scattered { t, weight: w } => {
                    event = Some((t, s.medium, weight * w));
                    false
                }
                FreeFlight::Passed { weight: w } => {
                    weight *= w;
                    true
                }
            }
        });
        match (event, end) {
            (Some((t, medium, weight)), _) => Flight::Scattered { t, medium, weight },
            (None, end) => Flight::Passed {
                weight,
                medium: end.flatten(),
            },
        }
    }
}

/// Where a flight through the media ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Flight {
    /// Scattered at `t` in `medium`; `weight` multiplies the throughput (before the phase).
    Scattered {
        t: f32,
        medium: MediumId,
        weight: Vec3,
    },
    /// Reached the segment's end in `medium`, `weight` for the media passed.
    Passed {
        weight: Vec3,
        medium: Option<MediumId>,
    },
}
