//! Radiance estimates: one interface ([`RadianceEstimate`]), its implementations side by side.
//! An estimate turns the photons near a surface point into photon power per unit area
//! (irradiance, W/m² per channel); the caller applies the BRDF. Owns kernels and their
//! normalisation; must not trace rays or know about Embree, cameras or images.

use crate::photon::{Neighbours, PhotonMap};
use glam::Vec3;

/// Where an estimate is asked for: a surface point and its unit normal (on the side light
/// arrives from).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Query {
    pub position: Vec3,
    pub normal: Vec3,
}

/// Per-thread scratch space so that queries allocate nothing.
#[derive(Clone, Debug, Default)]
pub struct Scratch {
    pub neighbours: Neighbours,
    pub second: Neighbours,
}

pub trait RadianceEstimate: Send + Sync {
    /// Short name, as on the command line.
    fn name(&self) -> &'static str;

    /// Work on the whole map before any query (the diffusion estimate's gradient pass).
    /// The default does nothing, so no pass runs for an estimate that does not need it.
    fn prepare(&self, _map: &mut PhotonMap) {}

    /// Photon power per unit area arriving at `query`.
    fn irradiance(&self, map: &PhotonMap, query: &Query, scratch: &mut Scratch) -> Vec3;
}
