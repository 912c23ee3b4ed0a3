//! One medium as light transport meets it, whatever its kind: what a segment of a ray lets
//! through (transmittance), where a flight along it scatters first (a free flight, with the
//! weight it carries), and how it scatters (its phase function). Built from a scene's
//! description; a homogeneous medium answers in closed form, a grid by tracking.

use super::grid::DensityGrid;
use super::homogeneous::{FreeFlight, Homogeneous};
use super::phase::HenyeyGreenstein;
use super::tracking::GridMedium;
use crate::sampling::Rng;
use crate::scene::{self, MediumKind};
use glam::{UVec3, Vec3};

#[derive(Clone, Debug)]
pub enum Medium {
    Homogeneous {
        coefficients: Homogeneous,
        phase: HenyeyGreenstein,
    },
    Grid {
        grid: GridMedium,
        phase: HenyeyGreenstein,
    },
}

impl Medium {
    /// The medium `described` defines; `None` where its grid cannot be built (σt differing
    /// by channel, a size that does not match its values), which the scene readers refuse.
    pub fn new(described: &scene::Medium) -> Option<Self> {
        let phase = HenyeyGreenstein::new(described.g);
        Some(match &described.kind {
            MediumKind::Homogeneous { sigma_a, sigma_s } => Medium::Homogeneous {
                coefficients: Homogeneous {
                    sigma_a: *sigma_a,
                    sigma_s: *sigma_s,
                },
                phase,
            },
            MediumKind::Grid {
                sigma_a,
                sigma_s,
                size,
                density,
                grid_to_world,
            } => {
                let density = DensityGrid::new(UVec3::from_array(*size), density.clone())?;
                Medium::Grid {
                    grid: GridMedium::new(density, *grid_to_world, *sigma_a, *sigma_s)?,
                    phase,
                }
            }
        })
    }

    pub fn phase(&self) -> HenyeyGreenstein {
        match self {
            Medium::Homogeneous { phase, .. } | Medium::Grid { phase, .. } => *phase,
        }
    }

    /// Transmittance along `o + t·d` (unit `d`) for t in [`t0`, `t1`): exact in a homogeneous
    /// medium, an unbiased ratio-tracking estimate in a grid.
    pub fn transmittance(&self, o: Vec3, d: Vec3, t0: f32, t1: f32, rng: &mut Rng) -> Vec3 {
        let length = (t1 - t0).min(f32::MAX);
        if length <= 0.0 {
            return Vec3::ONE;
        }
        match self {
            Medium::Homogeneous { coefficients, .. } => coefficients.transmittance(length),
            Medium::Grid { grid, .. } => {
                Vec3::splat(grid.transmittance(o + t0 * d, d, length, rng))
            }
        }
    }

    /// The first scattering event along `o + t·d` (unit `d`) for t in [`t0`, `t1`), drawn so
    /// that the weight it returns keeps every channel unbiased: at an event σs·Tr/pdf (a
    /// grid's albedo), past the segment Tr/P(no event) (1 in a grid). Absorption is in the
    /// weight, never a lost path.
    pub fn free_flight(&self, o: Vec3, d: Vec3, t0: f32, t1: f32, rng: &mut Rng) -> FreeFlight {
        let length = (t1 - t0).min(f32::MAX);
        if length <= 0.0 {
            return FreeFlight::Passed { weight: Vec3::ONE };
        }
        match self {
            Medium::Homogeneous { coefficients, .. } => {
                let (u_channel, u) = rng.next_2d();
                match coefficients.free_flight(length, u_channel, u) {
                    FreeFlight::Scattered { t, weight } => {
                        FreeFlight::Scattered { t: t0 + t, weight }
                    }
                    passed => passed,
                }
            }
            Medium::Grid { grid, .. } => match grid.free_flight(o + t0 * d, d, length, rng) {
                Some(t) => FreeFlight::Scattered {
                    t: t0 + t,
                    weight: grid.albedo(),
                },
                None => FreeFlight::Passed { weight: Vec3::ONE },
            },
        }
    }

    /// σs at the world point `p`.
    pub fn sigma_s_at(&self, p: Vec3) -> Vec3 {
        match self {
            Medium::Homogeneous { coefficients, .. } => coefficients.sigma_s,
            Medium::Grid { grid, .. } => grid.albedo() * grid.sigma_t_at(p),
        }
    }

    /// Bytes the medium keeps (a grid's density and majorants).
    pub fn bytes(&self) -> usize {
        match self {
            Medium::Homogeneous { .. } => std::mem::size_of::<Self>(),
            Medium::Grid { grid, .. } => std::mem::size_of::<Self>() + grid.bytes(),
        }
    }
}
