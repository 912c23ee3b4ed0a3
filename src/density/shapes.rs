//! The plane shapes the built-in photon distributions are made of: each knows its density
//! profile (1 at its densest), its mass (the profile's integral), how to draw a point from the
//! profile, and where its profile jumps (discontinuities) or bends (kinks). Owns 2-D geometry
//! only; it knows nothing of photons, images or estimates.

use super::rng::SplitMix64;
use glam::DVec2;
use std::f64::consts::TAU;

/// A place where the density changes abruptly, as a curve in the plane.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Curve {
    Segment {
        a: DVec2,
        b: DVec2,
    },
    /// The arc of the circle (`centre`, `radius`) from angle `start` counter-clockwise to `end`
    /// (radians, `start < end`); a full circle is `0..TAU`.
    Arc {
        centre: DVec2,
        radius: f64,
        start: f64,
        end: f64,
    },
}

impl Curve {
    pub fn distance(&self, p: DVec2) -> f64 {
        match *self {
            Curve::Segment { a, b } => distance_to_segment(p, a, b),
            Curve::Arc {
                centre,
                radius,
                start,
                end,
            } => {
                let d = p - centre;
                let angle = d.y.atan2(d.x).rem_euclid(TAU);
                // The angle may also be matched one turn up, for arcs that pass through 0.
                let within = |t: f64| t >= start && t <= end;
                if within(angle) || within(angle + TAU) {
                    (d.length() - radius).abs()
                } else {
                    let at = |t: f64| centre + radius * DVec2::new(t.cos(), t.sin());
                    p.distance(at(start)).min(p.distance(at(end)))
                }
            }
        }
    }
}

pub fn distance_to_segment(p: DVec2, a: DVec2, b: DVec2) -> f64 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(f64::MIN_POSITIVE)).clamp(0.0, 1.0);
    p.distance(a + t * ab)
}

/// A rectangle's frame: centre, unit axis `u` (the `half.x` direction) and half sizes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub centre: DVec2,
    pub u: DVec2,
    pub half: DVec2,
}

impl Frame {
    pub fn new(centre: DVec2, angle_degrees: f64, half: DVec2) -> Self {
        let a = angle_degrees.to_radians();
        Self {
            centre,
            u: DVec2::new(a.cos(), a.sin()),
            half,
        }
    }
    fn v(&self) -> DVec2 {
        self.u.perp()
    }
    /// Coordinates of `p` along `u` and `v`.
    pub fn local(&self, p: DVec2) -> DVec2 {
        let d = p - self.centre;
        DVec2::new(d.dot(self.u), d.dot(self.v()))
    }
    pub fn world(&self, l: DVec2) -> DVec2 {
        self.centre + l.x * self.u + l.y * self.v()
    }
    fn inside(&self, l: DVec2) -> bool {
        l.x.abs() <= self.half.x && l.y.abs() <= self.half.y
    }
    /// The side of the rectangle at local `(sx·half.x, ·)` (sx = ±1, across `v`) or at local
    /// `(·, sy·half.y)` (along `u`).
    fn side_across(&self, sx: f64) -> Curve {
        let (h, x) = (self.half, sx * self.half.x);
        Curve::Segment {
            a: self.world(DVec2::new(x, -h.y)),
            b: self.world(DVec2::new(x, h.y)),
        }
    }
    fn side_along(&self, sy: f64) -> Curve {
        let (h, y) = (self.half, sy * self.half.y);
        Curve::Segment {
            a: self.world(DVec2::new(-h.x, y)),
            b: self.world(DVec2::new(h.x, y)),
        }
    }
    fn all_sides(&self) -> Vec<Curve> {
        vec![
            self.side_across(-1.0),
            self.side_across(1.0),
            self.side_along(-1.0),
            self.side_along(1.0),
        ]
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape {
    Disc {
        centre: DVec2,
        radius: f64,
    },
    /// A uniform rectangle (also the thin line: a long, narrow rectangle).
    Rectangle(Frame),
    /// A tent across `v`: 1 on the centre line (along `u`), falling linearly to 0 at `±half.y`.
    Ridge(Frame),
    /// A ramp along `u`: 0 at `-half.x`, rising linearly to 1 at `+half.x`.
    Ramp(Frame),
    Triangle([DVec2; 3]),
    Annulus {
        centre: DVec2,
        inner: f64,
        outer: f64,
    },
    /// The part of an annulus between two angles (degrees, counter-clockwise from `start`).
    ArcBand {
        centre: DVec2,
        inner: f64,
        outer: f64,
        start: f64,
        end: f64,
    },
}

impl Shape {
    /// The density profile at `p`, in [0, 1].
    pub fn profile(&self, p: DVec2) -> f64 {
        match *self {
            Shape::Disc { centre, radius } => inside(p.distance_squared(centre) <= radius * radius),
            Shape::Rectangle(f) => inside(f.inside(f.local(p))),
            Shape::Ridge(f) => {
                let l = f.local(p);
                if f.inside(l) {
                    1.0 - l.y.abs() / f.half.y
                } else {
                    0.0
                }
            }
            Shape::Ramp(f) => {
                let l = f.local(p);
                if f.inside(l) {
                    (l.x + f.half.x) / (2.0 * f.half.x)
                } else {
                    0.0
                }
            }
            Shape::Triangle(t) => inside(in_triangle(p, t)),
            Shape::Annulus {
                centre,
                inner,
                outer,
            } => {
                let d = p.distance(centre);
                inside(d >= inner && d <= outer)
            }
            Shape::ArcBand {
                centre,
                inner,
                outer,
                start,
                end,
            } => {
                let d = p - centre;
                let r = d.length();
                let angle = d.y.atan2(d.x).to_degrees().rem_euclid(360.0);
                let within = |a: f64| a >= start && a <= end;
                inside(r >= inner && r <= outer && (within(angle) || within(angle + 360.0)))
            }
        }
    }

    /// The integral of the profile over the plane.
    pub fn mass(&self) -> f64 {
        match *self {
            Shape::Disc { radius, .. } => std::f64::consts::PI * radius * radius,
            Shape::Rectangle(f) => 4.0 * f.half.x * f.half.y,
            Shape::Ridge(f) | Shape::Ramp(f) => 2.0 * f.half.x * f.half.y,
            Shape::Triangle([a, b, c]) => 0.5 * (b - a).perp_dot(c - a).abs(),
            Shape::Annulus { inner, outer, .. } => {
                std::f64::consts::PI * (outer * outer - inner * inner)
            }
            Shape::ArcBand {
                inner,
                outer,
                start,
                end,
                ..
            } => 0.5 * (end - start).to_radians() * (outer * outer - inner * inner),
        }
    }

    /// A point drawn with probability density `profile / mass`.
    pub fn sample(&self, rng: &mut SplitMix64) -> DVec2 {
        let (u1, u2) = (rng.next_f64(), rng.next_f64());
        match *self {
            Shape::Disc { centre, radius } => centre + radius * u1.sqrt() * unit(TAU * u2),
            Shape::Rectangle(f) => f.world(f.half * DVec2::new(2.0 * u1 - 1.0, 2.0 * u2 - 1.0)),
            Shape::Ridge(f) => {
                // The sum of two uniforms has the tent density on [0, 2].
                let across = rng.next_f64() + u2 - 1.0;
                f.world(DVec2::new(f.half.x * (2.0 * u1 - 1.0), f.half.y * across))
            }
            Shape::Ramp(f) => {
                // Inverse of the cumulative of a density rising linearly from 0 to 1.
                f.world(DVec2::new(
                    f.half.x * (2.0 * u1.sqrt() - 1.0),
                    f.half.y * (2.0 * u2 - 1.0),
                ))
            }
            Shape::Triangle([a, b, c]) => {
                let s = u1.sqrt();
                a * (1.0 - s) + b * (s * (1.0 - u2)) + c * (s * u2)
            }
            Shape::Annulus {
                centre,
                inner,
                outer,
            } => centre + annulus_radius(inner, outer, u1) * unit(TAU * u2),
            Shape::ArcBand {
                centre,
                inner,
                outer,
                start,
                end,
            } => {
                let angle = (start + (end - start) * u2).to_radians();
                centre + annulus_radius(inner, outer, u1) * unit(angle)
            }
        }
    }

    /// Curves where the profile jumps.
    pub fn discontinuities(&self) -> Vec<Curve> {
        match *self {
            Shape::Disc { centre, radius } => vec![circle(centre, radius)],
            Shape::Rectangle(f) => f.all_sides(),
            // The tent is cut off at both ends; its sides fall to 0 continuously.
            Shape::Ridge(f) => vec![f.side_across(-1.0), f.side_across(1.0)],
            // The low end starts at 0; the high end and the long sides jump.
            Shape::Ramp(f) => vec![f.side_across(1.0), f.side_along(-1.0), f.side_along(1.0)],
            Shape::Triangle([a, b, c]) => vec![
                Curve::Segment { a, b },
                Curve::Segment { a: b, b: c },
                Curve::Segment { a: c, b: a },
            ],
            Shape::Annulus {
                centre,
                inner,
                outer,
            } => vec![circle(centre, inner), circle(centre, outer)],
            Shape::ArcBand {
                centre,
                inner,
                outer,
                start,
                end,
            } => {
                let (s, e) = (start.to_radians(), end.to_radians());
                let arc = |radius| Curve::Arc {
                    centre,
                    radius,
                    start: s,
                    end: e,
                };
                let radial = |t: f64| Curve::Segment {
                    a: centre + inner * unit(t),
                    b: centre + outer * unit(t),
                };
                vec![arc(inner), arc(outer), radial(s), radial(e)]
            }
        }
    }

    /// Curves where the profile is continuous but its slope jumps.
    pub fn kinks(&self) -> Vec<Curve> {
        match *self {
            Shape::Ridge(f) => vec![f.side_along(-1.0), f.side_along(1.0), {
                let h = f.half.x;
                Curve::Segment {
                    a: f.world(DVec2::new(-h, 0.0)),
                    b: f.world(DVec2::new(h, 0.0)),
                }
            }],
            Shape::Ramp(f) => vec![f.side_across(-1.0)],
            _ => Vec::new(),
        }
    }
}

fn inside(b: bool) -> f64 {
    if b { 1.0 } else { 0.0 }
}

fn unit(angle: f64) -> DVec2 {
    DVec2::new(angle.cos(), angle.sin())
}

fn circle(centre: DVec2, radius: f64) -> Curve {
    Curve::Arc {
        centre,
        radius,
        start: 0.0,
        end: TAU,
    }
}

/// A radius drawn so that points are uniform over the annulus area.
fn annulus_radius(inner: f64, outer: f64, u: f64) -> f64 {
    (inner * inner + u * (outer * outer - inner * inner)).sqrt()
}

fn in_triangle(p: DVec2, [a, b, c]: [DVec2; 3]) -> bool {
    let s1 = (b - a).perp_dot(p - a);
    let s2 = (c - b).perp_dot(p - b);
    let s3 = (a - c).perp_dot(p - c);
    (s1 >= 0.0 && s2 >= 0.0 && s3 >= 0.0) || (s1 <= 0.0 && s2 <= 0.0 && s3 <= 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn shapes() -> Vec<Shape> {
        let c = DVec2::new(0.5, 0.5);
        vec![
            Shape::Disc {
                centre: c,
                radius: 0.2,
            },
            Shape::Rectangle(Frame::new(c, 30.0, DVec2::new(0.2, 0.05))),
            Shape::Ridge(Frame::new(c, -20.0, DVec2::new(0.25, 0.08))),
            Shape::Ramp(Frame::new(c, 10.0, DVec2::new(0.2, 0.1))),
            Shape::Triangle([
                DVec2::new(0.2, 0.2),
                DVec2::new(0.8, 0.3),
                DVec2::new(0.4, 0.75),
            ]),
            Shape::Annulus {
                centre: c,
                inner: 0.1,
                outer: 0.3,
            },
            Shape::ArcBand {
                centre: c,
                inner: 0.2,
                outer: 0.3,
                start: 300.0,
                end: 420.0,
            },
        ]
    }

    /// The profile integrates to the mass (midpoint rule on a fine grid).
    #[test]
    fn mass_is_the_integral_of_the_profile() {
        let n = 800;
        for s in shapes() {
            let h = 1.0 / n as f64;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    sum += s.profile(DVec2::new((i as f64 + 0.5) * h, (j as f64 + 0.5) * h));
                }
            }
            let integral = sum * h * h;
            assert!(
                (integral - s.mass()).abs() < 0.01 * s.mass(),
                "{s:?}: {integral} vs {}",
                s.mass()
            );
        }
    }

    /// Samples land where the profile is positive, with mean profile matching ∫p²/∫p.
    #[test]
    fn samples_follow_the_profile() {
        for s in shapes() {
            let mut rng = SplitMix64::new(5);
            let n = 40_000;
            let mut mean = 0.0;
            for _ in 0..n {
                let p = s.sample(&mut rng);
                let v = s.profile(p);
                assert!(
                    v > 0.0 || s.discontinuities().iter().any(|c| c.distance(p) < 1e-9),
                    "{s:?} {p}"
                );
                mean += v / n as f64;
            }
            // For a uniform profile every sample sees 1; for the tent and the ramp E[p] = 2/3.
            let expected = match s {
                Shape::Ridge(_) | Shape::Ramp(_) => 2.0 / 3.0,
                _ => 1.0,
            };
            assert!((mean - expected).abs() < 0.01, "{s:?}: {mean}");
        }
    }

    #[test]
    fn distances_to_curves() {
        let arc = Curve::Arc {
            centre: DVec2::ZERO,
            radius: 1.0,
            start: 0.0,
            end: 1.0,
        };
        assert!((arc.distance(DVec2::new(2.0, 0.0)) - 1.0).abs() < 1e-12);
        assert!((arc.distance(DVec2::new(0.0, -1.0)) - 2f64.sqrt()).abs() < 1e-12);
        let seg = Curve::Segment {
            a: DVec2::ZERO,
            b: DVec2::X,
        };
        assert!((seg.distance(DVec2::new(0.5, 0.3)) - 0.3).abs() < 1e-12);
        assert!((seg.distance(DVec2::new(-3.0, 4.0)) - 5.0).abs() < 1e-12);
    }
}
