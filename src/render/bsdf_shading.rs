//! The eye pass at a surface with a BSDF model (pbrt's plastic, uber, rough metals and glass,
//! …). Its lobes come in three parts ([`Part`]): broad lobes (Lambert, a coated base, the
//! Fresnel blend) read the caustic and global maps as a diffuse surface does; glossy lobes
//! rough enough to read photons read the caustic map, each photon weighed by f for its
//! direction, and sample the rest of their light by one ray that leaves the caustic map's
//! paths to it ([`Emission::CausticMap`]); followed lobes are sampled by one ray, as a
//! mirror is. Direct light comes from shadow rays over every non-delta lobe
//! (`super::direct_light`), weighed against each sampled part's own samples by multiple
//! importance sampling (the balance heuristic, counting each light's samples). Part of
//! [`Integrator`]; owns that split, must not build maps or touch pixels.

use super::direct_light::{At, Sampled, balance};
use super::gather::Reception;
use super::integrator::{Emission, Integrator, Radiance, RayStart};
use crate::bsdf::{Bsdf, Model, Part};
use crate::estimate::{Query, Scratch};
use crate::sampling::{Frame, PathSampler};
use crate::scene::MediumId;
use crate::world::{Interaction, Surface};
use glam::Vec3;

impl Integrator<'_> {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn shade_bsdf(
        &self,
        hit: &Interaction,
        model: &Model,
        (dir, medium): (Vec3, Option<MediumId>),
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
        // Light reaching the followed lobes from emitters is the caustic map's when the path
        // came from a glossy lobe that reads it.
        let followed_lit = emission != Emission::CausticMap;
        // A point light behind rough glass reaches the eye through it only by a shadow ray
        // from the far side (the lobe's own samples never find it), as pbrt samples it.
        let back = (followed_lit && bsdf.transmits_spread(Part::Followed))
            .then(|| self.world.offset_from(hit, -ng));
        let at = At {
            hit,
            frame,
            wo,
            p: self.world.offset_from(hit, ng),
            back,
            ng,
            ns,
            medium,
        };
        let diffuse_hit = sampler.next_diffuse_hit();
        let deeper = depth < self.max_depth;
        let sampled = Sampled {
            glossy: deeper && bsdf.has(Part::Glossy),
            followed: deeper && followed_lit && bsdf.has(Part::Followed),
        };
        let mut out = Radiance {
            direct: self.direct_bsdf(&at, &bsdf, sampled, followed_lit, diffuse_hit, sampler),
            ..Radiance::default()
        };
        let transport = self.world.description.transport;
        if bsdf.has(Part::Estimated) && transport.reads_photons(depth) {
            let query = Query {
                position: hit.position,
                normal: ns,
            };
            let caustic = Reception::of(&bsdf, Part::Estimated, frame, wo);
            out.caustic = self.caustic(&caustic, &query, scratch);
            if bsdf.has(Part::Broad) {
                let broad = Reception::of(&bsdf, Part::Broad, frame, wo);
                out.indirect = self.indirect(
                    &broad,
                    (at.p, self.medium_after(hit, ng, medium)),
                    (ng, ns, -dir),
                    diffuse_hit,
                    depth,
                    &query,
                    sampler,
                    scratch,
                );
            }
        }
        if !deeper {
            return out;
        }
        if sampled.glossy {
            // What reaches a glossy lobe past the caustic map: emitters seen directly (weighed
            // against the shadow rays) and whatever a surface that reads photons sends.
            let modes = (Emission::CausticMap, Emission::CausticMap);
            out += self.sample_part(
                &at,
                &bsdf,
                Part::Glossy,
                depth,
                modes,
                true,
                sampler,
                scratch,
            );
        }
        if bsdf.has(Part::Followed) {
            let after = if followed_lit {
                Emission::Counted
            } else {
                Emission::CausticMap
            };
            let modes = (emission, after);
            out += self.sample_part(
                &at,
                &bsdf,
                Part::Followed,
                depth,
                modes,
                followed_lit,
                sampler,
                scratch,
            );
        }
        out
    }

    /// Radiance arriving along one sample of `bsdf`'s `part`, times the sample's weight: a
    /// delta lobe's ray goes on in mode `along` (the path's own, for a specular chain); a
    /// non-delta lobe's ray counts the emitter or environment it meets first (when `lit`,
    /// weighed against the shadow rays) and shades anything else in mode `after`.
    #[allow(clippy::too_many_arguments)]
    fn sample_part(
        &self,
        at: &At,
        bsdf: &Bsdf,
        part: Part,
        depth: u32,
        (along, after): (Emission, Emission),
        lit: bool,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> Radiance {
        let (u_lobe, u) = (sampler.rng.next_f32(), sampler.rng.next_2d());
        let Some(s) = bsdf.sample(at.wo, u_lobe, u, part) else {
            return Radiance::default();
        };
        let weight = s.f * (s.wi.z.abs() / s.pdf);
        if weight.max_element() <= 0.0 || !weight.is_finite() {
            return Radiance::default();
        }
        let next = at.frame.to_world(s.wi);
        let origin = self.world.spawn_from(at.hit, at.ng, next);
        let medium = self.medium_after(at.hit, next, at.medium);
        if s.delta {
            let start = RayStart::on_surface(origin, at.ng);
            return weight * self.trace(start, next, medium, depth + 1, along, sampler, scratch);
        }
        // Shadow rays sample the far side only through a lobe that spreads transmitted light;
        // elsewhere light through a transmitting lobe is this sample's alone.
        let (from, facing) = match (s.transmission, at.back) {
            (false, _) => (Some(at.p), at.ns),
            (true, back) => (back, -at.ns),
        };
        let mis = |light_pdf: f32, light: &crate::world::lights::LightSource| match from {
            Some(_) => balance(s.pdf, self.samples_of(light) * light_pdf),
            None => 1.0,
        };
        let from_side = from;
        let from = from.unwrap_or(at.p);
        let found = self.world.intersect(origin, next, 0.0, f32::INFINITY);
        // Through media the sample goes on as a camera ray does: what lies at its end is
        // dimmed, and the light scattered towards the surface along the way is added.
        let through = (self.world.media.is_some()).then(|| {
            let start = RayStart::on_surface(origin, at.ng);
            self.through_media(
                start,
                next,
                found.as_ref(),
                medium,
                depth + 1,
                sampler,
                scratch,
            )
        });
        // `end`: what the sample sees at its end, already times its weight.
        let seen_through = |end: Radiance| match &through {
            None => end,
            Some(t) => weight * t.in_scattered + t.transmittance * end,
        };
        let Some(found) = found else {
            let mut sky = Vec3::ZERO;
            if lit {
                for light in &self.world.light_sources {
                    let radiance = light.radiance_at_infinity() + light.sky_radiance(next);
                    if radiance != Vec3::ZERO {
                        let light_pdf =
                            light.incident_pdf(from, facing, next, f32::INFINITY, Vec3::ZERO);
                        sky += radiance * mis(light_pdf, light);
                    }
                }
            }
            return seen_through(Radiance {
                direct: weight * sky,
                ..Radiance::default()
            });
        };
        if let Surface::Light(l) = found.surface {
            if !lit {
                return seen_through(Radiance::default());
            }
            let light = &self.world.light_sources[l];
            let emitted = light.emitted_radiance(-next.dot(found.geometric_normal));
            let weigh = match (&from_side, self.world.light_sampler.samples_every_light()) {
                (None, _) => 1.0,
                (Some(_), true) => {
                    let light_pdf =
                        light.incident_pdf(from, facing, next, found.t, found.geometric_normal);
                    mis(light_pdf, light)
                }
                (Some(_), false) => {
                    self.drawn_emitter_weight(at, (from, facing, next), s.pdf, &found)
                }
            };
            return seen_through(Radiance {
                direct: weight * emitted * weigh,
                ..Radiance::default()
            });
        }
        if !self.world.description.transport.glossy_sees_surfaces() {
            // pbrt's direct lighting: a glossy lobe sees lights, not what they light.
            return seen_through(Radiance::default());
        }
        let end = through.as_ref().and_then(|t| t.medium_at_end);
        if through
            .as_ref()
            .is_some_and(|t| t.transmittance == Vec3::ZERO)
        {
            return seen_through(Radiance::default());
        }
        seen_through(weight * self.shade(&found, next, end, depth + 1, after, sampler, scratch))
    }
}
