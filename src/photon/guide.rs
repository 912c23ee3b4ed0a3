//! Learning where a render's aimed caustic photons do most good (importance-driven emission, in
//! the spirit of Peter and Pietrek's importance-driven photon maps, 1998): pilot paths traced
//! once per render on their own stream, so that every pass, thread count and machine sees the
//! same guide; their landings valued by the caller (`render::caustic_guide` weighs a landing by
//! what the image shows there, asking the pilots' own photons for the caustic light); and the
//! values tallied per cone cell of the light each path left ([`crate::world::aim_guide`]), in
//! fixed runs of paths summed in order. Owns the pilot paths and their caustic irradiance; must
//! not decide what a landing is worth, nor shade.

use super::tracer::{Emitter, LivePath, MapKind, NoRayLog, TracedPhoton, trace_path};
use super::{KdTree, Neighbours, Photon};
use crate::world::World;
use crate::world::aim::PreparedUnion;
use crate::world::aim_guide::{AimedCones, CELLS, ConeCells, GuideTally};
use glam::Vec3;
use rayon::prelude::*;
use std::sync::Arc;

/// Photons in the pilots' caustic irradiance at a landing (the landing's own included).
const NEIGHBOURS: usize = 16;

/// The farthest a landing's neighbours are looked for, as a fraction of the scene's diagonal:
/// a lone photon on a wide floor is as dim as the pilots can tell at that.
const REACH: f32 = 0.01;

/// Pilot paths a cone cell gets at most. On the metal ring's 512 cells, 25,000 to 50,000
/// pilots (49 to 98 a cell) gave the same error; more only cost time (BENCHMARKS.md).
pub const PILOTS_PER_CELL: u64 = 128;

/// Paths per parallel task.
const CHUNK: u64 = 4096;

/// Where a pilot path stored its caustic photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Landing {
    pub position: Vec3,
    /// The surface normal on the side the photon arrived from.
    pub normal: Vec3,
}

/// What learning found.
#[derive(Clone, Debug, Default)]
pub struct LearntGuide {
    /// Per light in the scene's order: its cells, or `None` where it stays unguided (not aimed
    /// from one point, or nothing its pilots found was worth anything).
    pub cells: Vec<Option<Arc<ConeCells>>>,
    /// Pilot paths traced and caustic photons they stored.
    pub paths: u64,
    pub landings: u64,
}

impl LearntGuide {
    /// Lights that are guided.
    pub fn guided_lights(&self) -> usize {
        self.cells.iter().flatten().count()
    }
}

/// Traces `paths` pilot caustic paths (aimed, unguided), has `worth` value their landings
/// (one number per landing, ≥ 0; the pilots' photons give the caustic light there), and
/// learns each aimed light's cells from them. At most [`PILOTS_PER_CELL`] paths a cell of the
/// aimed lights' cones are traced: a light aimed at two spheres has 128 cells, and 50,000
/// pilots would cost it a sixth of a pass for nothing more. No guide for a scene without
/// caustic targets or lights aimed from one point.
pub fn learn_caustic_guide(
    world: &World,
    seed: u64,
    paths: u64,
    worth: impl FnOnce(&[Landing], &PilotPhotons) -> Vec<f64>,
) -> LearntGuide {
    let none = LearntGuide::default();
    if world.caustic_targets.is_empty() || paths == 0 {
        return none;
    }
    let Some(emitter) = Emitter::pilots(world, seed) else {
        return none;
    };
    // Each light's cones, where it aims from one point.
    let unions: Vec<Option<&PreparedUnion>> = (0..world.light_sources.len())
        .map(|l| emitter.light(l).aimed_cones().map(AimedCones::union))
        .collect();
    if unions.iter().all(Option::is_none) {
        return none;
    }
    let cells: usize = unions.iter().flatten().map(|u| u.len() * CELLS).sum();
    let paths = paths.min(PILOTS_PER_CELL * cells as u64);
    // Per path: its light, first direction and the photon it stored, in path order.
    let traced: Vec<(usize, Vec3, Option<TracedPhoton>)> = (0..paths.div_ceil(CHUNK))
        .into_par_iter()
        .flat_map_iter(|c| {
            let mut stored = Vec::new();
            let mut out = Vec::with_capacity(CHUNK as usize);
            for path in c * CHUNK..((c + 1) * CHUNK).min(paths) {
                let Some(start) = emitter.start(path) else {
                    continue;
                };
                let (light, direction) = (start.light, start.direction);
                stored.clear();
                let live = LivePath::new(0, start);
                trace_path(world, MapKind::Caustic, live, &mut stored, &mut NoRayLog);
                out.push((light, direction, stored.first().copied()));
            }
            out
        })
        .collect();
    let scale = 1.0 / paths as f32;
    // Position, normal and power (mean over the channels) of each photon.
    let photons: Vec<(Vec3, Vec3, f32)> = (traced.iter())
        .filter_map(|(_, _, p)| {
            let p = p.as_ref()?;
            let photon = Photon::with_directions(p.position, p.flux * scale, p.directions);
            Some((
                p.position,
                photon.normal(),
                photon.power().element_sum() / 3.0,
            ))
        })
        .collect();
    let landings: Vec<Landing> = (photons.iter())
        .map(|&(position, normal, _)| Landing { position, normal })
        .collect();
    let pilots = PilotPhotons::new(&photons, REACH * world.scale);
    let values = worth(&landings, &pilots);
    assert_eq!(values.len(), landings.len(), "one worth per landing");
    // Each path's worth: its landing's, or nothing where it stored no photon.
    let mut next = values.iter();
    let paths_worth: Vec<f64> = (traced.iter())
        .map(|(_, _, photon)| match photon {
            Some(_) => next.next().map_or(0.0, |v| v.max(0.0)),
            None => 0.0,
        })
        .collect();
    // Tallied in fixed runs of paths and summed in their order: the same sums whatever the
    // thread count.
    let fresh =
        || -> Vec<Option<GuideTally>> { unions.iter().map(|u| u.map(GuideTally::new)).collect() };
    let runs: Vec<Vec<Option<GuideTally>>> = (traced.par_chunks(CHUNK as usize))
        .zip(paths_worth.par_chunks(CHUNK as usize))
        .map(|(paths, worth)| {
            let mut tallies = fresh();
            for ((light, direction, _), &value) in paths.iter().zip(worth) {
                if let (Some(tally), Some(union)) = (&mut tallies[*light], unions[*light]) {
                    tally.add(union, *direction, value);
                }
            }
            tallies
        })
        .collect();
    let mut tallies = fresh();
    for run in &runs {
        for (total, part) in tallies.iter_mut().zip(run) {
            if let (Some(total), Some(part)) = (total, part) {
                total.merge(part);
            }
        }
    }
    let cells = (tallies.iter().zip(&unions))
        .map(|(tally, union)| ConeCells::learn((*union)?, tally.as_ref()?).map(Arc::new))
        .collect();
    LearntGuide {
        cells,
        paths,
        landings: landings.len() as u64,
    }
}

/// The pilots' caustic photons, for the caustic irradiance they give near a landing.
pub struct PilotPhotons {
    tree: KdTree,
    /// Power (mean over the channels) of each photon, by source index.
    power: Vec<f32>,
    reach: f32,
}

impl PilotPhotons {
    fn new(photons: &[(Vec3, Vec3, f32)], reach: f32) -> Self {
        let positions: Vec<Vec3> = photons.iter().map(|p| p.0).collect();
        Self {
            tree: KdTree::build(&positions),
            power: photons.iter().map(|p| p.2).collect(),
            reach,
        }
    }

    /// Caustic irradiance at `position` (W/m², mean over the channels): the power of the
    /// [`NEIGHBOURS`] nearest pilot photons over their disc, the farthest left out as the k-NN
    /// estimates do; with fewer within the reach, theirs over the reach's disc.
    pub fn caustic_irradiance(&self, position: Vec3, found: &mut Neighbours) -> f32 {
        let k = NEIGHBOURS.min(self.power.len());
        if k == 0 {
            return 0.0;
        }
        self.tree
            .k_nearest(position, k, self.reach * self.reach, found);
        let (far, full) = match found.farthest() {
            Some(f) if found.len() == k && f.dist2 > 0.0 => (f.dist2, true),
            _ => (self.reach * self.reach, false),
        };
        let power: f32 = (found.as_slice().iter())
            .filter(|n| n.dist2 < far || !full)
            .map(|n| self.power[self.tree.source_index(n.slot as usize) as usize])
            .sum();
        power / (std::f32::consts::PI * far)
    }
}
