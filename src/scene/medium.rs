//! Participating media in a scene description, as a pbrt file defines them and before any is
//! built for rendering (`crate::media` builds them): a homogeneous medium's coefficients, or a
//! density grid placed in the world scaling them. Owns these types and their one-line
//! descriptions; must not know pbrt's parameter names or how media are sampled.

use glam::{Mat4, Vec3};

/// A named medium.
#[derive(Clone, Debug, PartialEq)]
pub struct Medium {
    pub name: String,
    /// Where it was defined (file:line:column), for reports.
    pub defined_at: String,
    /// Henyey–Greenstein asymmetry, |g| < 1.
    pub g: f32,
    /// Shapes whose `MediumInterface` names it on either side.
    pub bounded_by: usize,
    pub kind: MediumKind,
}

#[derive(Clone, Debug, PartialEq)]
pub enum MediumKind {
    /// σa and σs per unit length, everywhere.
    Homogeneous { sigma_a: Vec3, sigma_s: Vec3 },
    /// σa and σs at density 1, scaled by a grid of `size` voxels (x fastest) that fills the
    /// unit cube `grid_to_world` places.
    Grid {
        sigma_a: Vec3,
        sigma_s: Vec3,
        size: [u32; 3],
        density: Vec<f32>,
        grid_to_world: Mat4,
    },
}

impl Medium {
    /// One line for `dpm check`.
    pub fn describe(&self) -> String {
        let rgb = |v: Vec3| format!("({} {} {})", v.x, v.y, v.z);
        let what = match &self.kind {
            MediumKind::Homogeneous { sigma_a, sigma_s } => {
                format!("homogeneous, σa {}, σs {}", rgb(*sigma_a), rgb(*sigma_s))
            }
            MediumKind::Grid {
                sigma_a,
                sigma_s,
                size,
                density,
                ..
            } => {
                let max = density.iter().fold(0.0f32, |a, &b| a.max(b));
                format!(
                    "a {}×{}×{} density grid (largest {max}), σa {}, σs {} at density 1",
                    size[0],
                    size[1],
                    size[2],
                    rgb(*sigma_a),
                    rgb(*sigma_s)
                )
            }
        };
        let bounds = match self.bounded_by {
            0 => "no shape names it in a MediumInterface".to_string(),
            1 => "bounded by 1 shape".to_string(),
            n => format!("bounded by {n} shapes"),
        };
        format!(
            "medium \"{}\" ({}): {what}, g {}; {bounds}",
            self.name, self.defined_at, self.g
        )
    }
}
