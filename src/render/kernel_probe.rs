//! The kernel-field probe: the diffusion kernel's shape (λ1, λ2 and the edge direction) where a
//! pixel's centre ray first meets a surface that reads photons, for the kernel-field layer
//! (the paper's Figure 2b). Owns that one ray and the channels' encoding; must not estimate
//! radiance or touch the film.

use crate::estimate::{DiffusionEstimate, Query, Scratch};
use crate::photon::PhotonMap;
use crate::world::{Surface, World};
use glam::Vec3;

/// The diffusion kernel's shape where a pixel's centre ray first meets a diffuse surface.
pub struct KernelProbe<'a> {
    pub world: &'a World,
    pub map: &'a PhotonMap,
    pub estimate: &'a DiffusionEstimate,
}

impl KernelProbe<'_> {
    /// (λ2, (1 − λ2) cos 2θ, (1 − λ2) sin 2θ, λ1) with θ the edge direction's angle in the
    /// surface's tangent frame; a round kernel (1, 0, 0, 1) where nothing diffuse is hit.
    pub fn channels(&self, origin: Vec3, dir: Vec3, scratch: &mut Scratch) -> [f32; 4] {
        const ROUND: [f32; 4] = [1.0, 0.0, 0.0, 1.0];
        let Some(hit) = self.world.intersect(origin, dir, 0.0, f32::INFINITY) else {
            return ROUND;
        };
        let Surface::Material(m) = hit.surface else {
            return ROUND;
        };
        if !self.world.reads_photons(m) {
            return ROUND;
        }
        let (_, n) = hit.facing(dir);
        let query = Query {
            position: hit.position,
            normal: n,
        };
        let shape = self.estimate.kernel_at(self.map, &query, scratch);
        let (t, b) = crate::sampling::basis(n);
        let theta = shape.x1.dot(b).atan2(shape.x1.dot(t));
        let w = 1.0 - shape.lambda2;
        [
            shape.lambda2,
            w * (2.0 * theta).cos(),
            w * (2.0 * theta).sin(),
            shape.lambda1,
        ]
    }
}
