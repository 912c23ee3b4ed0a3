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
    /// Under the surface of a subsurface material: a path's scattering events in it are one
    /// walk under that surface, not bounces.
    pub subsurface: bool,
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

/// Index of a medium in [`SceneMedia::media`].
pub type MediumId = u16;

/// The media on the two sides of a surface: `inside` behind its geometric normal (as dpm
/// orients the shape), `outside` on the side the normal points to; `None` is vacuum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumInterface {
    pub inside: Option<MediumId>,
    pub outside: Option<MediumId>,
}

impl MediumInterface {
    /// Whether crossing the surface changes the medium (pbrt ignores an interface that does
    /// not: the ray keeps the medium it had).
    pub fn is_transition(&self) -> bool {
        self.inside != self.outside
    }

    /// The medium a ray is in after crossing the surface along `dir`, `normal` its geometric
    /// normal: inside when it heads against the normal.
    pub fn after_crossing(&self, dir: Vec3, normal: Vec3) -> Option<MediumId> {
        if dir.dot(normal) < 0.0 {
            self.inside
        } else {
            self.outside
        }
    }
}

/// A surface that only bounds media (pbrt's `Material ""`, `"none"`, `"interface"`): rays
/// cross it without a bounce, changing medium.
#[derive(Clone, Debug, PartialEq)]
pub struct MediumBoundary {
    /// The shape; its material is not read.
    pub shape: super::Shape,
    pub interface: MediumInterface,
}

/// Everything a scene says of participating media: empty in a scene without them, which then
/// renders exactly as before media existed.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneMedia {
    /// In order of definition.
    pub media: Vec<Medium>,
    pub boundaries: Vec<MediumBoundary>,
    /// Shapes with a material whose two sides hold different media (a glass of fog), by index
    /// into [`super::SceneDescription::shapes`].
    pub shape_interfaces: Vec<(usize, MediumInterface)>,
    /// The medium each light sits in, by index into [`super::SceneDescription::lights`]
    /// (lights not listed are in vacuum; a light at infinity always is).
    pub light_media: Vec<(usize, MediumId)>,
    /// The medium the camera sits in.
    pub camera: Option<MediumId>,
}

impl SceneMedia {
    /// Whether any light travels through a medium.
    pub fn is_empty(&self) -> bool {
        self.media.is_empty()
    }
}
