//! The eye pass in participating media: along every camera segment inside a medium, the
//! light the medium scatters towards the eye, and what it lets through to the surface behind.
//! Single scattering comes from the lights by next-event estimation (a point, spot or sphere
//! light's scattering point sampled equiangularly along the segment, the other lights' by a
//! free flight), every shadow ray ratio-tracked through the media it crosses; the rest (light
//! that scattered or bounced before, and volumetric caustics) from the volume photon maps by
//! the beam radiance estimate. Part of [`Integrator`]; owns that split, must not build maps.

use super::integrator::{Integrator, Radiance, RayStart};
use crate::estimate::beam::walls::SegmentWalls;
use crate::estimate::{Scratch, beam};
use crate::media::equiangular::{equiangular, within_cone};
use crate::media::{FreeFlight, Medium};
use crate::sampling::PathSampler;
use crate::scene::MediumId;
use crate::world::Interaction;
use crate::world::lights::LightSource;
use glam::Vec3;

/// What a camera segment through media brings: the light scattered towards its start, what
/// it lets through from its end, and the medium at its end.
pub(super) struct ThroughMedia {
    pub in_scattered: Radiance,
    pub transmittance: Vec3,
    pub medium_at_end: Option<MediumId>,
}

impl Integrator<'_> {
    /// The medium a ray leaving `hit` along `dir` is in, `medium` the one it arrived in.
    #[inline]
    pub(super) fn medium_after(
        &self,
        hit: &Interaction,
        dir: Vec3,
        medium: Option<MediumId>,
    ) -> Option<MediumId> {
        match &self.world.media {
            None => medium,
            Some(media) => media.after_surface(
                hit.geometry,
                hit.instance,
                hit.geometric_normal,
                dir,
                medium,
            ),
        }
    }

    /// What reaches `p` from `p + tfar·dir` (unit `dir`) starting in `medium`: nothing behind
    /// a surface, else the media's transmittance (1 without media).
    #[inline]
    pub(super) fn visibility(
        &self,
        p: Vec3,
        dir: Vec3,
        tfar: f32,
        medium: Option<MediumId>,
        sampler: &mut PathSampler,
    ) -> Vec3 {
        if self.world.occluded(p, dir, 0.0, tfar) {
            return Vec3::ZERO;
        }
        match &self.world.media {
            None => Vec3::ONE,
            Some(media) => media.transmittance((p, dir), tfar, medium, &mut sampler.rng),
        }
    }

    /// What the media let through along `ray` up to `hit` (or to infinity), and the medium
    /// there: the emitted light seen along a specular chain is dimmed by it (1 without media).
    pub(super) fn across_media(
        &self,
        ray: (Vec3, Vec3),
        hit: Option<&Interaction>,
        medium: Option<MediumId>,
        rng: &mut crate::sampling::Rng,
    ) -> (Vec3, Option<MediumId>) {
        match &self.world.media {
            None => (Vec3::ONE, medium),
            Some(media) => media.across(ray, hit.map_or(f32::INFINITY, |h| h.t), medium, rng),
        }
    }

    /// The segment `origin + t·dir` from `start` to `end` (the first surface, or infinity),
    /// starting in `medium`, on an eye path `depth` bounces from the camera: a scattering
    /// point there is that path's next vertex, lit by the lights and read from the maps as
    /// far as the scene's cap on paths allows, as a surface there would be. The surfaces at
    /// either end, and the boundaries crossed, are walls to the beam estimate.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn through_media(
        &self,
        start: RayStart,
        dir: Vec3,
        end: Option<&Interaction>,
        medium: Option<MediumId>,
        depth: u32,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> ThroughMedia {
        let mut out = ThroughMedia {
            in_scattered: Radiance::default(),
            transmittance: Vec3::ONE,
            medium_at_end: medium,
        };
        let Some(media) = &self.world.media else {
            return out;
        };
        let transport = self.world.description.transport;
        let (lit, reads_photons) = (transport.shades(depth), transport.reads_photons(depth));
        let (origin, t_max) = (start.point, end.map_or(f32::INFINITY, |h| h.t));
        let end_normal = end.map(|h| h.geometric_normal);
        let end = media.walk(origin, dir, t_max, medium, |s| {
            let m = media.medium(s.medium);
            // Radiance inside glass, seen from outside it (the eye's throughput does not
            // carry the glass's 1/η² itself: it cancels where a ray enters and leaves).
            let eta = media.index(s.medium);
            let tr = out.transmittance / (eta * eta);
            // Under a subsurface surface every shadow ray meets that surface: the light
            // that enters comes through the photons that refracted in.
            if lit && !media.is_subsurface(s.medium) {
                let single = self.single_scattered(origin, dir, s.medium, (s.t0, s.t1), sampler);
                out.in_scattered.direct += tr * single;
            }
            let found = &mut scratch.beam;
            let rng = &mut sampler.rng;
            let span = (s.t0, s.t1);
            let walls = SegmentWalls::new(
                match s.t0 > 0.0 {
                    true => s.entered_through,
                    false => start.surface_normal,
                },
                match s.t1 < t_max {
                    true => s.left_through,
                    false => end_normal,
                },
                dir,
            );
            if let (true, Some(map)) = (reads_photons, self.volume.caustic) {
                let l = beam::in_scattered(map, m, origin, dir, span, &walls, rng, found);
                out.in_scattered.caustic += tr * l;
            }
            if let (true, Some(map)) = (reads_photons, self.volume.global) {
                let l = beam::in_scattered(map, m, origin, dir, span, &walls, rng, found);
                out.in_scattered.indirect += tr * l;
            }
            out.transmittance *= m.transmittance(origin, dir, s.t0, s.t1, rng);
            out.transmittance.max_element() > 0.0
        });
        out.medium_at_end = end.flatten();
        out
    }

    /// Single scattering towards `origin` from the stretch `(t0, t1)` of `origin + t·dir`
    /// inside `medium`, before the transmittance up to `t0`: one scattering point per light
    /// (equiangular about a small light, else by a free flight shared by the others), its
    /// light sampled as at a surface but over the whole sphere, its shadow ray ratio-tracked.
    fn single_scattered(
        &self,
        origin: Vec3,
        dir: Vec3,
        medium: MediumId,
        (t0, t1): (f32, f32),
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let Some(media) = &self.world.media else {
            return Vec3::ZERO;
        };
        let m = media.medium(medium);
        let phase = m.phase();
        let mut sum = Vec3::ZERO;
        // The free-flight point, drawn once for every light without a centre.
        let flight = if self
            .world
            .light_sources
            .iter()
            .any(|l| l.center().is_none())
        {
            m.free_flight(origin, dir, t0, t1, &mut sampler.rng)
        } else {
            FreeFlight::Passed { weight: Vec3::ZERO }
        };
        let lights = &self.world.light_sampler;
        let one_by_one = lights.one_by_one(self.world.light_sources.len());
        let ray = (origin, dir, (t0, t1), (medium, m));
        for l in one_by_one {
            let light = &self.world.light_sources[l];
            let count = self.samples_of(light) as u32;
            let mut from_light = Vec3::ZERO;
            for _ in 0..count {
                from_light += self.scattered_from(light, ray, flight, &phase, sampler);
            }
            sum += from_light / count as f32;
        }
        if lights.samples_every_light() {
            return sum;
        }
        // Past a few lights, lights drawn by power: a ray's stretch has no one point to rank
        // them from.
        let draws = self.light_samples.max(1);
        let mut drawn = Vec3::ZERO;
        for j in 0..draws {
            let pick = (j as f32 + sampler.rng.next_f32()) / draws as f32;
            let Some((l, probability)) = lights.sample_by_power(pick) else {
                continue;
            };
            let light = &self.world.light_sources[l];
            drawn += self.scattered_from(light, ray, flight, &phase, sampler) / probability;
        }
        sum + drawn / draws as f32
    }

    /// One sample of the light `light` scatters towards the ray's origin from the stretch
    /// `(t0, t1)` of `origin + t·dir` ([`Self::single_scattered`]).
    fn scattered_from(
        &self,
        light: &LightSource,
        (origin, dir, (t0, t1), (medium, m)): (Vec3, Vec3, (f32, f32), (MediumId, &Medium)),
        flight: FreeFlight,
        phase: &crate::media::phase::HenyeyGreenstein,
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let (t, weight) = match light.center() {
            Some(c) => match self.equiangular_on(light, c, (origin, dir), (t0, t1), sampler) {
                Some((t, pdf)) => {
                    let x = origin + t * dir;
                    let tr = m.transmittance(origin, dir, t0, t, &mut sampler.rng);
                    (t, tr * m.sigma_s_at(x) / pdf)
                }
                None => return Vec3::ZERO,
            },
            None => match flight {
                FreeFlight::Scattered { t, weight } => (t, weight),
                FreeFlight::Passed { .. } => return Vec3::ZERO,
            },
        };
        let x = origin + t * dir;
        weight * self.light_at(light, x, -dir, phase, medium, sampler)
    }

    /// A scattering point for `light` (centre `c`) on the stretch (`t0`, `t1`) of the ray,
    /// drawn equiangularly about `c` within the part its cone lights (a spot's).
    fn equiangular_on(
        &self,
        light: &LightSource,
        c: Vec3,
        (origin, dir): (Vec3, Vec3),
        span: (f32, f32),
        sampler: &mut PathSampler,
    ) -> Option<(f32, f32)> {
        let span = match light.cone() {
            Some(cone) => within_cone(origin, dir, cone, span)?,
            None => span,
        };
        equiangular(origin, dir, c, span, sampler.rng.next_f32())
    }

    /// One sample of `light`'s radiance at the medium point `x`, scattered towards `wo`.
    fn light_at(
        &self,
        light: &LightSource,
        x: Vec3,
        wo: Vec3,
        phase: &crate::media::phase::HenyeyGreenstein,
        medium: MediumId,
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let Some(s) = light.sample_incident_in_medium(x, sampler.rng.next_2d()) else {
            return Vec3::ZERO;
        };
        let p = phase.p(wo, s.direction);
        if p <= 0.0 || s.irradiance == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let tfar = s.distance * (1.0 - 1e-4);
        s.irradiance * p * self.visibility(x, s.direction, tfar, Some(medium), sampler)
    }
}
