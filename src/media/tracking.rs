//! Free flights and transmittance through a grid medium, over the majorant grid's segments:
//! delta tracking draws tentative collisions at the cell's bound σ̄ and keeps one as real with
//! probability σt(x)/σ̄ (the rest are null collisions, which change nothing), so the first real
//! one is distributed exactly as in the medium; ratio tracking multiplies 1 − σt(x)/σ̄ over the
//! tentative collisions up to the segment's end, an unbiased estimate of exp(−∫σt). Both see
//! only the cells the ray crosses. As pbrt-v3's `heterogeneous` medium, σt = density · σt₀ is
//! the same in every channel; a real collision's weight is the albedo σs/σt.

use super::grid::{DensityGrid, MajorantGrid};
use crate::sampling::Rng;
use glam::{Mat4, Vec3};

/// A heterogeneous medium: a density grid placed in the world, scaling σa and σs.
#[derive(Clone, Debug)]
pub struct GridMedium {
    density: DensityGrid,
    majorants: MajorantGrid,
    /// World to the grid's unit cube.
    to_grid: Mat4,
    /// σt at density 1 (one value: pbrt-v3 refuses a grid whose σt differs by channel).
    sigma_t: f32,
    albedo: Vec3,
}

/// Majorant cells a side, as pbrt-v4's grid media keep.
pub const MAJORANT_CELLS: u32 = 16;

impl GridMedium {
    /// `density` placed by `grid_to_world` (the unit cube to the world), with σa and σs at
    /// density 1; `None` when σt differs between channels or a coefficient is negative or
    /// not finite.
    pub fn new(
        density: DensityGrid,
        grid_to_world: Mat4,
        sigma_a: Vec3,
        sigma_s: Vec3,
    ) -> Option<Self> {
        let sigma_t = sigma_a + sigma_s;
        let valid = (sigma_a.is_finite() && sigma_s.is_finite())
            && sigma_a.min_element() >= 0.0
            && sigma_s.min_element() >= 0.0
            && (sigma_t.max_element() - sigma_t.min_element()) <= 1e-6 * sigma_t.max_element()
            && grid_to_world.determinant().abs() > 0.0;
        let albedo = if sigma_t.x > 0.0 {
            sigma_s / sigma_t
        } else {
            Vec3::ZERO
        };
        valid.then(|| Self {
            majorants: MajorantGrid::new(&density, MAJORANT_CELLS),
            density,
            to_grid: grid_to_world.inverse(),
            sigma_t: sigma_t.x,
            albedo,
        })
    }

    /// σt at the world point `p`.
    pub fn sigma_t_at(&self, p: Vec3) -> f32 {
        self.sigma_t * self.density.density(self.to_grid.transform_point3(p))
    }

    /// Bytes of its density and majorant grids.
    pub fn bytes(&self) -> usize {
        4 * (self.density.len() + self.majorants.len())
    }

    /// What a real collision multiplies a path's throughput by: the albedo.
    pub fn albedo(&self) -> Vec3 {
        self.albedo
    }

    /// The first real collision of the ray `o + t·d` (world space, any length of `d`) with
    /// t in [0, `t_max`), or `None` when it passes.
    pub fn free_flight(&self, o: Vec3, d: Vec3, t_max: f32, rng: &mut Rng) -> Option<f32> {
        let mut hit = None;
        self.tentative_collisions(o, d, t_max, rng, |t, real, rng| {
            if rng.next_f32() < real {
                hit = Some(t);
                return false;
            }
            true
        });
        hit
    }

    /// An unbiased estimate of exp(−∫σt) along `o + t·d` for t in [0, `t_max`).
    pub fn transmittance(&self, o: Vec3, d: Vec3, t_max: f32, rng: &mut Rng) -> f32 {
        let mut tr = 1.0f32;
        self.tentative_collisions(o, d, t_max, rng, |_, real, _| {
            tr *= 1.0 - real;
            tr > 0.0
        });
        tr.max(0.0)
    }

    /// Tentative collisions along `o + t·d` up to `t_max`, drawn at each majorant cell's
    /// bound: `collide(t, σt(x)/σ̄, rng)` sees each in order and returns false to stop.
    fn tentative_collisions(
        &self,
        o: Vec3,
        d: Vec3,
        t_max: f32,
        rng: &mut Rng,
        mut collide: impl FnMut(f32, f32, &mut Rng) -> bool,
    ) {
        let (go, gd) = (
            self.to_grid.transform_point3(o),
            self.to_grid.transform_vector3(d),
        );
        // σ per unit of t: per unit of world length times the world length of a unit of t.
        let sigma_t = self.sigma_t * d.length();
        self.majorants.segments(go, gd, 0.0, t_max, |segment| {
            let bound = sigma_t * segment.majorant;
            if bound <= 0.0 {
                return true;
            }
            let mut t = segment.t0;
            loop {
                t -= (1.0 - rng.next_f32()).ln() / bound;
                if t >= segment.t1 {
                    return true;
                }
                let real = sigma_t * self.density.density(go + gd * t);
                if !collide(t, real / bound, rng) {
                    return false;
                }
            }
        });
    }
}
