//! pbrt's quadrics (disk, cylinder, cone, paraboloid, hyperboloid, partial sphere) as
//! surfaces of revolution about z, and their tessellation on a grid in (φ, meridian) whose
//! counts grow until the measured distance between the surface and its triangles is within
//! [`RELATIVE_ERROR_BOUND`] of the radius. Owns the shapes' definitions (where each lies,
//! which way its normal points: pbrt's ∂p/∂u × ∂p/∂v) and the grid; must not check parameters
//! (the mapping does, naming them) nor place anything in the world.

use super::{RELATIVE_ERROR_BOUND, Tessellation};
use glam::DVec3;

/// The most 1 − cos(angle) between a triangle's normal and the surface's at the triangle's
/// centre: with it the triangles' area is the surface's to within about the error bound
/// (a triangle close to the surface can still lie tilted across it and add area).
const NORMAL_GAP: f64 = RELATIVE_ERROR_BOUND;

/// More grid cells than this is not a sensible tessellation of one quadric.
const MAX_CELLS: usize = 1 << 22;

/// A quadric in its own space, angles in radians, φ from 0 to `phi_max` about +z. The
/// values obey what the mapping checks: radii > 0, `z_min < z_max`, 0 < `phi_max` ≤ 2π.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Quadric {
    /// The annulus inner_radius ≤ ρ ≤ radius at z = height, normal +z.
    Disk {
        height: f64,
        radius: f64,
        inner_radius: f64,
        phi_max: f64,
    },
    Cylinder {
        radius: f64,
        z_min: f64,
        z_max: f64,
        phi_max: f64,
    },
    /// Base of `radius` at z = 0, apex at z = `height`.
    Cone {
        height: f64,
        radius: f64,
        phi_max: f64,
    },
    /// z = z_max·ρ²/radius², for 0 ≤ z_min ≤ z ≤ z_max.
    Paraboloid {
        radius: f64,
        z_min: f64,
        z_max: f64,
        phi_max: f64,
    },
    /// The surface the segment p1–p2 sweeps turning about z.
    Hyperboloid { p1: DVec3, p2: DVec3, phi_max: f64 },
    /// The part of the sphere of `radius` between z_min and z_max (both within ±radius).
    Sphere {
        radius: f64,
        z_min: f64,
        z_max: f64,
        phi_max: f64,
    },
}

impl Quadric {
    fn phi_max(&self) -> f64 {
        match *self {
            Quadric::Disk { phi_max, .. }
            | Quadric::Cylinder { phi_max, .. }
            | Quadric::Cone { phi_max, .. }
            | Quadric::Paraboloid { phi_max, .. }
            | Quadric::Hyperboloid { phi_max, .. }
            | Quadric::Sphere { phi_max, .. } => phi_max,
        }
    }

    /// The largest distance of the surface from its axis: what the error bound scales with.
    pub(crate) fn radius(&self) -> f64 {
        match *self {
            Quadric::Disk { radius, .. }
            | Quadric::Cylinder { radius, .. }
            | Quadric::Cone { radius, .. }
            | Quadric::Paraboloid { radius, .. }
            | Quadric::Sphere { radius, .. } => radius,
            Quadric::Hyperboloid { p1, p2, .. } => {
                p1.truncate().length().max(p2.truncate().length())
            }
        }
    }

    /// pbrt swaps a hyperboloid's points when p2 lies at z = 0, which turns its v and so
    /// its normal; the tessellation follows pbrt's order.
    fn hyperboloid_ends(p1: DVec3, p2: DVec3) -> (DVec3, DVec3) {
        if p2.z == 0.0 { (p2, p1) } else { (p1, p2) }
    }

    /// The point at meridian parameter t ∈ [0, 1] in the φ = 0 half-plane (a hyperboloid's
    /// may leave it), the unit normal there, and pbrt's v for it.
    fn meridian(&self, t: f64) -> (DVec3, DVec3, f64) {
        match *self {
            Quadric::Disk {
                height,
                radius,
                inner_radius,
                ..
            } => {
                let rho = radius + t * (inner_radius - radius);
                (DVec3::new(rho, 0.0, height), DVec3::Z, t)
            }
            Quadric::Cylinder {
                radius,
                z_min,
                z_max,
                ..
            } => (
                DVec3::new(radius, 0.0, z_min + t * (z_max - z_min)),
                DVec3::X,
                t,
            ),
            Quadric::Cone { height, radius, .. } => (
                DVec3::new(radius * (1.0 - t), 0.0, t * height),
                DVec3::new(height, 0.0, radius).normalize(),
                t,
            ),
            Quadric::Paraboloid {
                radius,
                z_min,
                z_max,
                ..
            } => {
                // Even steps in ρ, not z: the meridian's curvature is greatest at the apex,
                // where steps in z would crowd the error into the first ring.
                let rho_min = radius * (z_min / z_max).sqrt();
                let rho = rho_min + t * (radius - rho_min);
                let z = z_max * rho * rho / (radius * radius);
                let normal = DVec3::new(2.0 * z_max * rho / (radius * radius), 0.0, -1.0);
                let v = (z - z_min) / (z_max - z_min);
                (DVec3::new(rho, 0.0, z), normal.normalize(), v)
            }
            Quadric::Hyperboloid { p1, p2, .. } => {
                let (p1, p2) = Self::hyperboloid_ends(p1, p2);
                let p = p1 + t * (p2 - p1);
                let normal = |p: DVec3| DVec3::new(-p.y, p.x, 0.0).cross(p2 - p1);
                let mut n = normal(p);
                if n.length_squared() == 0.0 {
                    // On the axis the surface has no normal; take its neighbour's.
                    n = normal(p1 + (0.5 + 0.999 * (t - 0.5)) * (p2 - p1));
                }
                (p, n.normalize_or_zero(), t)
            }
            Quadric::Sphere {
                radius,
                z_min,
                z_max,
                ..
            } => {
                let (theta_low, theta_high) = (
                    (z_min / radius).clamp(-1.0, 1.0).acos(),
                    (z_max / radius).clamp(-1.0, 1.0).acos(),
                );
                let theta = theta_low + t * (theta_high - theta_low);
                let n = DVec3::new(theta.sin(), 0.0, theta.cos());
                (radius * n, n, t)
            }
        }
    }

    /// The closed-form area of the surface (the hyperboloid's by quadrature of its
    /// meridian, which has no short closed form).
    #[cfg(test)]
    pub(crate) fn area(&self) -> f64 {
        match *self {
            Quadric::Disk {
                radius,
                inner_radius,
                phi_max,
                ..
            } => 0.5 * phi_max * (radius * radius - inner_radius * inner_radius),
            Quadric::Cylinder {
                radius,
                z_min,
                z_max,
                phi_max,
            }
            | Quadric::Sphere {
                radius,
                z_min,
                z_max,
                phi_max,
            } => phi_max * radius * (z_max - z_min),
            Quadric::Cone {
                height,
                radius,
                phi_max,
            } => 0.5 * phi_max * radius * (height * height + radius * radius).sqrt(),
            Quadric::Paraboloid {
                radius,
                z_min,
                z_max,
                phi_max,
            } => {
                let k = 4.0 * z_max / (radius * radius);
                radius.powi(4) * phi_max / (12.0 * z_max * z_max)
                    * ((k * z_max + 1.0).powf(1.5) - (k * z_min + 1.0).powf(1.5))
            }
            Quadric::Hyperboloid { p1, p2, phi_max } => {
                // φ_max ∫ ρ(t) |(ρ'(t), z'(t))| dt by Simpson's rule.
                let n = 20_000;
                let rho = |t: f64| (p1 + t * (p2 - p1)).truncate().length();
                let integrand = |t: f64| {
                    let h = 1e-7;
                    let d_rho = (rho((t + h).min(1.0)) - rho((t - h).max(0.0)))
                        / ((t + h).min(1.0) - (t - h).max(0.0));
                    rho(t) * (d_rho * d_rho + (p2.z - p1.z).powi(2)).sqrt()
                };
                let step = 1.0 / n as f64;
                let mut sum = integrand(0.0) + integrand(1.0);
                for k in 1..n {
                    sum += integrand(k as f64 * step) * if k % 2 == 1 { 4.0 } else { 2.0 };
                }
                phi_max * sum * step / 3.0
            }
        }
    }

    /// The surface's point, unit normal and pbrt (u, v) at grid parameters (s, t) ∈ [0, 1]².
    fn at(&self, s: f64, t: f64) -> (DVec3, DVec3, [f64; 2]) {
        let (p, n, v) = self.meridian(t);
        let phi = s * self.phi_max();
        // The seam of a closed quadric meets its start exactly.
        let (sin, cos) = if s == 1.0 && self.phi_max() >= std::f64::consts::TAU {
            (0.0, 1.0)
        } else {
            phi.sin_cos()
        };
        let turn = |q: DVec3| DVec3::new(q.x * cos - q.y * sin, q.x * sin + q.y * cos, q.z);
        (turn(p), turn(n), [s, v])
    }

    /// Triangles within [`RELATIVE_ERROR_BOUND`] × [`Quadric::radius`] of the surface
    /// (measured: see [`Grid::deviation`]), with the surface's normals at the vertices.
    /// Fails only when that would take more than [`MAX_CELLS`] cells.
    pub(crate) fn tessellate(&self) -> Result<Tessellation, String> {
        let bound = RELATIVE_ERROR_BOUND * self.radius();
        let grid = self.grid_within(bound)?;
        Ok(grid.tessellation(self))
    }

    fn grid_within(&self, bound: f64) -> Result<Grid, String> {
        // A circle of radius R cut into chords of angle Δφ strays R(1 − cos(Δφ/2)) from
        // them: start from half the bound around, one step along the meridian.
        let half_step = (1.0 - 0.5 * RELATIVE_ERROR_BOUND).acos();
        let mut grid = Grid {
            around: ((self.phi_max() / (2.0 * half_step)).ceil() as usize).max(1),
            along: 1,
        };
        let grow = |n: usize, ratio: f64| {
            let factor = ratio.sqrt().clamp(1.1, 64.0);
            ((n as f64 * factor).ceil() as usize).max(n + 1)
        };
        loop {
            let d = grid.deviation(self);
            if !(d.overall.is_finite() && d.normal_gap.is_finite()) {
                return Err("its surface is not finite in its own space".into());
            }
            if d.overall <= bound && d.normal_gap <= NORMAL_GAP {
                return Ok(grid);
            }
            let sagitta = d.along_meridian.max(d.around);
            if d.overall > bound && sagitta > 0.45 * bound {
                if d.along_meridian >= d.around {
                    grid.along = grow(grid.along, d.along_meridian.max(d.overall) / (0.45 * bound));
                } else {
                    grid.around = grow(grid.around, d.around.max(d.overall) / (0.45 * bound));
                }
            } else {
                // The cells' edges follow the surface but their insides do not (a twisted
                // cell), or lie close to it but tilted (slivers on a saddle, as in Schwarz's
                // lantern): shorten the cells' long side.
                let ratio = (d.overall / (0.9 * bound)).max(d.normal_gap / (0.9 * NORMAL_GAP));
                if d.along_length >= d.around_length {
                    grid.along = grow(grid.along, ratio);
                } else {
                    grid.around = grow(grid.around, ratio);
                }
            }
            if grid.around.saturating_mul(grid.along) > MAX_CELLS {
                return Err(format!(
                    "needs more than {MAX_CELLS} grid cells to stay within {RELATIVE_ERROR_BOUND} of its radius {}",
                    self.radius()
                ));
            }
        }
    }
}

/// `around` cells in φ by `along` cells along the meridian.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Grid {
    pub around: usize,
    pub along: usize,
}

/// How far the surface strays from a grid's triangles: at the midpoints of the edges around
/// and along, and anywhere sampled.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Deviation {
    pub around: f64,
    pub along_meridian: f64,
    pub overall: f64,
    /// The largest 1 − |cos| between a triangle's normal and the surface's at its centre.
    pub normal_gap: f64,
    /// The longest cell edges around and along, in space.
    pub around_length: f64,
    pub along_length: f64,
}

impl Grid {
    fn vertex(&self, i: usize, j: usize) -> u32 {
        (i + j * (self.around + 1)) as u32
    }

    /// The cell's two triangles as vertex (i, j) pairs, leaving out the one that collapses
    /// where a row of the grid is a single point (a pole, an apex, a disk's centre).
    fn cell_triangles(
        &self,
        i: usize,
        j: usize,
        row_is_point: &[bool],
    ) -> Vec<[(usize, usize); 3]> {
        let (a, b, c, d) = ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1));
        let mut out = Vec::with_capacity(2);
        if !row_is_point[j] {
            out.push([a, b, c]);
        }
        if !row_is_point[j + 1] {
            out.push([a, c, d]);
        }
        out
    }

    fn rows_that_are_points(&self, q: &Quadric) -> Vec<bool> {
        (0..=self.along)
            .map(|j| q.meridian(j as f64 / self.along as f64).0.truncate() == glam::DVec2::ZERO)
            .collect()
    }

    /// The surface's distance from the triangles of one column of cells, sampled on a 5 × 5
    /// lattice in each cell's (s, t) (the quadrics turn about z, so every column is alike).
    pub(crate) fn deviation(&self, q: &Quadric) -> Deviation {
        let points = self.rows_that_are_points(q);
        let st = |i: f64, j: f64| (i / self.around as f64, j / self.along as f64);
        let point = |i: f64, j: f64| {
            let (s, t) = st(i, j);
            q.at(s, t).0
        };
        let mut d = Deviation {
            around: 0.0,
            along_meridian: 0.0,
            overall: 0.0,
            normal_gap: 0.0,
            around_length: 0.0,
            along_length: 0.0,
        };
        for j in 0..self.along {
            let corners = self.cell_triangles(0, j, &points);
            let triangles: Vec<[DVec3; 3]> = corners
                .iter()
                .map(|t| t.map(|(i, j)| point(i as f64, j as f64)))
                .collect();
            for (corner, [a, b, c]) in corners.iter().zip(&triangles) {
                let centre = corner.iter().fold((0.0, 0.0), |(i, j), &(ci, cj)| {
                    (i + ci as f64 / 3.0, j + cj as f64 / 3.0)
                });
                let (s, t) = st(centre.0, centre.1);
                let surface_normal = q.at(s, t).1;
                let face = (*b - *a).cross(*c - *a).normalize_or_zero();
                if face == DVec3::ZERO {
                    // A sliver too thin to have a direction adds no area either.
                    continue;
                }
                d.normal_gap = d.normal_gap.max(1.0 - face.dot(surface_normal).abs());
            }
            let (a, b, c) = (
                point(0.0, j as f64),
                point(1.0, j as f64),
                point(0.0, j as f64 + 1.0),
            );
            d.around_length = d.around_length.max((b - a).length());
            d.along_length = d.along_length.max((c - a).length());
            for a in 0..=4 {
                for b in 0..=4 {
                    let p = point(a as f64 / 4.0, j as f64 + b as f64 / 4.0);
                    let distance = triangles
                        .iter()
                        .map(|t| distance_to_triangle(p, *t))
                        .fold(f64::INFINITY, f64::min);
                    d.overall = d.overall.max(distance);
                    if a == 2 && (b == 0 || b == 4) {
                        d.around = d.around.max(distance);
                    }
                    if b == 2 && (a == 0 || a == 4) {
                        d.along_meridian = d.along_meridian.max(distance);
                    }
                }
            }
        }
        d
    }

    fn tessellation(&self, q: &Quadric) -> Tessellation {
        let mut out = Tessellation {
            normals: Some(Vec::new()),
            ..Tessellation::default()
        };
        let normals = out.normals.as_mut().expect("just set");
        for j in 0..=self.along {
            for i in 0..=self.around {
                let (p, n, uv) = q.at(i as f64 / self.around as f64, j as f64 / self.along as f64);
                out.positions.push(p.as_vec3());
                normals.push(n.as_vec3());
                out.uv.push(uv.map(|x| x as f32));
            }
        }
        let points = self.rows_that_are_points(q);
        for j in 0..self.along {
            for i in 0..self.around {
                for t in self.cell_triangles(i, j, &points) {
                    out.triangles.push(t.map(|(i, j)| self.vertex(i, j)));
                }
            }
        }
        out
    }
}

/// The distance from `p` to the triangle `t` (its closest point may lie on an edge or a
/// corner). A triangle with no area is measured along its longest edge.
pub(crate) fn distance_to_triangle(p: DVec3, [a, b, c]: [DVec3; 3]) -> f64 {
    let normal = (b - a).cross(c - a);
    if normal.length_squared() > 0.0 {
        let n = normal.normalize();
        let q = p - n * (p - a).dot(n);
        // Inside when q is on the inner side of all three edges.
        let inside = [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(e0, e1)| (e1 - e0).cross(q - e0).dot(normal) >= 0.0);
        if inside {
            return (p - q).length();
        }
    }
    [(a, b), (b, c), (c, a)]
        .iter()
        .map(|&(e0, e1)| distance_to_segment(p, e0, e1))
        .fold(f64::INFINITY, f64::min)
}

fn distance_to_segment(p: DVec3, a: DVec3, b: DVec3) -> f64 {
    let e = b - a;
    let t = if e.length_squared() > 0.0 {
        ((p - a).dot(e) / e.length_squared()).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p - (a + t * e)).length()
}
