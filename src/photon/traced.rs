//! A pass's photons as the tracer leaves them, before any kd-tree: each with the path that
//! stored it, in path order, surface and volume photons side by side, the flux not yet
//! divided by the paths emitted. Owns that buffer and its split into the surface map and the
//! volume photons; must not trace.

use super::volume::VolumePhoton;
use super::{EncodedDirections, Photon, PhotonAttributes, PhotonMap};
use glam::Vec3;
use rayon::prelude::*;

/// What a pass did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct TraceCounts {
    pub emitted: u64,
    pub stored: u64,
}

/// Set in a traced photon's `path_in_chunk` when it was left in a medium (a volume photon).
pub(super) const IN_VOLUME: u32 = 1 << 31;

/// A photon as traced, before the flux is divided by the number of paths emitted (32 bytes:
/// the directions are encoded as stored, since their encoding does not depend on that number).
#[derive(Clone, Copy)]
pub(super) struct TracedPhoton {
    pub(super) position: Vec3,
    pub(super) flux: Vec3,
    pub(super) directions: EncodedDirections,
    /// The path that stored it, counted from the first path of its chunk: where a pass that
    /// reaches its target stops counting.
    pub(super) path_in_chunk: u32,
}

impl TracedPhoton {
    /// The stored photon, its flux multiplied by `scale` (one over the paths emitted).
    pub(super) fn record(&self, scale: f32) -> Photon {
        Photon::with_directions(self.position, self.flux * scale, self.directions)
    }
}

/// The photons of one pass, before any kd-tree is built: in path index order, as traced, with
/// the flux not yet divided by the number of paths emitted. Their power is encoded where the map
/// orders them ([`TracedPhotons::into_map`]): one pass over the photons, not two.
pub struct TracedPhotons {
    /// Runs of consecutive paths' photons, in order.
    chunks: Vec<Vec<TracedPhoton>>,
    len: usize,
    pub counts: TraceCounts,
    /// Closest-hit rays cast, counting the paths traced past the target too.
    pub rays: u64,
    /// An interruption was requested: there are no photons, and the pass must be discarded.
    pub interrupted: bool,
}

impl TracedPhotons {
    pub(super) fn new(chunks: Vec<Vec<TracedPhoton>>, counts: TraceCounts, rays: u64) -> Self {
        Self {
            len: chunks.iter().map(Vec::len).sum(),
            chunks,
            counts,
            rays,
            interrupted: false,
        }
    }

    pub fn len(&self) -> usize {
        self.len
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn flux_scale(&self) -> f32 {
        1.0 / self.counts.emitted.max(1) as f32
    }

    /// Takes the volume photons out, in path order, their power divided by the paths
    /// emitted; the surface photons stay.
    pub fn take_volume(&mut self) -> Vec<VolumePhoton> {
        let scale = self.flux_scale();
        let mut volume = Vec::new();
        for chunk in &mut self.chunks {
            if chunk.iter().all(|p| p.path_in_chunk & IN_VOLUME == 0) {
                continue;
            }
            chunk.retain(|p| {
                if p.path_in_chunk & IN_VOLUME == 0 {
                    return true;
                }
                volume.push(VolumePhoton {
                    position: p.position,
                    power: p.flux * scale,
                    direction: Photon::with_directions(p.position, Vec3::ONE, p.directions)
                        .direction(),
                });
                false
            });
        }
        self.len -= volume.len();
        volume
    }

    /// The stored photons, in path order.
    pub fn photons(&self) -> Vec<Photon> {
        let scale = self.flux_scale();
        (self.chunks.iter().flatten())
            .map(|p| p.record(scale))
            .collect()
    }

    /// The photon map of these photons: the same map as [`PhotonMap::build`] of
    /// [`TracedPhotons::photons`]. Each chunk is encoded (in parallel) into positions and
    /// attributes and freed before the kd-tree is built, so the 32-byte traced photons are gone
    /// by the time the tree and the map's attributes take their memory.
    pub fn into_map(self) -> PhotonMap {
        let scale = self.flux_scale();
        let emitted = self.counts.emitted;
        let encoded: Vec<(Vec<Vec3>, Vec<PhotonAttributes>)> = (self.chunks.into_par_iter())
            .map(|chunk| {
                let encoded = chunk
                    .iter()
                    .map(|p| (p.position, p.record(scale).attributes()))
                    .unzip();
                drop(chunk);
                encoded
            })
            .collect();
        let mut positions = Vec::with_capacity(self.len);
        let mut attributes = Vec::with_capacity(self.len);
        for (p, a) in encoded {
            positions.extend_from_slice(&p);
            attributes.extend_from_slice(&a);
        }
        PhotonMap::from_sources(positions, |i| attributes[i], emitted)
    }
}
