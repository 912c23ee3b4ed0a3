//! A photon map: photons in kd-tree order, plus the per-photon gradient when an estimate asks
//! for one. Owns storage and lookup; knows nothing of kernels, Embree or light transport.

use super::{KdTree, Photon};
use glam::Vec3;

#[derive(Clone, Debug, Default)]
pub struct PhotonMap {
    tree: KdTree,
    photons: Vec<Photon>,
    gradients: Option<Vec<Vec3>>,
    /// Photon paths emitted from the lights to fill this map (for reporting and scaling).
    pub emitted: u64,
}

impl PhotonMap {
    pub fn build(photons: Vec<Photon>, emitted: u64) -> Self {
        let positions: Vec<Vec3> = photons.iter().map(Photon::position).collect();
        let tree = KdTree::build(&positions);
        let photons = (0..tree.len())
            .map(|s| photons[tree.source_index(s) as usize])
            .collect();
        Self {
            tree,
            photons,
            gradients: None,
            emitted,
        }
    }
    pub fn len(&self) -> usize {
        self.photons.len()
    }
    pub fn is_empty(&self) -> bool {
        self.photons.is_empty()
    }
    pub fn tree(&self) -> &KdTree {
        &self.tree
    }
    /// Photons in tree order: slot `s` of a query result is `photons()[s]`.
    pub fn photons(&self) -> &[Photon] {
        &self.photons
    }
    pub fn photon(&self, slot: u32) -> &Photon {
        &self.photons[slot as usize]
    }
    /// Total stored power.
    pub fn total_power(&self) -> Vec3 {
        self.photons.iter().map(Photon::power).sum()
    }
    /// Gradients in tree order, one per photon (set by the gradient pass).
    pub fn set_gradients(&mut self, gradients: Vec<Vec3>) {
        assert_eq!(gradients.len(), self.photons.len());
        self.gradients = Some(gradients);
    }
    pub fn gradients(&self) -> Option<&[Vec3]> {
        self.gradients.as_deref()
    }
}
