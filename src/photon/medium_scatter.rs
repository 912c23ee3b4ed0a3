//! A photon path at a scattering event in a medium: what it leaves in the volume maps, and
//! where it goes on. Part of the tracer (`tracer`), as `bsdf_scatter` is for BSDF surfaces.

use super::EncodedDirections;
use super::path::{LivePath, MAX_WALK_EVENTS, MapKind, bounce_limit};
use super::traced::{IN_VOLUME, TracedPhoton};
use crate::scene::MediumId;
use crate::world::World;
use glam::Vec3;

/// Moves a path on from a scattering event at `t` along its ray in `medium`, `weight` the
/// flight's (σs·Tr/pdf): leaves a volume photon where its map keeps one (a volumetric
/// caustic's first event after mirrors and glass in the caustic map; any event after a
/// diffuse bounce or an earlier event in the global map; single scattering straight from
/// the light is the eye pass's own, by next-event estimation), then scatters by the phase
/// function under Russian roulette. Under a subsurface surface the whole walk is the
/// surface's own transport, as a glass's refraction is: every event is kept in the map the
/// path's entry chose (the caustic pass's walks go on), none counts as a bounce or makes the
/// path diffuse. Returns whether the path goes on.
pub(super) fn scatter_in_medium(
    world: &World,
    kind: MapKind,
    path: &mut LivePath,
    t: f32,
    medium: MediumId,
    weight: Vec3,
    stored: &mut Vec<TracedPhoton>,
) -> bool {
    let Some(media) = &world.media else {
        return false;
    };
    let d = path.direction;
    let position = path.origin + t * d;
    let scattered = path.flux * weight;
    let keep = match kind {
        MapKind::Caustic => path.specular_seen && !path.diffuse_seen,
        MapKind::Global { .. } => path.diffuse_seen,
    };
    if keep && scattered.max_element() > 0.0 {
        stored.push(TracedPhoton {
            position,
            flux: scattered,
            directions: EncodedDirections::new(d, -d),
            path_in_chunk: path.path_in_chunk | IN_VOLUME,
        });
    }
    let walk = media.is_subsurface(medium);
    if kind == MapKind::Caustic && !walk {
        return false;
    }
    let survive = weight.max_element().min(1.0);
    if survive <= 0.0 || path.rng.next_f32() >= survive {
        return false;
    }
    path.flux = scattered / survive;
    path.diffuse_seen |= !walk;
    path.medium = Some(medium);
    path.origin = position;
    path.direction = media
        .medium(medium)
        .phase()
        .sample(-d, path.rng.next_2d())
        .0;
    if walk {
        path.walk_events += 1;
        return path.walk_events < MAX_WALK_EVENTS;
    }
    path.bounces += 1;
    path.bounces < bounce_limit(world)
}
