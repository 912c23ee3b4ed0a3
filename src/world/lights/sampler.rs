//! Which lights a shading point samples. With a few bounded lights every point samples every
//! light, as it always did; past [`SAMPLE_EVERY_LIGHT_MAX`] of them a point draws its shadow
//! rays' lights from the light tree instead ([`super::tree`]), each draw weighed by one over
//! its probability, so a point's cost no longer grows with the lights. Lights at infinity
//! (distant, environments) are sampled at every point either way: they reach everything
//! alike and a tree cannot rank them. Owns that choice and the map from tree entries to
//! lights and mesh triangles; must not sample points on lights or trace rays.

use super::LightSource;
use super::tree::LightTree;
use glam::Vec3;

/// Bounded lights up to which every shading point samples each of them.
pub const SAMPLE_EVERY_LIGHT_MAX: usize = 8;

/// One light drawn from the tree: the light, and the triangle of a mesh light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LightPart {
    pub light: usize,
    pub triangle: Option<u32>,
}

/// How a world's lights are chosen at a shading point.
#[derive(Clone, Debug, Default)]
pub struct LightSampler {
    drawn: Option<Drawn>,
}

#[derive(Clone, Debug)]
struct Drawn {
    tree: LightTree,
    /// What each tree entry is.
    parts: Vec<LightPart>,
    /// Each light's first entry (`u32::MAX` for a light at infinity).
    first_entry: Vec<u32>,
    /// The lights at infinity, sampled at every point.
    everywhere: Vec<usize>,
    /// The bounded lights' powers summed up to and including each light, over the total
    /// (lights at infinity add nothing).
    power_cdf: Vec<f32>,
}

impl LightSampler {
    pub fn new(lights: &[LightSource]) -> Self {
        Self::with_limit(lights, SAMPLE_EVERY_LIGHT_MAX)
    }

    /// A tree once more than `every_light_max` lights are bounded.
    pub fn with_limit(lights: &[LightSource], every_light_max: usize) -> Self {
        let entries: Vec<_> = lights.iter().map(LightSource::tree_entries).collect();
        let bounded = entries.iter().filter(|e| !e.is_empty()).count();
        if bounded <= every_light_max {
            return Self::default();
        }
        let mut parts = Vec::new();
        let mut bounds = Vec::new();
        let mut first_entry = Vec::with_capacity(lights.len());
        let mut everywhere = Vec::new();
        for (l, (light, e)) in lights.iter().zip(entries).enumerate() {
            if e.is_empty() {
                first_entry.push(u32::MAX);
                everywhere.push(l);
                continue;
            }
            first_entry.push(parts.len() as u32);
            let mesh = light.drawn_by_triangle();
            parts.extend((0..e.len()).map(|k| LightPart {
                light: l,
                triangle: mesh.then_some(k as u32),
            }));
            bounds.extend(e);
        }
        let Some(tree) = LightTree::build(&bounds) else {
            return Self::default();
        };
        let powers: Vec<f64> = (lights.iter().zip(&first_entry))
            .map(|(light, &first)| match first {
                u32::MAX => 0.0,
                _ => f64::from(super::weight(light.power())),
            })
            .collect();
        let total: f64 = powers.iter().sum();
        let mut running = 0.0;
        let power_cdf = (powers.iter())
            .map(|p| {
                running += p;
                (running / total) as f32
            })
            .collect();
        Self {
            drawn: Some(Drawn {
                tree,
                parts,
                first_entry,
                everywhere,
                power_cdf,
            }),
        }
    }

    /// Whether every point samples every light (no tree).
    pub fn samples_every_light(&self) -> bool {
        self.drawn.is_none()
    }

    /// The lights each point samples one by one (`lights` in all): every light without a
    /// tree, the lights at infinity with one.
    pub fn one_by_one(&self, lights: usize) -> impl Iterator<Item = usize> + '_ {
        let every = if self.samples_every_light() {
            lights
        } else {
            0
        };
        (0..every).chain(self.everywhere().iter().copied())
    }

    /// The lights sampled at every point even with a tree: those at infinity.
    pub fn everywhere(&self) -> &[usize] {
        self.drawn.as_ref().map_or(&[], |d| &d.everywhere)
    }

    /// One light (or mesh triangle) for the point `p` with unit normal `n` (zero inside a
    /// medium), drawn with `u` in [0, 1), and its probability; `None` without a tree or
    /// where no bounded light can reach `p`.
    pub fn sample(&self, p: Vec3, n: Vec3, u: f32) -> Option<(LightPart, f32)> {
        let drawn = self.drawn.as_ref()?;
        let (entry, pmf) = drawn.tree.sample(p, n, u)?;
        Some((drawn.parts[entry], pmf))
    }

    /// The probability [`Self::sample`] at `p` (normal `n`) draws `light` (its triangle
    /// `triangle` where it is a mesh); 1 without a tree or for a light at infinity, which
    /// every point samples.
    pub fn pmf(&self, p: Vec3, n: Vec3, light: usize, triangle: u32) -> f32 {
        let Some(drawn) = &self.drawn else {
            return 1.0;
        };
        let first = drawn.first_entry[light];
        if first == u32::MAX {
            return 1.0;
        }
        let entry = match drawn.parts[first as usize].triangle {
            Some(_) => first as usize + triangle as usize,
            None => first as usize,
        };
        match drawn.parts.get(entry) {
            Some(part) if part.light == light => drawn.tree.pmf(p, n, entry),
            _ => 0.0,
        }
    }

    /// One bounded light drawn in proportion to its power with `u` in [0, 1), and its
    /// probability; `None` without a tree.
    pub fn sample_by_power(&self, u: f32) -> Option<(usize, f32)> {
        let cdf = &self.drawn.as_ref()?.power_cdf;
        let l = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
        let below = if l == 0 { 0.0 } else { cdf[l - 1] };
        let probability = cdf[l] - below;
        (probability > 0.0).then_some((l, probability))
    }

    /// Nodes in the tree (0 without one).
    pub fn tree_nodes(&self) -> usize {
        self.drawn.as_ref().map_or(0, |d| d.tree.len())
    }
}
