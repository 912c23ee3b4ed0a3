//! Where, within the cones towards its targets, an aimed light sends its caustic photons: a
//! piecewise-constant density over cells of equal solid angle in every cone of the light's
//! union ([`SIDE`] rings of cos θ by [`SIDE`] sectors of φ), learnt once per render from
//! pilot paths (`photon::guide`, valued by `render::caustic_guide`). Owns the cells, their
//! probabilities, the density of a direction drawn from them and the tally that learns them;
//! must not trace rays or decide what a photon is worth.
//!
//! Unbiased whatever the table says: every cell keeps a probability above zero (a share of the
//! photons, [`UNIFORM_SHARE`], is drawn as unguided ones are), a direction's density is summed
//! over every cone that holds it (as the unguided union's is), and the photon carries one over
//! that density. The table only moves photons: from cells whose paths miss or land where the
//! image is bright (the caustic's own peak, directly lit floor) to cells whose photons land
//! where it is dim, so that the estimate's relative error evens out over the picture.

use super::aim::PreparedUnion;
use crate::sampling::{ConeFrame, Rng};
use glam::Vec3;
use std::sync::Arc;

/// Rings and sectors per cone: 64 cells a cone, 512 for a light aimed at eight targets. Finer
/// cells learnt from as many pilots are noisier, and were no better on the metal ring (16 a side
/// with 100k pilots, 32 with 400k; BENCHMARKS.md, "The caustic guide's cost").
pub const SIDE: usize = 8;
/// Cells per cone.
pub const CELLS: usize = SIDE * SIDE;

/// The share of photons still drawn as unguided ones are (uniformly over the union): a guided
/// photon carries at most 1/UNIFORM_SHARE times an unguided one's flux wherever it lands, so a
/// cell the pilots misjudged (coarse cells straddle a caustic's bright and dim parts) cannot
/// send a photon that stands out as a bright blot, and no direction is ever left out.
pub const UNIFORM_SHARE: f64 = 0.4;

/// A light's union of cones towards its targets, and the cells that guide it once learnt.
#[derive(Clone, Debug)]
pub struct AimedCones {
    union: PreparedUnion,
    cells: Option<Arc<ConeCells>>,
}

impl AimedCones {
    /// The union, unguided: directions drawn uniformly from it.
    pub fn new(union: PreparedUnion) -> Self {
        Self { union, cells: None }
    }

    pub fn union(&self) -> &PreparedUnion {
        &self.union
    }

    /// Draw from `cells` (learnt on this union) from now on.
    pub fn guide(&mut self, cells: Arc<ConeCells>) {
        assert_eq!(
            cells.probability.len(),
            self.union.len() * CELLS,
            "cells learnt on another union"
        );
        self.cells = Some(cells);
    }

    /// A direction towards the targets and the reciprocal of its density.
    #[inline(always)]
    pub fn sample(&self, rng: &mut Rng) -> (Vec3, f32) {
        match &self.cells {
            Some(cells) => cells.sample(&self.union, rng),
            None => self.union.sample(rng),
        }
    }
}

/// Cell `(ring, sector)` of `direction` in the cone of `frame`, as an index below [`CELLS`]:
/// the cell whose numbers [`ConeFrame::sample`] turns into it. A guided photon asks this of
/// every other cone that holds its direction, so the sector is found without an arctangent.
#[inline(always)]
fn cell_in(frame: &ConeFrame, direction: Vec3) -> usize {
    let (x, y) = frame.tangent(direction);
    let ring = ((frame.first_coordinate(x, y) * SIDE as f32) as usize).min(SIDE - 1);
    ring * SIDE + octant(x, y)
}

/// Which eighth of a turn, counted from +x towards +y, the angle of (`x`, `y`) falls in: the
/// sector of a cone cell, since there are eight ([`SIDE`]).
#[inline(always)]
fn octant(x: f32, y: f32) -> usize {
    const _: () = assert!(SIDE == 8, "sectors are octants");
    if y > 0.0 || (y == 0.0 && x >= 0.0) {
        // [0, ½) turn.
        match (x > 0.0, y < x.abs()) {
            (true, true) => 0,
            (true, false) => 1,
            (false, false) => 2,
            (false, true) => 3,
        }
    } else {
        // [½, 1) turn.
        match (x < 0.0, -y < x.abs()) {
            (true, true) => 4,
            (true, false) => 5,
            (false, false) => 6,
            (false, true) => 7,
        }
    }
}

/// Pilot photons' worth summed per cell of one light's cones: a direction counts in every cone
/// that holds it, so overlapping cones learn from each other's pilots.
#[derive(Clone, Debug)]
pub struct GuideTally {
    worth: Vec<f64>,
    count: Vec<u64>,
}

impl GuideTally {
    pub fn new(union: &PreparedUnion) -> Self {
        let cells = union.len() * CELLS;
        Self {
            worth: vec![0.0; cells],
            count: vec![0; cells],
        }
    }

    /// A pilot path that left along `direction` (drawn from `union`, unguided) and whose photon
    /// is worth `worth` (0 where it stored none).
    pub fn add(&mut self, union: &PreparedUnion, direction: Vec3, worth: f64) {
        for k in 0..union.len() {
            if union.holds(k, direction) {
                let e = k * CELLS + cell_in(union.frame(k), direction);
                self.worth[e] += worth;
                self.count[e] += 1;
            }
        }
    }

    /// Adds another tally of the same union.
    pub fn merge(&mut self, other: &GuideTally) {
        for (a, b) in self.worth.iter_mut().zip(&other.worth) {
            *a += b;
        }
        for (a, b) in self.count.iter_mut().zip(&other.count) {
            *a += b;
        }
    }

    /// Pilot paths tallied, over all cells (a path in two cones counts twice).
    pub fn samples(&self) -> u64 {
        self.count.iter().sum()
    }
}

/// The learnt density over one light's cone cells.
#[derive(Clone, Debug, PartialEq)]
pub struct ConeCells {
    /// Probability of cell (cone k, ring i, sector j), at `k · SIDE² + i · SIDE + j`.
    probability: Vec<f32>,
    /// Probabilities summed up to and including each cell.
    cumulative: Vec<f32>,
    /// Per cone, cells over its solid angle: a cell's probability times this is the density
    /// it gives a direction in it.
    cells_per_steradian: Vec<f32>,
}

impl ConeCells {
    /// The density that draws [`UNIFORM_SHARE`] of the photons as the unguided union does and
    /// the rest in proportion to each cell's share of the union times its mean worth; a cell
    /// without pilots counts at the mean. `None` when no pilot path found anything worth
    /// anything: the light stays unguided.
    pub fn learn(union: &PreparedUnion, tally: &GuideTally) -> Option<Self> {
        let cones = union.len();
        assert_eq!(tally.worth.len(), cones * CELLS, "a tally of another union");
        let share = |e: usize| f64::from(union.solid_angle_of(e / CELLS)) / CELLS as f64;
        let (mut sum, mut weight) = (0.0, 0.0);
        for e in 0..cones * CELLS {
            if tally.count[e] > 0 {
                sum += share(e) * tally.worth[e] / tally.count[e] as f64;
                weight += share(e);
            }
        }
        let mean = sum / weight;
        if !(mean > 0.0 && mean.is_finite()) {
            return None;
        }
        let worth: Vec<f64> = (0..cones * CELLS)
            .map(|e| {
                share(e)
                    * match tally.count[e] {
                        0 => mean,
                        n => tally.worth[e] / n as f64,
                    }
            })
            .collect();
        let total_worth: f64 = worth.iter().sum();
        let total_share: f64 = (0..cones * CELLS).map(share).sum();
        let mixed: Vec<f64> = (0..cones * CELLS)
            .map(|e| {
                UNIFORM_SHARE * share(e) / total_share
                    + (1.0 - UNIFORM_SHARE) * worth[e] / total_worth
            })
            .collect();
        let total: f64 = mixed.iter().sum();
        let probability: Vec<f32> = mixed.iter().map(|w| (w / total) as f32).collect();
        let mut running = 0.0f64;
        let cumulative = (mixed.iter())
            .map(|w| {
                running += w / total;
                running as f32
            })
            .collect();
        Some(Self {
            probability,
            cumulative,
            cells_per_steradian: (0..cones)
                .map(|k| CELLS as f32 / union.solid_angle_of(k))
                .collect(),
        })
    }

    /// A bound on the flux a guided photon carries relative to an unguided one's: the union's
    /// uniform density over the smallest a cell gives, at most 1 / [`UNIFORM_SHARE`].
    pub fn largest_weight(&self, union: &PreparedUnion) -> f32 {
        let total = union.solid_angle_of_all();
        (0..self.probability.len())
            .map(|e| 1.0 / (self.probability[e] * self.cells_per_steradian[e / CELLS] * total))
            .fold(0.0, f32::max)
    }

    /// A direction drawn from the cells of `union`, and the reciprocal of its density (the
    /// solid angle the photon sent that way stands for).
    #[inline(always)]
    pub fn sample(&self, union: &PreparedUnion, rng: &mut Rng) -> (Vec3, f32) {
        let pick = rng.next_f32() * self.cumulative[self.cumulative.len() - 1];
        let e = self
            .cumulative
            .partition_point(|&c| c <= pick)
            .min(self.cumulative.len() - 1);
        let (k, cell) = (e / CELLS, e % CELLS);
        let (a, b) = rng.next_2d();
        let u = (
            ((cell / SIDE) as f32 + a) / SIDE as f32,
            ((cell % SIDE) as f32 + b) / SIDE as f32,
        );
        let direction = union.frame(k).sample(u);
        // The cell it was drawn from counts whatever rounding says of it.
        let mut density = self.probability[e] * self.cells_per_steradian[k];
        for m in (0..union.len()).filter(|&m| m != k) {
            if union.holds(m, direction) {
                let c = m * CELLS + cell_in(union.frame(m), direction);
                density += self.probability[c] * self.cells_per_steradian[m];
            }
        }
        (direction, 1.0 / density)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Stream, uniform_sphere};
    use crate::world::BoundingSphere;
    use crate::world::aim::UnionOfCones;

    fn union(targets: &[(Vec3, f32)]) -> PreparedUnion {
        let targets: Vec<BoundingSphere> = (targets.iter())
            .map(|&(center, radius)| BoundingSphere { center, radius })
            .collect();
        UnionOfCones::towards(&targets, Vec3::ZERO)
            .expect("the origin is outside every target")
            .prepared()
    }

    /// Overlapping cones, worth that varies steeply across them.
    fn overlapping() -> PreparedUnion {
        union(&[
            (Vec3::new(0.0, 0.0, 3.0), 1.0),
            (Vec3::new(0.8, 0.2, 3.0), 0.7),
            (Vec3::new(-2.0, 1.0, 1.0), 0.5),
        ])
    }

    fn worth(direction: Vec3) -> f64 {
        // Zero over part of the union (paths that miss), a steep peak elsewhere.
        let x = f64::from(direction.x);
        if x < -0.6 { 0.0 } else { (8.0 * x).exp() }
    }

    /// The tally of `pilots` unguided directions, each worth `worth` of it.
    fn tally(union: &PreparedUnion, pilots: u64, worth: impl Fn(Vec3) -> f64) -> GuideTally {
        let mut tally = GuideTally::new(union);
        let mut rng = Rng::for_index(5, Stream::CausticPilots, 0);
        for _ in 0..pilots {
            let (d, _) = union.sample(&mut rng);
            tally.add(union, d, worth(d));
        }
        tally
    }

    fn learnt(union: &PreparedUnion, pilots: u64) -> ConeCells {
        ConeCells::learn(union, &tally(union, pilots, worth)).expect("the pilots found worth")
    }

    /// Importance sampling stays unbiased: the weighted mean of a function over guided
    /// directions matches its integral over the union, found by sampling the whole sphere; and
    /// so does the solid angle (the function 1).
    #[test]
    fn guided_directions_integrate_over_the_union() {
        let union = overlapping();
        let cells = learnt(&union, 200_000);
        let f = |d: Vec3| 1.0 + 3.0 * f64::from(d.y).powi(2) + worth(d).sqrt();
        let in_union = |d: Vec3| (0..union.len()).any(|k| union.holds(k, d));
        let n = 4_000_000;
        let mut rng = Rng::for_index(9, Stream::Distribution, 0);
        let (mut sphere_f, mut sphere_1) = (0.0, 0.0);
        for _ in 0..n {
            let d = uniform_sphere(rng.next_2d());
            if in_union(d) {
                sphere_f += f(d);
                sphere_1 += 1.0;
            }
        }
        let scale = 4.0 * std::f64::consts::PI / n as f64;
        let (sphere_f, sphere_1) = (sphere_f * scale, sphere_1 * scale);
        let m = 1_000_000;
        let (mut guided_f, mut guided_1) = (0.0, 0.0);
        for _ in 0..m {
            let (d, w) = cells.sample(&union, &mut rng);
            assert!(in_union(d), "{d} is outside the union");
            guided_f += f(d) * f64::from(w);
            guided_1 += f64::from(w);
        }
        let (guided_f, guided_1) = (guided_f / m as f64, guided_1 / m as f64);
        assert!(
            (guided_1 / sphere_1 - 1.0).abs() < 0.01,
            "solid angle {guided_1} against {sphere_1}"
        );
        assert!(
            (guided_f / sphere_f - 1.0).abs() < 0.01,
            "integral {guided_f} against {sphere_f}"
        );
    }

    /// The guide sends more photons where the worth is high, only the uniform share where it
    /// is zero, and no photon carries more than that share allows.
    #[test]
    fn guided_directions_follow_the_worth_down_to_the_uniform_share() {
        let union = overlapping();
        let cells = learnt(&union, 200_000);
        let mut rng = Rng::for_index(2, Stream::Distribution, 0);
        let (mut unguided_high, mut guided_high) = (0, 0);
        let (mut unguided_zero, mut guided_zero) = (0, 0);
        let uniform = union.solid_angle_of_all();
        let mut largest = 0.0f32;
        for _ in 0..200_000 {
            let (d, _) = union.sample(&mut rng);
            unguided_high += usize::from(d.x > 0.3);
            unguided_zero += usize::from(d.x < -0.6);
            let (g, w) = cells.sample(&union, &mut rng);
            guided_high += usize::from(g.x > 0.3);
            guided_zero += usize::from(g.x < -0.6);
            largest = largest.max(w / uniform);
        }
        assert!(
            guided_high > 2 * unguided_high,
            "{guided_high} vs {unguided_high}"
        );
        // Where nothing is worth anything, only the uniform share is drawn.
        let zero_share = guided_zero as f64 / unguided_zero as f64;
        assert!(
            (zero_share / UNIFORM_SHARE - 1.0).abs() < 0.05,
            "{guided_zero} vs {unguided_zero}"
        );
        let bound = cells.largest_weight(&union);
        assert!(bound <= 1.0 / UNIFORM_SHARE as f32 * 1.001, "{bound}");
        assert!(largest <= bound * 1.001, "{largest} > {bound}");
    }

    /// Worth that is the same everywhere learns the union's own uniform density (where cones
    /// overlap, the union's density counts every cone that holds the direction).
    #[test]
    fn constant_worth_learns_the_uniform_density() {
        let union = overlapping();
        let cells = ConeCells::learn(&union, &tally(&union, 50_000, |_| 2.5)).unwrap();
        let mut rng = Rng::for_index(4, Stream::Distribution, 0);
        let uniform = union.solid_angle_of_all();
        for _ in 0..10_000 {
            let (d, w) = cells.sample(&union, &mut rng);
            let holding = (0..union.len()).filter(|&k| union.holds(k, d)).count() as f32;
            assert!(
                (w * holding / uniform - 1.0).abs() < 1e-3,
                "{w} vs {uniform}"
            );
        }
    }

    /// The octant found by comparisons is the sector the arctangent gives, off the boundaries.
    #[test]
    fn octants_are_the_sectors_of_the_turn() {
        let mut rng = Rng::for_index(8, Stream::Distribution, 0);
        let frame = ConeFrame::new(Vec3::new(0.3, -0.5, 0.8).normalize(), 0.2);
        let mut seen = [0; SIDE];
        for _ in 0..100_000 {
            let d = frame.sample(rng.next_2d());
            let (_, turns) = frame.coordinates(d);
            let eighths = turns * 8.0;
            if (eighths - eighths.round()).abs() < 1e-4 {
                continue;
            }
            let (x, y) = frame.tangent(d);
            assert_eq!(
                octant(x, y),
                eighths as usize,
                "({x}, {y}) at {turns} turns"
            );
            seen[octant(x, y)] += 1;
        }
        assert!(seen.iter().all(|&n| n > 10_000), "{seen:?}");
        // The axes, exactly: a quarter turn starts each of octants 0, 2, 4 and 6.
        assert_eq!(
            [
                octant(1.0, 0.0),
                octant(0.0, 1.0),
                octant(-1.0, 0.0),
                octant(0.0, -1.0)
            ],
            [0, 2, 4, 6]
        );
    }

    /// Pilots that found nothing leave the light unguided.
    #[test]
    fn no_worth_learns_nothing() {
        let union = overlapping();
        let tally = tally(&union, 1000, |_| 0.0);
        assert!(tally.samples() >= 1000);
        assert!(ConeCells::learn(&union, &tally).is_none());
    }
}
