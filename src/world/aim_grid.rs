//! Aiming an area light's caustic photons without building cones per photon: a grid laid over
//! the light's parallelogram, and for each cell the union of the cones that hold every
//! direction from any point of the cell to each target, built once. A photon draws its
//! direction from its cell's union, and one that misses every target carries nothing (it is
//! never traced). Owns the cells and their sampling density; must not know lights' power, trace
//! rays or store photons.
//!
//! Per photon, the per-point cones cost two square roots and a division per target, and a
//! frame (another division) for the cone drawn from; a cell's union costs a table lookup and,
//! per target, a dot product for the exact test. The cell's cones are wider than a point's, so
//! some directions miss: the cell size keeps that to about a tenth (see [`AimGrid::new`]).
//!
//! Why it stays unbiased: from a point `p` within `h` of the cell's centre `c`, a direction
//! towards a point `y` of a target of radius `R` is the direction from `c` towards
//! `y + (c − p)`, a point within `R + h` of the target's centre. So the cone from `c` of
//! sin θ = (R + h) / D (`D` the distance from `c` to the centre) holds every direction that
//! reaches the target from anywhere in the cell, and drawing uniformly from the union of a
//! cell's cones covers every direction that can carry a caustic photon.

use super::BoundingSphere;
use super::aim::{UnionOfCones, cone_towards, draw_from_cones};
use crate::sampling::{ConeFrame, Rng};
use glam::Vec3;

/// Cells per side at most: 64² cells of eight targets take 1.4 MiB.
const MAX_SIDE: usize = 64;

/// A cell's half-diagonal as a fraction of the smallest target's radius: the cell's cones are
/// then wider than a point's by about that much, and about 2 × 5% of the directions drawn miss.
const CELL_REACH: f32 = 0.05;

/// What a photon leaving a point of the light draws, by its cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CellDraw {
    /// A direction that reaches a target, and the solid angle it stands for (one over its
    /// density).
    Aimed(Vec3, f32),
    /// No target is reached this way, or from this cell at all (every cone lies behind the
    /// light): the photon carries nothing.
    Nothing,
    /// The cell is too close to a target for cell-wide cones: aim from the point itself.
    PerPoint,
}

/// Per-cell unions of cones from a parallelogram `corner + s·edge_u + t·edge_v`
/// (`s`, `t` in [0, 1)) towards the targets.
#[derive(Clone, Debug)]
pub struct AimGrid {
    side: usize,
    targets: Vec<BoundingSphere>,
    /// `targets.len()` frames per cell, cell by cell.
    frames: Vec<ConeFrame>,
    /// Solid angles summed up to and including each cone, laid out as `frames`.
    cumulative: Vec<f32>,
    cells: Vec<CellKind>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CellKind {
    Aimed,
    /// Every cone lies wholly behind the light's surface.
    Behind,
    PerPoint,
}

impl AimGrid {
    /// The grid over the parallelogram, whose surface faces `normal`; `None` without targets.
    /// Cells are small enough that their half-diagonal is at most a twentieth of the smallest
    /// target's radius, with at most 64 cells per side.
    pub fn new(
        corner: Vec3,
        edge_u: Vec3,
        edge_v: Vec3,
        normal: Vec3,
        targets: &[BoundingSphere],
    ) -> Option<Self> {
        let smallest = targets.iter().map(|t| t.radius).reduce(f32::min)?;
        let diagonal = (edge_u + edge_v).length().max((edge_u - edge_v).length());
        let wanted = (diagonal / (2.0 * CELL_REACH * smallest)).ceil();
        let side = if wanted.is_finite() {
            (wanted as usize).clamp(1, MAX_SIDE)
        } else {
            MAX_SIDE
        };
        let (cell_u, cell_v) = (edge_u / side as f32, edge_v / side as f32);
        // A little over the half-diagonal, and over the rounding of points this far from the
        // origin (relative to the coordinates, so the aim does not change with the units).
        let magnitude = corner.abs().max_element() + edge_u.abs().max_element();
        let reach = 0.5 * (cell_u + cell_v).length().max((cell_u - cell_v).length()) * 1.01
            + 8.0 * f32::EPSILON * (magnitude + edge_v.abs().max_element());
        let mut grid = Self {
            side,
            targets: targets.to_vec(),
            frames: Vec::with_capacity(side * side * targets.len()),
            cumulative: Vec::with_capacity(side * side * targets.len()),
            cells: Vec::with_capacity(side * side),
        };
        for j in 0..side {
            for i in 0..side {
                let center = corner + (i as f32 + 0.5) * cell_u + (j as f32 + 0.5) * cell_v;
                let cones: Option<Vec<(Vec3, f32)>> = (targets.iter())
                    .map(|t| {
                        let grown = BoundingSphere {
                            center: t.center,
                            radius: t.radius + reach,
                        };
                        cone_towards(&grown, center)
                    })
                    .collect();
                let union = cones.and_then(UnionOfCones::new);
                let kind = match &union {
                    None => CellKind::PerPoint,
                    Some(union) if union.behind(normal) => CellKind::Behind,
                    Some(_) => CellKind::Aimed,
                };
                grid.cells.push(kind);
                // Every cell keeps its place in the layout; only aimed cells' cones are read.
                for k in 0..targets.len() {
                    let ((axis, cos_max), cumulative) = match &union {
                        Some(union) => (union.cone(k), union.cumulative(k)),
                        None => ((normal, 1.0), 0.0),
                    };
                    grid.frames.push(ConeFrame::new(axis, cos_max));
                    grid.cumulative.push(cumulative);
                }
            }
        }
        Some(grid)
    }

    /// Cells per side.
    pub fn side(&self) -> usize {
        self.side
    }

    /// A direction for a photon leaving `origin`, the point at (`s`, `t`) of the
    /// parallelogram, drawn from `rng` only when the cell is aimed.
    #[inline(always)]
    pub fn draw(&self, s: f32, t: f32, origin: Vec3, rng: &mut Rng) -> CellDraw {
        let last = self.side - 1;
        let i = ((s * self.side as f32) as usize).min(last);
        let j = ((t * self.side as f32) as usize).min(last);
        let cell = j * self.side + i;
        match self.cells[cell] {
            CellKind::PerPoint => return CellDraw::PerPoint,
            CellKind::Behind => return CellDraw::Nothing,
            CellKind::Aimed => {}
        }
        let n = self.targets.len();
        let frames = &self.frames[cell * n..(cell + 1) * n];
        let (direction, weight) = draw_from_cones(
            &self.cumulative[cell * n..(cell + 1) * n],
            |k| (frames[k].axis(), frames[k].cos_max()),
            |k| frames[k],
            rng,
        );
        if self.targets.iter().any(|t| reaches(t, origin, direction)) {
            CellDraw::Aimed(direction, weight)
        } else {
            CellDraw::Nothing
        }
    }
}

/// Whether the ray from `origin` (outside the sphere) along unit `direction` meets `target`.
#[inline(always)]
fn reaches(target: &BoundingSphere, origin: Vec3, direction: Vec3) -> bool {
    let to = target.center - origin;
    let along = to.dot(direction);
    along > 0.0 && to.length_squared() - along * along <= target.radius * target.radius
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::{Stream, uniform_sphere};

    fn sphere(x: f32, y: f32, z: f32, radius: f32) -> BoundingSphere {
        BoundingSphere {
            center: Vec3::new(x, y, z),
            radius,
        }
    }

    /// A light 0.5 on a side, facing down, as the Cornell box's.
    const CORNER: Vec3 = Vec3::new(-0.25, 2.0, -0.25);
    const EDGE_U: Vec3 = Vec3::new(0.5, 0.0, 0.0);
    const EDGE_V: Vec3 = Vec3::new(0.0, 0.0, 0.5);

    /// Every direction from any point of a cell that reaches a target lies in one of the
    /// cell's cones: from random points and from the cells' corners, towards points on the
    /// targets' surfaces (where the directions lean furthest out).
    #[test]
    fn a_cells_cones_hold_every_direction_from_the_cell_to_the_targets() {
        let targets = [
            sphere(-0.45, 0.35, -0.35, 0.35),
            sphere(0.45, 0.35, 0.3, 0.35),
        ];
        let grid = AimGrid::new(CORNER, EDGE_U, EDGE_V, -Vec3::Y, &targets).unwrap();
        let side = grid.side();
        assert!(side >= 8, "{side} cells per side");
        let mut rng = Rng::for_index(3, Stream::CausticPhotons, 0);
        for k in 0..100_000 {
            let (i, j) = (
                (rng.next_f32() * side as f32) as usize,
                (rng.next_f32() * side as f32) as usize,
            );
            // Every other point at a corner of its cell, the furthest from its centre.
            let (a, b) = if k % 2 == 0 {
                rng.next_2d()
            } else {
                let corner = rng.next_u32();
                ((corner & 1) as f32, (corner >> 1 & 1) as f32)
            };
            let (s, t) = ((i as f32 + a) / side as f32, (j as f32 + b) / side as f32);
            let origin = CORNER + s * EDGE_U + t * EDGE_V;
            let target = targets[k % 2];
            let y = target.center + target.radius * uniform_sphere(rng.next_2d());
            let d = (y - origin).normalize();
            let cell = j * side + i;
            assert_eq!(grid.cells[cell], CellKind::Aimed);
            let held = (0..targets.len()).any(|n| {
                let f = grid.frames[cell * targets.len() + n];
                d.dot(f.axis()) >= f.cos_max()
            });
            assert!(held, "{origin} -> {y} is in no cone of cell ({i}, {j})");
        }
    }

    /// Drawing from the cells is unbiased: the weighted count of photons into each target
    /// matches the solid angle each target subtends, averaged over the light (found per point).
    #[test]
    fn cell_draws_integrate_the_solid_angle_of_each_target() {
        let targets = [sphere(-0.45, 0.35, -0.35, 0.35), sphere(0.3, 0.6, 0.3, 0.2)];
        let grid = AimGrid::new(CORNER, EDGE_U, EDGE_V, -Vec3::Y, &targets).unwrap();
        let n = 400_000;
        let (mut drawn, mut exact) = ([0.0f64; 2], [0.0f64; 2]);
        let mut missed = 0;
        let mut rng = Rng::for_index(4, Stream::CausticPhotons, 0);
        for _ in 0..n {
            let (s, t) = rng.next_2d();
            let origin = CORNER + s * EDGE_U + t * EDGE_V;
            for (k, target) in targets.iter().enumerate() {
                let (_, cos_max) = cone_towards(target, origin).unwrap();
                exact[k] += crate::sampling::cone_solid_angle(cos_max) as f64;
            }
            match grid.draw(s, t, origin, &mut rng) {
                CellDraw::Aimed(d, weight) => {
                    for (k, target) in targets.iter().enumerate() {
                        if reaches(target, origin, d) {
                            drawn[k] += weight as f64;
                        }
                    }
                }
                CellDraw::Nothing => missed += 1,
                CellDraw::PerPoint => panic!("no cell is near a target"),
            }
        }
        for k in 0..2 {
            let (drawn, exact) = (drawn[k] / n as f64, exact[k] / n as f64);
            assert!(
                (drawn - exact).abs() < 0.01 * exact,
                "target {k}: {drawn} vs {exact}"
            );
        }
        // The cells' cones are only a little wider than the points'.
        assert!(missed > 0 && missed < n / 5, "{missed} of {n} missed");
    }

    /// Cells that overlap a target are left to per-point aiming; cells facing away from every
    /// target draw nothing; no targets, no grid.
    #[test]
    fn near_and_hidden_cells_and_no_targets() {
        let near = [sphere(-0.25, 2.05, -0.25, 0.1)];
        let grid = AimGrid::new(CORNER, EDGE_U, EDGE_V, -Vec3::Y, &near).unwrap();
        let mut rng = Rng::for_index(5, Stream::CausticPhotons, 0);
        assert_eq!(grid.draw(0.0, 0.0, CORNER, &mut rng), CellDraw::PerPoint);
        let above = [sphere(0.0, 3.0, 0.0, 0.2)];
        let grid = AimGrid::new(CORNER, EDGE_U, EDGE_V, -Vec3::Y, &above).unwrap();
        let before = rng.clone().next_u32();
        assert_eq!(grid.draw(0.5, 0.5, CORNER, &mut rng), CellDraw::Nothing);
        assert_eq!(rng.next_u32(), before, "a hidden cell draws no numbers");
        assert!(AimGrid::new(CORNER, EDGE_U, EDGE_V, -Vec3::Y, &[]).is_none());
    }
}
