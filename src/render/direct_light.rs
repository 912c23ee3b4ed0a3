//! Direct light at an eye hit: which lights a hit samples (every light, or draws from the
//! world's light tree past a few, [`crate::world::lights::sampler`]), the shadow rays towards
//! them, and the balance-heuristic weights that set those samples against a BSDF's own
//! (counting every draw and its probability). Part of [`Integrator`]; owns the light samples,
//! must not read photon maps or follow paths.

use super::integrator::Integrator;
use crate::bsdf::{Bsdf, Part};
use crate::sampling::{Frame, PathSampler};
use crate::scene::MediumId;
use crate::world::lights::LightSource;
use crate::world::{Interaction, SHADING_AGREEMENT_MIN_COS, Surface};
use glam::Vec3;

/// The light slot of [`PathSampler::light_2d`] that draws from the light tree take (no
/// scene has this many lights).
pub(super) const DRAWN_LIGHTS: usize = 0xFF_FFFF;

/// The balance heuristic's weight of a strategy of density `pdf` against another of `other`.
#[inline]
pub(super) fn balance(pdf: f32, other: f32) -> f32 {
    if pdf.is_infinite() {
        1.0
    } else if pdf + other > 0.0 {
        pdf / (pdf + other)
    } else {
        0.0
    }
}

/// Where a BSDF hit is and how it is seen.
pub(super) struct At<'h> {
    pub(super) hit: &'h Interaction,
    pub(super) frame: Frame,
    pub(super) wo: Vec3,
    /// Off the surface on the side the ray came from.
    pub(super) p: Vec3,
    /// Off the surface on the other side, where lights are sampled through a followed lobe
    /// that spreads transmitted light (rough glass); `None` where none is.
    pub(super) back: Option<Vec3>,
    /// The geometric and shading normals facing the ray.
    pub(super) ng: Vec3,
    pub(super) ns: Vec3,
    /// The medium the ray arrived in.
    pub(super) medium: Option<MediumId>,
}

/// Which sampled parts of a BSDF direct light is weighed against.
#[derive(Clone, Copy)]
pub(super) struct Sampled {
    pub(super) glossy: bool,
    pub(super) followed: bool,
}

/// How a light sample was drawn: which triangle of a mesh light (`None`: anywhere on the
/// light), one of how many draws, with what probability of picking the light.
#[derive(Clone, Copy, Debug)]
struct Drawn {
    part: Option<u32>,
    count: u32,
    probability: f32,
}

impl Integrator<'_> {
    /// Direct irradiance at `p` (diffuse hit `at` of the path): the mean of `light_samples`
    /// shadow-tested samples per area light and environment, stratified (see
    /// [`PathSampler::light_2d`]), and one per point, spot or distant light, which have
    /// nothing to stratify; past a few bounded lights, `light_samples` lights drawn from the
    /// light tree instead ([`crate::world::lights::sampler`]). As pbrt reflects light: from
    /// the side of the geometric normal `ng` the path came from, weighed by the cosine to the
    /// shading normal `ns` (a shading normal tilted far from the face, even lying in it, still
    /// sees that side's light).
    pub(super) fn direct(
        &self,
        p: Vec3,
        (ng, ns): (Vec3, Vec3),
        medium: Option<MediumId>,
        at: u32,
        sampler: &mut PathSampler,
    ) -> Vec3 {
        self.over_light_samples((p, ns), at, sampler, |light, drawn, u, sampler| {
            self.direct_from(light, drawn.part, p, (ng, ns), medium, u, sampler)
        })
    }

    /// The sum over the lights each hit samples one by one of the mean of their samples
    /// (`samples_of` each), plus, past a few bounded lights, the mean of `light_samples` draws
    /// from the light tree at `p` (shading normal `ns`), each over its probability: `sample`
    /// gives one sample `u` of a light as `Drawn` says. `hit` numbers the path's diffuse hit
    /// for the stratified pairs.
    fn over_light_samples(
        &self,
        (p, ns): (Vec3, Vec3),
        hit: u32,
        sampler: &mut PathSampler,
        mut sample: impl FnMut(&LightSource, Drawn, (f32, f32), &mut PathSampler) -> Vec3,
    ) -> Vec3 {
        let lights = &self.world.light_sampler;
        let mut total = Vec3::ZERO;
        for l in lights.one_by_one(self.world.light_sources.len()) {
            let light = &self.world.light_sources[l];
            let count = self.samples_of(light) as u32;
            let mut sum = Vec3::ZERO;
            for j in 0..count {
                let u = sampler.light_2d(hit, l, j, count);
                let drawn = Drawn {
                    part: None,
                    count,
                    probability: 1.0,
                };
                sum += sample(light, drawn, u, sampler);
            }
            total += sum / count as f32;
        }
        if lights.samples_every_light() {
            return total;
        }
        let draws = self.light_samples.max(1);
        let mut sum = Vec3::ZERO;
        for j in 0..draws {
            let pick = (j as f32 + sampler.rng.next_f32()) / draws as f32;
            let Some((part, pmf)) = lights.sample(p, ns, pick) else {
                continue;
            };
            let u = sampler.light_2d(hit, DRAWN_LIGHTS, j, draws);
            let drawn = Drawn {
                part: part.triangle,
                count: draws,
                probability: pmf,
            };
            sum += sample(&self.world.light_sources[part.light], drawn, u, sampler) / pmf;
        }
        total + sum / draws as f32
    }

    /// One shadow-tested sample `u` of the irradiance `light` (its triangle `part`, where
    /// drawn from the tree) gives [`Self::direct`].
    #[allow(clippy::too_many_arguments)]
    fn direct_from(
        &self,
        light: &LightSource,
        part: Option<u32>,
        p: Vec3,
        (ng, ns): (Vec3, Vec3),
        medium: Option<MediumId>,
        u: (f32, f32),
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let sample = if part.is_some() {
            light.sample_incident_part(p, ng, u, part)
        } else if ns.dot(ng) < SHADING_AGREEMENT_MIN_COS {
            light.sample_incident_wide(p, ng, u)
        } else {
            light.sample_incident(p, ng, u)
        };
        let Some(s) = sample else {
            return Vec3::ZERO;
        };
        if ng.dot(s.direction) <= 0.0 {
            return Vec3::ZERO;
        }
        let cos = ns.dot(s.direction).abs();
        // Stop short of the light's own surface.
        let tfar = s.distance * (1.0 - 1e-4);
        let seen = self.visibility(p, s.direction, tfar, medium, sampler);
        if seen != Vec3::ZERO {
            s.irradiance * cos * seen
        } else {
            Vec3::ZERO
        }
    }

    /// Shadow rays a light takes at each hit.
    pub(super) fn samples_of(&self, light: &LightSource) -> f32 {
        if light.is_delta() {
            1.0
        } else {
            self.light_samples.max(1) as f32
        }
    }

    /// Reflected direct radiance at `at`: every non-delta lobe by shadow rays (the followed
    /// lobes only when `followed_lit`), each `sampled` part's share weighed against its own
    /// samples. Light from the other side reaches the transmitting lobes by their own samples
    /// alone. Past a few bounded lights, `light_samples` lights drawn from the light tree.
    pub(super) fn direct_bsdf(
        &self,
        at: &At,
        bsdf: &Bsdf,
        sampled: Sampled,
        followed_lit: bool,
        diffuse_hit: u32,
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let lit = (bsdf, sampled, followed_lit);
        self.over_light_samples(
            (at.p, at.ns),
            diffuse_hit,
            sampler,
            |light, drawn, u, sampler| self.direct_sample(at, lit, light, drawn, u, sampler),
        )
    }

    /// One shadow-tested sample `u` of `light` for [`Self::direct_bsdf`], from the near side
    /// and (through the followed lobes) the far side, weighed against the BSDF's samples by
    /// the density of all `drawn.count` draws.
    fn direct_sample(
        &self,
        at: &At,
        (bsdf, sampled, followed_lit): (&Bsdf, Sampled, bool),
        light: &LightSource,
        drawn: Drawn,
        u: (f32, f32),
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let (p, n, wo) = (at.p, at.ns, at.wo);
        let mut sum = Vec3::ZERO;
        if let Some(back) = at.back {
            sum += self.through_back(at, bsdf, sampled, light, back, (drawn, u), sampler);
        }
        let Some(s) = light.sample_incident_part(p, n, u, drawn.part) else {
            return sum;
        };
        let wi = at.frame.to_local(s.direction);
        if wi.z * wo.z <= 0.0 {
            return sum;
        }
        let light_pdf = drawn.count as f32 * drawn.probability * s.pdf;
        let mut f = bsdf.f(wo, wi, Part::Broad);
        for (part, is_sampled, is_lit) in [
            (Part::Glossy, sampled.glossy, true),
            (Part::Followed, sampled.followed, followed_lit),
        ] {
            if !is_lit {
                continue;
            }
            let mut g = bsdf.f(wo, wi, part);
            if is_sampled && g != Vec3::ZERO {
                g *= balance(light_pdf, bsdf.pdf(wo, wi, part));
            }
            f += g;
        }
        if f.max_element() <= 0.0 {
            return sum;
        }
        let tfar = s.distance * (1.0 - 1e-4);
        let medium = self.medium_after(at.hit, s.direction, at.medium);
        let seen = self.visibility(p, s.direction, tfar, medium, sampler);
        if seen != Vec3::ZERO {
            sum += f * s.irradiance * wi.z.abs() * seen;
        }
        sum
    }

    /// One shadow-tested sample of `light` (drawn as `drawn` says) from the far side
    /// `back`, through the followed lobes that spread transmitted light, weighed against
    /// their own samples where they are sampled.
    #[allow(clippy::too_many_arguments)]
    fn through_back(
        &self,
        at: &At,
        bsdf: &Bsdf,
        sampled: Sampled,
        light: &LightSource,
        back: Vec3,
        (drawn, u): (Drawn, (f32, f32)),
        sampler: &mut PathSampler,
    ) -> Vec3 {
        let Some(s) = light.sample_incident_part(back, -at.ns, u, drawn.part) else {
            return Vec3::ZERO;
        };
        let wi = at.frame.to_local(s.direction);
        if wi.z * at.wo.z >= 0.0 {
            return Vec3::ZERO;
        }
        let mut f = bsdf.f(at.wo, wi, Part::Followed);
        if sampled.followed && f != Vec3::ZERO {
            let light_pdf = drawn.count as f32 * drawn.probability * s.pdf;
            f *= balance(light_pdf, bsdf.pdf(at.wo, wi, Part::Followed));
        }
        if f.max_element() <= 0.0 {
            return Vec3::ZERO;
        }
        let tfar = s.distance * (1.0 - 1e-4);
        let medium = self.medium_after(at.hit, s.direction, at.medium);
        let seen = self.visibility(back, s.direction, tfar, medium, sampler);
        if seen == Vec3::ZERO {
            return Vec3::ZERO;
        }
        f * s.irradiance * wi.z.abs() * seen
    }

    /// The balance-heuristic weight of a BSDF sample (along `dir` with solid-angle density
    /// `bsdf_pdf`, from `from` facing `facing`) that found the emitter `found`, against the light tree's draws
    /// at `at`, which pick its light (its triangle, for a mesh) with the tree's probability.
    pub(super) fn drawn_emitter_weight(
        &self,
        at: &At,
        (from, facing, dir): (Vec3, Vec3, Vec3),
        bsdf_pdf: f32,
        found: &Interaction,
    ) -> f32 {
        let Surface::Light(l) = found.surface else {
            return 1.0;
        };
        let light = &self.world.light_sources[l];
        let triangle = light.drawn_by_triangle().then_some(found.primitive);
        let light_pdf = light.incident_pdf_part(
            from,
            facing,
            (dir, found.t),
            found.geometric_normal,
            triangle,
        );
        let pick = self
            .world
            .light_sampler
            .pmf(at.p, at.ns, l, found.primitive);
        balance(
            bsdf_pdf,
            self.light_samples.max(1) as f32 * pick * light_pdf,
        )
    }
}
