//! A photon path as the tracer carries it: which map its pass fills, where it starts, what it
//! carries on its way (flux, medium, what it has met), how many surfaces and events it may
//! meet, and the rule for leaving a photon on a diffuse landing. Shared by the tracer and its
//! scattering parts (`bsdf_scatter`, `medium_scatter`) and the emitter; must not trace rays.

use super::EncodedDirections;
use super::traced::TracedPhoton;
use crate::sampling::Rng;
use crate::scene::MediumId;
use crate::world::World;
use glam::Vec3;

/// Which map a tracing pass fills.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MapKind {
    /// Light → specular+ → diffuse. Paths end at their first diffuse hit.
    Caustic,
    /// Photons on diffuse surfaces after at least one diffuse bounce (`with_direct`: every
    /// diffuse hit, as final gathering needs).
    Global { with_direct: bool },
}

/// Paths longer than this are cut: a photon trapped between mirrors must not loop forever.
const MAX_BOUNCES: u32 = 32;

/// Scattering events a walk under one subsurface surface may take (they count as no bounce):
/// Russian roulette ends nearly all walks long before, even at albedo 0.999.
pub(super) const MAX_WALK_EVENTS: u32 = 4096;

/// The start of a path that carries flux.
pub(super) struct PathStart {
    /// The light it left, in the scene's order.
    pub(super) light: usize,
    pub(super) rng: Rng,
    pub(super) origin: Vec3,
    pub(super) direction: Vec3,
    pub(super) flux: Vec3,
    /// The medium the light sits in.
    pub(super) medium: Option<MediumId>,
}

/// A path on its way: its next ray and what it carries.
pub(super) struct LivePath {
    pub(super) path_in_chunk: u32,
    pub(super) rng: Rng,
    pub(super) origin: Vec3,
    pub(super) direction: Vec3,
    pub(super) flux: Vec3,
    pub(super) bounces: u32,
    /// Events of its walks under subsurface surfaces.
    pub(super) walk_events: u32,
    pub(super) specular_seen: bool,
    /// Whether the path has bounced off a diffuse surface or scattered in a medium (other
    /// than under a subsurface surface, whose walk counts as the surface's own transport).
    pub(super) diffuse_seen: bool,
    pub(super) medium: Option<MediumId>,
}

impl LivePath {
    pub(super) fn new(path_in_chunk: u32, start: PathStart) -> Self {
        Self {
            path_in_chunk,
            rng: start.rng,
            origin: start.origin,
            direction: start.direction,
            flux: start.flux,
            bounces: 0,
            walk_events: 0,
            specular_seen: false,
            diffuse_seen: false,
            medium: start.medium,
        }
    }
}

/// Surfaces a path may meet: the tracer's own limit, or fewer where the scene caps paths
/// (a photon stored on its k-th surface has met k − 1 before it).
#[inline(always)]
pub(super) fn bounce_limit(world: &World) -> u32 {
    match world.description.transport.photon_bounces() {
        Some(cap) => MAX_BOUNCES.min(cap + 1),
        None => MAX_BOUNCES,
    }
}

/// Leaves the path's photon at a diffuse landing (`position`, arriving along `d` on the side
/// of `ns`) when its map keeps such paths: the caustic map those that met a mirror, glass or
/// glossy lobe first, the global map those past a diffuse bounce (or all, `with_direct`).
#[inline(always)]
pub(super) fn store_photon(
    kind: MapKind,
    path: &LivePath,
    position: Vec3,
    d: Vec3,
    ns: Vec3,
    stored: &mut Vec<TracedPhoton>,
) {
    let store = match kind {
        MapKind::Caustic => path.specular_seen,
        MapKind::Global { with_direct } => path.diffuse_seen || with_direct,
    };
    if store {
        stored.push(TracedPhoton {
            position,
            flux: path.flux,
            directions: EncodedDirections::new(d, ns),
            path_in_chunk: path.path_in_chunk,
        });
    }
}
