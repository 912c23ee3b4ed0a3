//! The eye pass's integrator: Whitted-style recursion through mirrors and glass (Fresnel, total
//! internal reflection, each branch scaled by its tint) to a depth limit, rays that leave the
//! scene seeing the environment; at diffuse surfaces direct light by shadow rays, the
//! caustic map's estimate, and indirect light from the global map (final gathering, reading
//! the precomputed irradiance where there is one, or the map shown directly). Radiance comes back split into its direct, caustic and indirect parts,
//! the film's layers. Knows nothing of passes or pixels: a camera path brings its own
//! [`PathSampler`]. Owns shading; must not build maps or write images.

use super::gather::Reception;
use crate::bsdf::Part;
use crate::estimate::precomputed::ShownIrradiance;
use crate::estimate::{KnnEstimate, PrecomputedIrradiance, Query, RadianceEstimate, Scratch};
use crate::optics::{fresnel_dielectric, reflect, refract, scatter_dielectric};
use crate::photon::PhotonMap;
use crate::photon::volume::VolumeMaps;
use crate::sampling::{Frame, PathSampler};
use crate::scene::Material;
use crate::scene::MediumId;
use crate::world::{Interaction, Surface, World};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// Radiance along a camera path, by where the light last came from before the eye path's
/// diffuse hit: emitters and shadow rays (direct), the caustic map, the global map (indirect).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Radiance {
    pub direct: Vec3,
    pub caustic: Vec3,
    pub indirect: Vec3,
}

/// Where an eye ray starts: its point, and the unit geometric normal of the surface it
/// leaves (`None` at the camera), which bounds the medium the ray starts in.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayStart {
    pub point: Vec3,
    pub surface_normal: Option<Vec3>,
}

impl From<Vec3> for RayStart {
    fn from(point: Vec3) -> Self {
        Self {
            point,
            surface_normal: None,
        }
    }
}

impl RayStart {
    /// A ray spawned from a surface of geometric normal `ng`.
    pub fn on_surface(point: Vec3, ng: Vec3) -> Self {
        Self {
            point,
            surface_normal: Some(ng),
        }
    }
}

impl Radiance {
    pub fn total(&self) -> Vec3 {
        self.direct + self.caustic + self.indirect
    }
}

impl std::ops::Add for Radiance {
    type Output = Radiance;
    fn add(self, o: Radiance) -> Radiance {
        Radiance {
            direct: self.direct + o.direct,
            caustic: self.caustic + o.caustic,
            indirect: self.indirect + o.indirect,
        }
    }
}

impl std::ops::AddAssign for Radiance {
    fn add_assign(&mut self, o: Radiance) {
        *self = *self + o;
    }
}

/// Scaled channel by channel (a tint).
impl std::ops::Mul<Radiance> for Vec3 {
    type Output = Radiance;
    fn mul(self, r: Radiance) -> Radiance {
        Radiance {
            direct: self * r.direct,
            caustic: self * r.caustic,
            indirect: self * r.indirect,
        }
    }
}

impl std::ops::Mul<Radiance> for f32 {
    type Output = Radiance;
    fn mul(self, r: Radiance) -> Radiance {
        Vec3::splat(self) * r
    }
}

/// A photon map with the estimate that reads it.
#[derive(Clone, Copy)]
pub struct EstimatedMap<'a> {
    pub map: &'a PhotonMap,
    pub estimate: &'a dyn RadianceEstimate,
}

/// Path depth (bounces from the eye, as [`Integrator::trace`] counts them) below which a
/// Lambert hit whose global-map estimate is thick traces its indirect light on rather than
/// reading the map: past it the map is read anyway, its error then weighed down by this many
/// albedos.
pub const CLUTTER_DEPTH: u32 = 8;

/// How indirect diffuse light is found.
#[derive(Clone, Copy)]
pub enum Indirect<'a> {
    None,
    /// The global map's estimate at the eye ray's diffuse hit (it holds indirect photons only),
    /// read through `table` at Lambertian hits where the map is sparse. Where the estimate's
    /// photons lie on many surfaces at once ([`crate::estimate::THICK_GATHER`]) the path goes
    /// on instead, up to [`CLUTTER_DEPTH`], and reads the map where it is thin.
    Visualize {
        map: &'a PhotonMap,
        estimate: &'a KnnEstimate,
        table: Option<&'a ShownIrradiance>,
    },
    /// `rays` cosine-distributed gather rays, each reading the global map (which then holds
    /// every diffuse photon) where it lands: the nearest agreeing point of `precomputed` when
    /// there is one, else the map's estimate.
    FinalGather {
        map: EstimatedMap<'a>,
        rays: u32,
        precomputed: Option<&'a PrecomputedIrradiance>,
    },
}

#[derive(Clone, Copy)]
pub struct Integrator<'a> {
    pub world: &'a World,
    pub caustics: Option<EstimatedMap<'a>>,
    pub indirect: Indirect<'a>,
    /// Specular bounces followed from the eye.
    pub max_depth: u32,
    /// Shadow rays per area light (sphere, quad, mesh) and environment at each diffuse eye
    /// hit; a point, spot or distant light takes one.
    pub light_samples: u32,
    /// Glass hits at depth below this follow both rays; deeper ones follow one, chosen with
    /// the Fresnel reflectance as probability (the same expectation, fewer rays).
    pub glass_split_depth: u32,
    /// The volume photon maps read along camera segments in media (none without media).
    pub volume: VolumeMaps<'a>,
}

/// Whether a camera path counts the light it sees along its specular chain itself: the
/// emitters and the environment it meets before any diffuse surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Emission {
    Counted,
    /// Left to [`Integrator::emitted`]'s own samples of the pixel (see `render::emission`).
    Elsewhere,
    /// The path left a glossy lobe that reads the caustic map: light that reaches it through
    /// mirrors, glass and followed lobes alone (emitters seen, and direct light at followed
    /// lobes) is that map's, and only a surface that reads photons brings more.
    CausticMap,
}

impl Emission {
    /// Emitted radiance `e` that a camera path sees, as this mode counts it.
    #[inline]
    pub(super) fn counted(self, e: Vec3) -> Radiance {
        Radiance {
            direct: if self == Emission::Counted {
                e
            } else {
                Vec3::ZERO
            },
            ..Radiance::default()
        }
    }
}

impl Integrator<'_> {
    /// Radiance arriving at `origin` from direction `-dir` (unit `dir`).
    pub fn radiance(
        &self,
        origin: Vec3,
        dir: Vec3,
        depth: u32,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> Radiance {
        let medium = self.world.media.as_ref().and_then(|m| m.camera());
        self.trace(
            origin,
            dir,
            medium,
            depth,
            Emission::Counted,
            sampler,
            scratch,
        )
    }

    /// [`Integrator::radiance`] from a ray in `medium`, counting the emitters and
    /// environment seen along the specular chain or not.
    #[allow(clippy::too_many_arguments)]
    pub fn trace(
        &self,
        start: impl Into<RayStart>,
        dir: Vec3,
        medium: Option<MediumId>,
        depth: u32,
        emission: Emission,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> Radiance {
        let counted = |e: Vec3| emission.counted(e);
        let start = start.into();
        let origin = start.point;
        let hit = self.world.intersect(origin, dir, 0.0, f32::INFINITY);
        if self.world.media.is_none() {
            let Some(hit) = hit else {
                return counted(self.world.background(dir));
            };
            return self.shade(&hit, dir, None, depth, emission, sampler, scratch);
        }
        let through = self.through_media(start, dir, hit.as_ref(), medium, depth, sampler, scratch);
        if through.transmittance == Vec3::ZERO {
            return through.in_scattered;
        }
        let seen = match hit {
            None => counted(self.world.background(dir)),
            Some(hit) => {
                let medium = through.medium_at_end;
                self.shade(&hit, dir, medium, depth, emission, sampler, scratch)
            }
        };
        through.in_scattered + through.transmittance * seen
    }

    /// Radiance leaving `hit` back along the ray `dir` that found it in `medium`.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn shade(
        &self,
        hit: &Interaction,
        dir: Vec3,
        medium: Option<MediumId>,
        depth: u32,
        emission: Emission,
        sampler: &mut PathSampler,
        scratch: &mut Scratch,
    ) -> Radiance {
        let counted = |e: Vec3| emission.counted(e);
        let m = match hit.surface {
            Surface::Light(l) => {
                let light = &self.world.light_sources[l];
                return counted(light.emitted_radiance(-dir.dot(hit.geometric_normal)));
            }
            Surface::Material(m) => m,
        };
        let transport = self.world.description.transport;
        if !transport.shades(depth) {
            // Past the scene's cap only emitters seen count.
            return Radiance::default();
        }
        let (ng, ns) = hit.facing(dir);
        match &self.world.material_at(m, hit) {
            Material::Bsdf(model) => {
                self.shade_bsdf(hit, model, (dir, medium), depth, emission, sampler, scratch)
            }
            Material::Diffuse { albedo } => {
                let p = self.world.offset_from(hit, ng);
                let query = Query {
                    position: hit.position,
                    normal: ns,
                };
                let brdf = *albedo * FRAC_1_PI;
                let at = sampler.next_diffuse_hit();
                let reception = Reception::Lambert(*albedo);
                let seen_from = self.medium_after(hit, ng, medium);
                let direct = brdf * self.direct(p, (ng, ns), seen_from, at, sampler);
                if !transport.reads_photons(depth) {
                    return Radiance {
                        direct,
                        ..Radiance::default()
                    };
                }
                Radiance {
                    direct,
                    caustic: self.caustic(&reception, &query, scratch),
                    indirect: self.indirect(
                        &reception,
                        (p, seen_from),
                        (ng, ns, -dir),
                        at,
                        depth,
                        &query,
                        sampler,
                        scratch,
                    ),
                }
            }
            Material::Mirror { tint } if depth < self.max_depth => {
                let r = reflect(dir, ns);
                *tint
                    * self.trace(
                        RayStart::on_surface(self.world.spawn_from(hit, ng, r), ng),
                        r,
                        self.medium_after(hit, r, medium),
                        depth + 1,
                        emission,
                        sampler,
                        scratch,
                    )
            }
            Material::Glass {
                ior,
                reflect_tint,
                transmit_tint,
            } if depth < self.max_depth => {
                let entering = hit.entering(dir);
                let eta = if entering { 1.0 / ior } else { *ior };
                let f = fresnel_dielectric(-dir.dot(ns), eta);
                let r = reflect(dir, ns);
                if depth >= self.glass_split_depth {
                    // One ray: reflection with probability F (always under total internal
                    // reflection), else refraction, each with weight 1 times its tint.
                    let refracted = refract(dir, ns, eta).filter(|_| f < 1.0);
                    let (next, tint) = match refracted {
                        Some(t) if sampler.rng.next_f32() >= f => (t, transmit_tint),
                        _ => (r, reflect_tint),
                    };
                    return *tint
                        * self.trace(
                            RayStart::on_surface(self.world.spawn_from(hit, ng, next), ng),
                            next,
                            self.medium_after(hit, next, medium),
                            depth + 1,
                            emission,
                            sampler,
                            scratch,
                        );
                }
                let mut l = (f * *reflect_tint)
                    * self.trace(
                        RayStart::on_surface(self.world.spawn_from(hit, ng, r), ng),
                        r,
                        self.medium_after(hit, r, medium),
                        depth + 1,
                        emission,
                        sampler,
                        scratch,
                    );
                if let Some(t) = refract(dir, ns, eta).filter(|_| f < 1.0) {
                    l += ((1.0 - f) * *transmit_tint)
                        * self.trace(
                            RayStart::on_surface(self.world.spawn_from(hit, ng, t), ng),
                            t,
                            self.medium_after(hit, t, medium),
                            depth + 1,
                            emission,
                            sampler,
                            scratch,
                        );
                }
                l
            }
            _ => Radiance::default(),
        }
    }

    /// The emitted radiance (emitters and environment) seen from `origin` along `dir` through
    /// mirrors and glass, nothing past a diffuse surface: the part of [`Integrator::radiance`]
    /// that [`Emission::Elsewhere`] leaves out. One path, chosen at each glass hit with the
    /// Fresnel reflectance as probability: a few rays and no estimate, where a split path
    /// costs a tree of rays (measured on the torus knot: split, 16 samples took 2.3× the
    /// pass time for no less error), so a pixel can take many to resolve a light's image
    /// smaller than itself.
    pub fn emitted(&self, mut origin: Vec3, mut dir: Vec3, rng: &mut crate::sampling::Rng) -> Vec3 {
        let mut throughput = Vec3::ONE;
        let mut medium = self.world.media.as_ref().and_then(|m| m.camera());
        for _ in 0..=self.max_depth {
            let hit = self.world.intersect(origin, dir, 0.0, f32::INFINITY);
            let (tr, end) = self.across_media((origin, dir), hit.as_ref(), medium, rng);
            (throughput, medium) = (throughput * tr, end);
            let Some(hit) = hit else {
                return throughput * self.world.background(dir);
            };
            let m = match hit.surface {
                Surface::Light(l) => {
                    let light = &self.world.light_sources[l];
                    return throughput * light.emitted_radiance(-dir.dot(hit.geometric_normal));
                }
                Surface::Material(m) => m,
            };
            let (ng, ns) = hit.facing(dir);
            let material = &self.world.material_at(m, &hit);
            let Some((next, tint)) = sampled_specular(self.world, material, &hit, dir, ns, rng)
            else {
                return Vec3::ZERO;
            };
            throughput *= tint;
            medium = self.medium_after(&hit, next, medium);
            origin = self.world.spawn_from(&hit, ng, next);
            dir = next;
        }
        Vec3::ZERO
    }

    /// What [`Self::emitted`] sees, and which chain it saw it along: the reflect (0) and
    /// refract (1) choices as a pilot's branch code (0 where a BSDF's delta lobe or depth made
    /// it no pilot's), and the probability that chain's choices had at their film point. With
    /// `along` the choices are not drawn but those of that code, and the chain ends after its
    /// last choice: it sees only a light or the environment there.
    pub fn emitted_chain(
        &self,
        mut origin: Vec3,
        mut dir: Vec3,
        rng: &mut crate::sampling::Rng,
        along: Option<u64>,
    ) -> EmittedChain {
        let mut chain = EmittedChain {
            value: Vec3::ZERO,
            code: 1,
            probability: 1.0,
        };
        let mut throughput = Vec3::ONE;
        let mut forced = along.map(super::light_images::chain_choices);
        let bounces = forced.as_ref().map_or(self.max_depth, |c| c.len() as u32);
        let mut medium = self.world.media.as_ref().and_then(|m| m.camera());
        for bounce in 0..=bounces {
            // A forced chain sees only what its last ray meets: a shorter chain is another
            // chain, which the forced strategy never samples.
            let early = forced.is_some() && bounce < bounces;
            let hit = self.world.intersect(origin, dir, 0.0, f32::INFINITY);
            let (tr, end) = self.across_media((origin, dir), hit.as_ref(), medium, rng);
            (throughput, medium) = (throughput * tr, end);
            if early
                && hit
                    .as_ref()
                    .is_none_or(|h| matches!(h.surface, Surface::Light(_)))
            {
                return chain;
            }
            let Some(hit) = hit else {
                chain.value = throughput * self.world.background(dir);
                return chain;
            };
            let m = match hit.surface {
                Surface::Light(l) => {
                    let light = &self.world.light_sources[l];
                    chain.value =
                        throughput * light.emitted_radiance(-dir.dot(hit.geometric_normal));
                    return chain;
                }
                Surface::Material(m) => m,
            };
            if bounce == bounces {
                break;
            }
            let (ng, ns) = hit.facing(dir);
            let material = &self.world.material_at(m, &hit);
            let (next, tint, refracts) = if let Some(choices) = forced.as_mut() {
                let refracts = choices.next().unwrap_or(false);
                let Some((next, tint, p)) = chosen_specular(material, &hit, dir, ns, refracts)
                else {
                    return chain;
                };
                chain.probability *= p;
                (next, tint, refracts)
            } else {
                let Some((next, tint)) = sampled_specular(self.world, material, &hit, dir, ns, rng)
                else {
                    return chain;
                };
                let refracts = next.dot(ns) * dir.dot(ns) > 0.0;
                match material {
                    Material::Mirror { .. } => {}
                    Material::Glass { ior, .. } => {
                        let eta = if hit.entering(dir) { 1.0 / ior } else { *ior };
                        let f = fresnel_dielectric(-dir.dot(ns), eta);
                        chain.probability *= if refracts { 1.0 - f } else { f };
                    }
                    // No pilot follows a BSDF's lobes.
                    _ => chain.code = 0,
                }
                (next, tint, refracts)
            };
            if chain.code != 0 {
                chain.code = if chain.code.leading_zeros() == 0 {
                    0
                } else {
                    chain.code << 1 | u64::from(refracts)
                };
            }
            throughput *= tint;
            medium = self.medium_after(&hit, next, medium);
            origin = self.world.spawn_from(&hit, ng, next);
            dir = next;
        }
        chain
    }
}

/// The light one emission sample saw, and along which chain ([`Integrator::emitted_chain`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmittedChain {
    /// Radiance times the chain's tints, not divided by its probability.
    pub value: Vec3,
    pub code: u64,
    pub probability: f32,
}

/// Where a chain that meets `material` at `hit` along `dir` (shading normal `ns`, facing the
/// ray) goes on when it takes the choice `refracts`, the tint it takes, and the probability
/// [`sampled_specular`] gives that choice (the Fresnel reflectance or its complement; 1 at
/// a mirror). `None` where the choice cannot be taken: a mirror asked to refract, total
/// internal reflection, a surface neither mirror nor glass.
pub(super) fn chosen_specular(
    material: &Material,
    hit: &crate::world::Interaction,
    dir: Vec3,
    ns: Vec3,
    refracts: bool,
) -> Option<(Vec3, Vec3, f32)> {
    match material {
        Material::Mirror { tint } if !refracts => Some((reflect(dir, ns), *tint, 1.0)),
        Material::Glass {
            ior,
            reflect_tint,
            transmit_tint,
        } => {
            let eta = if hit.entering(dir) { 1.0 / ior } else { *ior };
            let f = fresnel_dielectric(-dir.dot(ns), eta);
            if refracts {
                Some((refract(dir, ns, eta)?, *transmit_tint, 1.0 - f))
            } else {
                Some((reflect(dir, ns), *reflect_tint, f))
            }
        }
        _ => None,
    }
}

/// Where a path that meets `material` at `hit` along `dir` (shading normal `ns`, facing the
/// ray) goes on, and the tint it takes: a mirror reflects; glass reflects or refracts, one
/// branch chosen with the Fresnel reflectance as probability. `None` at a diffuse surface.
pub(super) fn sampled_specular(
    world: &World,
    material: &Material,
    hit: &crate::world::Interaction,
    dir: Vec3,
    ns: Vec3,
    rng: &mut crate::sampling::Rng,
) -> Option<(Vec3, Vec3)> {
    match material {
        // `World::material_at` never gives a mix.
        Material::Diffuse { .. } | Material::Mix { .. } => None,
        // Its delta lobes only: what a non-delta lobe sees is the camera path's own business.
        Material::Bsdf(model) => {
            let frame = Frame::new(hit.shading_normal);
            let s = world.bsdf(model).sample(
                frame.to_local(-dir),
                rng.next_f32(),
                rng.next_2d(),
                Part::Followed,
            )?;
            s.delta
                .then(|| (frame.to_world(s.wi), s.f * (s.wi.z.abs() / s.pdf)))
        }
        Material::Mirror { tint } => Some((reflect(dir, ns), *tint)),
        Material::Glass {
            ior,
            reflect_tint,
            transmit_tint,
        } => {
            let eta = if hit.entering(dir) { 1.0 / ior } else { *ior };
            let (next, branch) = scatter_dielectric(dir, ns, eta, rng.next_f32());
            Some((next, branch.pick(*reflect_tint, *transmit_tint)))
        }
    }
}
