//! What a camera path reads from the photon maps where it meets a surface that keeps photons:
//! the caustic estimate and the indirect light (final gathering, reading the precomputed
//! irradiance where there is one, or the global map shown directly). Lambert lobes read
//! irradiance and scale it by their albedo/π; other lobes that read photons weigh each photon
//! by their BSDF for the photon's direction ([`Reception`]) and send their gather rays by
//! sampling themselves. Part of [`Integrator`]; owns that reading, must not build maps or
//! touch pixels.

use super::integrator::{
    CLUTTER_DEPTH, Emission, EstimatedMap, Indirect, Integrator, RayStart, sampled_specular,
};
use crate::bsdf::{Bsdf, Part};
use crate::estimate::{PrecomputedIrradiance, Query, Receiver, Scratch, THICK_GATHER};
use crate::sampling::{Frame, PathSampler, Rng, cosine_hemisphere};
use crate::scene::Material;
use crate::scene::MediumId;
use crate::world::Surface;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Specular bounces a gather ray follows before giving up.
const GATHER_SPECULAR_DEPTH: u32 = 4;

/// How a surface reads the photons that reach it.
#[derive(Clone, Copy)]
pub(super) enum Reception<'b> {
    /// Lambert lobes of this summed reflectance: f = reflectance/π whatever the directions.
    Lambert(Vec3),
    /// Some lobes of a BSDF, not all Lambert, seen from one direction.
    Glossy(GlossyReceiver<'b>),
}

impl<'b> Reception<'b> {
    /// How the lobes of `bsdf` in `part` read photons, seen from `wo` (local to `frame`).
    pub(super) fn of(bsdf: &'b Bsdf, part: Part, frame: Frame, wo: Vec3) -> Self {
        match bsdf.lambert_reflectance(part) {
            Some(reflectance) => Reception::Lambert(reflectance),
            None => Reception::Glossy(GlossyReceiver {
                bsdf,
                part,
                frame,
                wo,
            }),
        }
    }
}

/// Some lobes of a BSDF seen from `wo`: their f for each photon's direction.
#[derive(Clone, Copy)]
pub(super) struct GlossyReceiver<'b> {
    bsdf: &'b Bsdf,
    part: Part,
    frame: Frame,
    wo: Vec3,
}

impl Receiver for GlossyReceiver<'_> {
    #[inline]
    fn bsdf(&self, travel: Vec3) -> Vec3 {
        let wi = self.frame.to_local(-travel);
        self.bsdf.f(self.wo, wi, self.part)
    }
}

impl EstimatedMap<'_> {
    /// Radiance the surface `reception` describes reflects from this map's photons at `query`.
    pub(super) fn reflected(
        &self,
        reception: &Reception,
        query: &Query,
        scratch: &mut Scratch,
    ) -> Vec3 {
        match reception {
            Reception::Lambert(reflectance) => {
                *reflectance * FRAC_1_PI * self.estimate.irradiance(self.map, query, scratch)
            }
            Reception::Glossy(receiver) => {
                (self.estimate).reflected(self.map, query, receiver, scratch)
            }
        }
    }
}

impl Integrator<'_> {
    /// Radiance from the caustic map reflected at `query`.
    pub(super) fn caustic(
        &self,
        reception: &Reception,
        query: &Query,
        scratch: &mut Scratch,
    ) -> Vec3 {
        match &self.caustics {
            Some(c) => c.reflected(reception, query, scratch),
            None => Vec3::ZERO,
        }
    }

    /// Indirect radiance reflected at a surface that reads photons (`p` offset off it, `ng`
    /// and `n` its geometric and shading normals on the ray's side, `wo` the unit direction
    /// back along the ray, `at` the path's diffuse hit, `depth` the path's depth there).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn indirect(
        &self,
        reception: &Reception,
        (p, medium): (Vec3, Option<MediumId>),
        (ng, n, wo): (Vec3, Vec3, Vec3),
        at: u32,
        depth: u32,
        query: &Query,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> Vec3 {
        match (&self.indirect, reception) {
            (Indirect::None, _) => Vec3::ZERO,
            // Shown directly, a dense map keeps its own estimate: the nearest table point's
            // piecewise-constant cells would be seen as such. A sparse one is read through
            // its split table, whose cells are smaller than its estimate's noise (see
            // `estimate::precomputed::ShownIrradiance`).
            (
                Indirect::Visualize {
                    map,
                    estimate,
                    table,
                },
                Reception::Lambert(reflectance),
            ) => {
                if let Some(e) = table.and_then(|t| t.lookup(query, scratch)) {
                    return *reflectance * (e * FRAC_1_PI);
                }
                let (e, thickness) = estimate.irradiance_and_thickness(map, query, scratch);
                if thickness > THICK_GATHER && depth < CLUTTER_DEPTH {
                    return *reflectance
                        * self.traced_on((p, medium), (ng, n, wo), at, depth, sampler, scratch);
                }
                *reflectance * (e * FRAC_1_PI)
            }
            (Indirect::Visualize { map, estimate, .. }, glossy) => {
                let g = EstimatedMap {
                    map,
                    estimate: *estimate,
                };
                g.reflected(glossy, query, scratch)
            }
            (
                Indirect::FinalGather {
                    map,
                    rays,
                    precomputed,
                },
                Reception::Lambert(reflectance),
            ) => {
                let mut sum = Vec3::ZERO;
                for j in 0..*rays {
                    // Stratified over the R rays of this hit and across samples and passes.
                    let d = cosine_hemisphere(n, sampler.gather_2d(at, j, *rays));
                    sum += self.gathered(map, *precomputed, p, d, &mut sampler.rng, scratch);
                }
                // Cosine-weighted sampling: E/π is the mean incoming radiance.
                *reflectance * (sum / (*rays).max(1) as f32)
            }
            (
                Indirect::FinalGather {
                    map,
                    rays,
                    precomputed,
                },
                Reception::Glossy(receiver),
            ) => {
                let mut sum = Vec3::ZERO;
                for j in 0..*rays {
                    let u = sampler.gather_2d(at, j, *rays);
                    let u_lobe = sampler.rng.next_f32();
                    let bsdf = receiver.bsdf;
                    let Some(s) = bsdf.sample(receiver.wo, u_lobe, u, receiver.part) else {
                        continue;
                    };
                    let weight = s.f * (s.wi.z.abs() / s.pdf);
                    if !weight.is_finite() || weight.max_element() <= 0.0 {
                        continue;
                    }
                    let d = receiver.frame.to_world(s.wi);
                    let l = self.gathered(map, *precomputed, p, d, &mut sampler.rng, scratch);
                    sum += weight * l;
                }
                sum / (*rays).max(1) as f32
            }
        }
    }

    /// The indirect light at a Lambert hit whose global-map estimate is thick, by the path
    /// traced on: the mean radiance arriving over the cosine-weighted hemisphere of `n` (E/π)
    /// less what the shadow rays at `p` counted already (emitters and the environment seen
    /// next are [`Emission::Elsewhere`]'s). The next surface adds its own direct light, its
    /// caustic estimate and its indirect light, read from the map there or traced on again.
    /// As pbrt samples a Lambert lobe: around the shading normal on the side `wo` leaves by,
    /// nothing from below the geometric one (a shading normal lying in its face, as
    /// buddha-fractal's floor's does, gathers from the viewer's half of the sky only).
    fn traced_on(
        &self,
        (p, medium): (Vec3, Option<MediumId>),
        (ng, n, wo): (Vec3, Vec3, Vec3),
        at: u32,
        depth: u32,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> Vec3 {
        let n = if n.dot(wo) < 0.0 { -n } else { n };
        let d = cosine_hemisphere(n, sampler.gather_2d(at, 0, 1));
        if d.dot(ng) <= 0.0 {
            return Vec3::ZERO;
        }
        let next = self.trace(
            RayStart::on_surface(p, ng),
            d,
            medium,
            depth + 1,
            Emission::Elsewhere,
            sampler,
            scratch,
        );
        next.total()
    }

    /// Radiance from the global map seen along a gather ray (through a few specular bounces).
    fn gathered(
        &self,
        map: &EstimatedMap,
        precomputed: Option<&PrecomputedIrradiance>,
        mut o: Vec3,
        mut d: Vec3,
        rng: &mut Rng,
        scratch: &mut Scratch,
    ) -> Vec3 {
        // What the specular bounces so far let through: their tints.
        let mut throughput = Vec3::ONE;
        // What the BSDF surfaces met on the way gave.
        let mut gathered = Vec3::ZERO;
        for _ in 0..=GATHER_SPECULAR_DEPTH {
            let Some(hit) = self.world.intersect(o, d, 0.0, f32::INFINITY) else {
                break;
            };
            // Direct light from emitters is already counted by the shadow rays.
            let Surface::Material(m) = hit.surface else {
                break;
            };
            let (ng, ns) = hit.facing(d);
            let material = &self.world.material_at(m, &hit);
            let irradiance = |scratch: &mut Scratch| {
                let q = Query {
                    position: hit.position,
                    normal: ns,
                };
                // The full estimate where the table has no agreeing point (see
                // `estimate::precomputed`).
                precomputed
                    .and_then(|t| t.lookup(&q, scratch))
                    .unwrap_or_else(|| map.estimate.irradiance(map.map, &q, scratch))
            };
            if let Material::Bsdf(model) = material {
                // The estimated lobes read the map; the others are followed, as a mirror is.
                let bsdf = self.world.bsdf(model);
                let frame = Frame::new(hit.shading_normal);
                let wo = frame.to_local(-d);
                if bsdf.has(Part::Estimated) {
                    gathered += throughput
                        * match Reception::of(&bsdf, Part::Estimated, frame, wo) {
                            Reception::Lambert(r) => r * FRAC_1_PI * irradiance(scratch),
                            glossy => {
                                let q = Query {
                                    position: hit.position,
                                    normal: ns,
                                };
                                map.reflected(&glossy, &q, scratch)
                            }
                        };
                }
                let Some(s) = bsdf.sample(wo, rng.next_f32(), rng.next_2d(), Part::Followed) else {
                    break;
                };
                throughput *= s.f * (s.wi.z.abs() / s.pdf);
                let next = frame.to_world(s.wi);
                o = self.world.spawn_from(&hit, ng, next);
                d = next;
                continue;
            }
            if let Material::Diffuse { albedo } = material {
                return gathered + throughput * *albedo * FRAC_1_PI * irradiance(scratch);
            }
            let Some((next, tint)) = sampled_specular(self.world, material, &hit, d, ns, rng)
            else {
                break;
            };
            throughput *= tint;
            o = self.world.spawn_from(&hit, ng, next);
            d = next;
        }
        gathered
    }
}
