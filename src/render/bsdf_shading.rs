//! The eye pass at a surface with a BSDF model (pbrt's plastic, uber, rough metals and glass,
//! …): its Lambert lobes read the caustic and global maps exactly as a diffuse surface does;
//! direct light comes from shadow rays over every non-delta lobe, weighed against the BSDF's
//! own samples by multiple importance sampling (the balance heuristic, counting each light's
//! samples); its other lobes are followed by one BSDF sample, whose ray counts the emitter or
//! environment it meets with the matching weight. Part of [`Integrator`]; owns that split,
//! must not build maps or touch pixels.

use super::gather::Reception;
use super::integrator::{Emission, Integrator, Radiance};
use crate::bsdf::{Bsdf, Model, Part};
use crate::estimate::{Query, Scratch};
use crate::sampling::{Frame, PathSampler};
use crate::world::{Interaction, Surface};
use glam::Vec3;

/// The balance heuristic's weight of a strategy of density `pdf` against another of `other`.
#[inline]
fn balance(pdf: f32, other: f32) -> f32 {
    if pdf.is_infinite() {
        1.0
    } else if pdf + other > 0.0 {
        pdf / (pdf + other)
    } else {
        0.0
    }
}

impl Integrator<'_> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn shade_bsdf(
        &self,
        hit: &Interaction,
        model: &Model,
        dir: Vec3,
        depth: u32,
        emission: Emission,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> Radiance {
        let (ng, ns) = hit.facing(dir);
        let bsdf = self.world.bsdf(model);
        // The surface's own side, not the ray's: a dielectric knows its inside by it.
        let frame = Frame::new(hit.shading_normal);
        let wo = frame.to_local(-dir);
        let at = sampler.next_diffuse_hit();
        let p = self.offset(hit.position, ng);
        let mut out = Radiance {
            direct: self.direct_bsdf(p, ns, &frame, wo, &bsdf, at, sampler),
            ..Radiance::default()
        };
        if bsdf.has(Part::Estimated) {
            let reception = Reception::of(&bsdf, frame, wo);
            let query = Query {
                position: hit.position,
                normal: ns,
            };
            out.caustic = self.caustic(&reception, &query, scratch);
            out.indirect = self.indirect(&reception, p, ns, at, &query, sampler, scratch);
        }
        if depth >= self.max_depth || !bsdf.has(Part::Followed) {
            return out;
        }
        let (u_lobe, u) = (sampler.rng.next_f32(), sampler.rng.next_2d());
        let Some(s) = bsdf.sample(wo, u_lobe, u, Part::Followed) else {
            return out;
        };
        let weight = s.f * (s.wi.z.abs() / s.pdf);
        if weight.max_element() <= 0.0 || !weight.is_finite() {
            return out;
        }
        let next = frame.to_world(s.wi);
        let origin = self.spawn(hit.position, ng, next);
        if s.delta {
            out += weight * self.trace(origin, next, depth + 1, emission, sampler, scratch);
            return out;
        }
        // A non-delta lobe's ray: what it meets first is weighed against the shadow rays.
        let Some(found) = self.world.intersect(origin, next, 0.0, f32::INFINITY) else {
            let mut sky = Vec3::ZERO;
            for light in &self.world.light_sources {
                let radiance = light.radiance_at_infinity() + light.sky_radiance(next);
                if radiance != Vec3::ZERO {
                    let light_pdf = light.incident_pdf(p, ns, next, f32::INFINITY, Vec3::ZERO);
                    sky += radiance * balance(s.pdf, self.samples_of(light) * light_pdf);
                }
            }
            out.direct += weight * sky;
            return out;
        };
        if let Surface::Light(l) = found.surface {
            let light = &self.world.light_sources[l];
            let emitted = light.emitted_radiance(-next.dot(found.geometric_normal));
            let light_pdf = light.incident_pdf(p, ns, next, found.t, found.geometric_normal);
            out.direct += weight * emitted * balance(s.pdf, self.samples_of(light) * light_pdf);
            return out;
        }
        out += weight * self.shade(&found, next, depth + 1, Emission::Counted, sampler, scratch);
        out
    }

    /// Shadow rays a light takes at each hit.
    fn samples_of(&self, light: &crate::world::lights::LightSource) -> f32 {
        if light.is_delta() {
            1.0
        } else {
            self.light_samples.max(1) as f32
        }
    }

    /// Reflected direct radiance at `p` (offset off the surface on the side the ray came
    /// from, whose normal is `n`): every non-delta lobe by shadow rays, the followed lobes'
    /// share weighed against their own samples. Light from the other side reaches the
    /// transmitting lobes by their own samples alone.
    #[allow(clippy::too_many_arguments)]
    fn direct_bsdf(
        &self,
        p: Vec3,
        n: Vec3,
        frame: &Frame,
        wo: Vec3,
        bsdf: &Bsdf,
        at: u32,
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let followed = bsdf.has(Part::Followed);
        let mut radiance = Vec3::ZERO;
        for (l, light) in self.world.light_sources.iter().enumerate() {
            let count = self.samples_of(light) as u32;
            let mut sum = Vec3::ZERO;
            for j in 0..count {
                let Some(s) = light.sample_incident(p, n, sampler.light_2d(at, l, j, count)) else {
                    continue;
                };
                let wi = frame.to_local(s.direction);
                if wi.z * wo.z <= 0.0 {
                    continue;
                }
                let mut f = bsdf.f(wo, wi, Part::Estimated);
                if followed {
                    let own = bsdf.pdf(wo, wi, Part::Followed);
                    f += bsdf.f(wo, wi, Part::Followed) * balance(count as f32 * s.pdf, own);
                }
                if f.max_element() <= 0.0 {
                    continue;
                }
                let tfar = s.distance * (1.0 - 1e-4);
                if !self.world.occluded(p, s.direction, 0.0, tfar) {
                    sum += f * s.irradiance * wi.z.abs();
                }
            }
            radiance += sum / count as f32;
        }
        radiance
    }
}
