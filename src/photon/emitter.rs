//! Where photon paths start: a light chosen in proportion to its power, a ray drawn from its
//! emission (aimed at the caustic targets for the caustic map, sent through the media more
//! often than their size alone would for the global map), each path from its own random
//! stream. Owns those choices; must not follow paths.

use crate::sampling::{Stream, StreamSeed};
use crate::world::lights::{self, Emission, LightEmitter};
use crate::world::{BoundingSphere, World};

use super::path::{MapKind, PathStart};

/// The share of the global photons from lights at infinity that start on the disc of the
/// media's bounds (the rest over the whole scene): a cloud far smaller than its scene would
/// otherwise catch few of them.
const MEDIA_SHARE: f32 = 0.5;

/// Splits photon paths among the lights in proportion to their power.
struct LightChooser {
    cdf: Vec<f32>,
    /// Probability of each light.
    pdf: Vec<f32>,
}

impl LightChooser {
    fn new(world: &World) -> Option<Self> {
        let w: Vec<f32> = (world.light_sources.iter())
            .map(|l| lights::weight(l.power()))
            .collect();
        let total: f32 = w.iter().sum();
        if total.is_nan() || total <= 0.0 || !total.is_finite() {
            return None;
        }
        let pdf: Vec<f32> = w.iter().map(|x| x / total).collect();
        let mut acc = 0.0;
        let cdf = pdf.iter().map(|p| {
            acc += p;
            acc
        });
        Some(Self {
            cdf: cdf.collect(),
            pdf,
        })
    }

    fn pick(&self, u: f32) -> usize {
        // The first light whose running total passes `u`: a binary search, for thousands.
        self.cdf
            .partition_point(|&c| c <= u)
            .min(self.cdf.len() - 1)
    }
}

/// How the paths of one pass start: which light, aimed where, with which random numbers.
pub(super) struct Emitter<'w> {
    pub(super) world: &'w World,
    chooser: LightChooser,
    /// One per light, in the scene's order.
    lights: Vec<LightEmitter>,
    streams: StreamSeed,
    ray_epsilon: f32,
}

impl<'w> Emitter<'w> {
    /// A pass's emitter: caustic photons aimed at the targets, through the world's caustic
    /// guide where it has one.
    pub(super) fn new(world: &'w World, kind: MapKind, seed: u64) -> Option<Self> {
        let targets = world.caustic_targets.as_slice();
        match kind {
            MapKind::Caustic => Self::with(world, targets, Stream::CausticPhotons, seed, true),
            MapKind::Global { .. } => Self::with(world, &[], Stream::GlobalPhotons, seed, false),
        }
    }

    /// The caustic guide's pilot paths: aimed, never guided, on their own stream.
    pub(super) fn pilots(world: &'w World, seed: u64) -> Option<Self> {
        let targets = world.caustic_targets.as_slice();
        Self::with(world, targets, Stream::CausticPilots, seed, false)
    }

    /// Paths from `stream`, aimed at `aim` (none: unaimed), through the world's caustic guide
    /// when `guided`.
    fn with(
        world: &'w World,
        aim: &[BoundingSphere],
        stream: Stream,
        seed: u64,
        guided: bool,
    ) -> Option<Self> {
        let lights = (world.light_sources.iter().enumerate())
            .map(|(l, light)| {
                let mut emitter = LightEmitter::new(light, aim);
                if stream == Stream::GlobalPhotons
                    && let Some(bounds) = world.media.as_ref().and_then(|m| m.bounds())
                {
                    emitter.share_with(&[(bounds, MEDIA_SHARE)]);
                }
                if let (true, Some(cells)) = (guided, world.caustic_guide.get(l).cloned().flatten())
                {
                    emitter.guide(cells);
                }
                emitter
            })
            .collect();
        Some(Self {
            world,
            chooser: LightChooser::new(world)?,
            lights,
            streams: StreamSeed::new(seed, stream),
            ray_epsilon: world.ray_epsilon(),
        })
    }

    /// Light `l`'s emitter.
    pub(super) fn light(&self, l: usize) -> &LightEmitter {
        &self.lights[l]
    }

    /// Path `index`: its generator (for the rest of the path) and first ray, or `None` when it
    /// carries no flux and so casts no ray.
    #[inline(always)]
    pub(super) fn start(&self, index: u64) -> Option<PathStart> {
        let mut rng = self.streams.rng(index);
        let l = self.chooser.pick(rng.next_f32());
        let Emission {
            origin,
            direction,
            flux,
        } = self.lights[l].emit(&mut rng);
        let flux = flux / self.chooser.pdf[l];
        (flux.max_element() > 0.0).then(|| PathStart {
            light: l,
            rng,
            // Just off the light: the first ray would otherwise hit the light's own surface.
            origin: origin + direction * self.ray_epsilon,
            direction,
            flux,
            medium: (self.world.media.as_ref()).and_then(|media| media.light(l)),
        })
    }
}
