//! pbrt-v3's `heterogeneous` density grid and the majorant grid over it. The grid's own space
//! is the unit cube: a point p in [0, 1]³ is looked up at p·n − ½ in voxel units, trilinear
//! between the voxel centres, every voxel outside the grid reading 0 (so the density falls to
//! half the border voxel's at the cube's face), and nothing outside the cube. Values are
//! stored x fastest, then y, then z.
//!
//! The majorant grid splits the cube into cells, each holding the largest density any point
//! in it can read (the largest of the voxels whose centres bound it: trilinear interpolation
//! never exceeds its corners). [`MajorantGrid::segments`] walks a ray through the cells by a
//! 3-D DDA, so free flights take steps sized to the density near them, not to the densest
//! voxel of the whole grid.

use glam::{IVec3, UVec3, Vec3};

/// A density grid as pbrt-v3 reads `density` with `nx`, `ny`, `nz`.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityGrid {
    size: UVec3,
    values: Vec<f32>,
}

impl DensityGrid {
    /// The grid of `size` voxels holding `values` (x fastest); `None` when their number is not
    /// nx·ny·nz, a size is 0, or a value is negative or not finite.
    pub fn new(size: UVec3, values: Vec<f32>) -> Option<Self> {
        let count = size.x as usize * size.y as usize * size.z as usize;
        let valid =
            count > 0 && values.len() == count && values.iter().all(|v| v.is_finite() && *v >= 0.0);
        valid.then_some(Self { size, values })
    }

    /// Voxels held.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    pub fn size(&self) -> UVec3 {
        self.size
    }

    /// The voxel at `i`, 0 outside the grid.
    fn voxel(&self, i: IVec3) -> f32 {
        let n = self.size.as_ivec3();
        if i.cmplt(IVec3::ZERO).any() || i.cmpge(n).any() {
            return 0.0;
        }
        self.values[(i.x + n.x * (i.y + n.y * i.z)) as usize]
    }

    /// The density at `p` in the unit cube's space: 0 outside the cube, which pbrt never
    /// reads past (half a voxel out the interpolation would still see the border voxels).
    pub fn density(&self, p: Vec3) -> f32 {
        if p.cmplt(Vec3::ZERO).any() || p.cmpgt(Vec3::ONE).any() {
            return 0.0;
        }
        let s = p * self.size.as_vec3() - Vec3::splat(0.5);
        let base = s.floor();
        let f = s - base;
        let i = base.as_ivec3();
        let at = |dx: i32, dy: i32, dz: i32| self.voxel(i + IVec3::new(dx, dy, dz));
        let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
        let x00 = lerp(at(0, 0, 0), at(1, 0, 0), f.x);
        let x10 = lerp(at(0, 1, 0), at(1, 1, 0), f.x);
        let x01 = lerp(at(0, 0, 1), at(1, 0, 1), f.x);
        let x11 = lerp(at(0, 1, 1), at(1, 1, 1), f.x);
        lerp(lerp(x00, x10, f.y), lerp(x01, x11, f.y), f.z)
    }

    /// The largest voxel value.
    pub fn max(&self) -> f32 {
        self.values.iter().fold(0.0, |a, &b| a.max(b))
    }
}

/// The largest density per cell of a regular split of the unit cube.
#[derive(Clone, Debug, PartialEq)]
pub struct MajorantGrid {
    cells: UVec3,
    values: Vec<f32>,
}

/// A stretch of a ray within one majorant cell: parameters `t0` to `t1` and the cell's bound.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MajorantSegment {
    pub t0: f32,
    pub t1: f32,
    pub majorant: f32,
}

impl MajorantGrid {
    /// `cells` cells a side (pbrt-v4 uses 16) over `grid`.
    pub fn new(grid: &DensityGrid, cells: u32) -> Self {
        let cells = UVec3::splat(cells.max(1));
        let n = grid.size.as_vec3();
        let mut values = Vec::with_capacity((cells.x * cells.y * cells.z) as usize);
        for z in 0..cells.z {
            for y in 0..cells.y {
                for x in 0..cells.x {
                    let c = UVec3::new(x, y, z).as_vec3();
                    let (lo, hi) = (c / cells.as_vec3(), (c + 1.0) / cells.as_vec3());
                    // Lookups in the cell read voxels floor(p·n − ½) and the next.
                    let first = (lo * n - 0.5).floor().as_ivec3();
                    let last = (hi * n - 0.5).floor().as_ivec3() + IVec3::ONE;
                    let mut m = 0.0f32;
                    for k in first.z..=last.z {
                        for j in first.y..=last.y {
                            for i in first.x..=last.x {
                                m = m.max(grid.voxel(IVec3::new(i, j, k)));
                            }
                        }
                    }
                    values.push(m);
                }
            }
        }
        Self { cells, values }
    }

    /// Cells held.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    fn cell(&self, c: IVec3) -> f32 {
        let n = self.cells.as_ivec3();
        self.values[(c.x + n.x * (c.y + n.y * c.z)) as usize]
    }

    /// The cell bound at the unit-cube point `p` (0 outside the cube).
    pub fn at(&self, p: Vec3) -> f32 {
        if p.cmplt(Vec3::ZERO).any() || p.cmpgt(Vec3::ONE).any() {
            return 0.0;
        }
        let n = self.cells.as_ivec3();
        let c = (p * self.cells.as_vec3())
            .floor()
            .as_ivec3()
            .clamp(IVec3::ZERO, n - 1);
        self.cell(c)
    }

    /// The ray o + t·d (in the unit cube's space) from `t_min` to `t_max` cell by cell, in
    /// order, each stretch with its cell's bound, inside the cube only: `visit` returns false
    /// to stop.
    pub fn segments(
        &self,
        o: Vec3,
        d: Vec3,
        t_min: f32,
        t_max: f32,
        mut visit: impl FnMut(MajorantSegment) -> bool,
    ) {
        // Clip to the cube.
        let inv = d.recip();
        let (a, b) = (-o * inv, (Vec3::ONE - o) * inv);
        let (near, far) = (a.min(b), a.max(b));
        let enter = near.max_element().max(t_min);
        let exit = far.min_element().min(t_max);
        if enter >= exit || enter.is_nan() || exit.is_nan() {
            return;
        }
        let n = self.cells.as_ivec3();
        let cells = self.cells.as_vec3();
        let start = (o + d * enter) * cells;
        let mut c = start.floor().as_ivec3().clamp(IVec3::ZERO, n - 1);
        // By the sign of 1/d, so that a −0 component steps the way its infinity points.
        let step = IVec3::new(
            if inv.x > 0.0 { 1 } else { -1 },
            if inv.y > 0.0 { 1 } else { -1 },
            if inv.z > 0.0 { 1 } else { -1 },
        );
        // The parameter at which the ray crosses the next cell wall on each axis.
        let next_wall = |c: IVec3, axis: usize| -> f32 {
            let wall = if step[axis] > 0 { c[axis] + 1 } else { c[axis] } as f32 / cells[axis];
            let t = (wall - o[axis]) * inv[axis];
            if t.is_nan() { f32::INFINITY } else { t }
        };
        let mut t = enter;
        loop {
            let walls = [next_wall(c, 0), next_wall(c, 1), next_wall(c, 2)];
            let axis = (0..3)
                .min_by(|&i, &j| walls[i].total_cmp(&walls[j]))
                .unwrap_or(0);
            let t1 = walls[axis].min(exit).max(t);
            let keep_on = visit(MajorantSegment {
                t0: t,
                t1,
                majorant: self.cell(c),
            });
            if !keep_on || t1 >= exit {
                return;
            }
            t = t1;
            c[axis] += step[axis];
            if c[axis] < 0 || c[axis] >= n[axis] {
                return;
            }
        }
    }
}
