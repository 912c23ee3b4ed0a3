//! Curves in a scene description: world-space cubic Bézier segments with a radius (half the
//! width) and, for ribbons, a normal at every control point, one material a geometry — what
//! pbrt's `curve` shape becomes once its basis, degree, widths and transform are resolved
//! (by the pbrt reader). Owns the curve types, the rules a [`Curves`] obeys
//! ([`check_curves`]) and its bounds; must not know pbrt's parameters or Embree.

use super::InvalidField;
use glam::Vec3;

/// How a curve's cross-section is drawn, as pbrt's curve `type` names it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CurveKind {
    /// A band as wide as the curve that always faces the viewer (pbrt's `flat`).
    Flat,
    /// A band turned by the curve's normals: its width runs along normal × tangent, so seen
    /// edge on it vanishes (pbrt's `ribbon`).
    Ribbon,
    /// A tube: a circle of the radius swept along the curve (pbrt's `cylinder`, which pbrt
    /// shades as a tube on a flat band; dpm intersects the tube itself).
    Cylinder,
}

/// World-space cubic Bézier curve segments with one material. Segment `k` is the four
/// control points `points[4k..4k + 4]`; `radii` (as many as `points`, each ≥ 0, some > 0 in
/// every segment) are the Bézier control values of the half-width along it, and `normals`
/// (ribbons only, and always for them: finite and non-zero, one per control point) those of
/// the ribbon's normal, whose direction alone counts at each point. A curve has no inside: light meets it on either side (a cylinder's tube aside).
/// Texture coordinates are pbrt's: u from 0 to 1 along each segment, v from 0 to 1 across.
#[derive(Clone, Debug, PartialEq)]
pub struct Curves {
    pub kind: CurveKind,
    pub points: Vec<Vec3>,
    pub radii: Vec<f32>,
    pub normals: Option<Vec<Vec3>>,
    /// Indexes [`super::SceneDescription::materials`].
    pub material: u32,
}

impl Curves {
    pub fn segment_count(&self) -> usize {
        self.points.len() / 4
    }

    /// A box around the curves: a Bézier segment lies in its control points' hull, and its
    /// radius is at most its largest control radius.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        let mut lo = Vec3::MAX;
        let mut hi = Vec3::MIN;
        for (segment, radii) in self.points.chunks(4).zip(self.radii.chunks(4)) {
            let r = Vec3::splat(radii.iter().fold(0.0f32, |a, &b| a.max(b)));
            for p in segment {
                (lo, hi) = (lo.min(*p - r), hi.max(*p + r));
            }
        }
        (lo, hi)
    }
}

/// Checks curves against the rules [`Curves`] states; the error names the field as the
/// struct spells it (`points[5]`, `radii[2]`, `normals`).
pub fn check_curves(curves: &Curves) -> Result<(), InvalidField> {
    let n = curves.points.len();
    if n == 0 || !n.is_multiple_of(4) {
        return Err(InvalidField::new(
            "points",
            format!("{n} control points: four a segment, and at least one segment"),
        ));
    }
    if let Some(i) = curves.points.iter().position(|p| !p.is_finite()) {
        return Err(InvalidField::new(format!("points[{i}]"), "is not finite"));
    }
    if curves.radii.len() != n {
        return Err(InvalidField::new(
            "radii",
            format!("{} radii for {n} control points", curves.radii.len()),
        ));
    }
    if let Some(i) = (curves.radii.iter()).position(|r| !r.is_finite() || *r < 0.0) {
        return Err(InvalidField::new(
            format!("radii[{i}]"),
            "is negative or not finite",
        ));
    }
    if let Some(k) = (curves.radii.chunks(4)).position(|r| r.iter().all(|&r| r == 0.0)) {
        return Err(InvalidField::new(
            format!("radii[{}]", 4 * k),
            format!("segment {k} has no width"),
        ));
    }
    match (&curves.normals, curves.kind) {
        (None, CurveKind::Ribbon) => Err(InvalidField::new("normals", "a ribbon needs normals")),
        (Some(_), CurveKind::Flat | CurveKind::Cylinder) => {
            Err(InvalidField::new("normals", "only ribbons have normals"))
        }
        (Some(normals), _) if normals.len() != n => Err(InvalidField::new(
            "normals",
            format!("{} normals for {n} control points", normals.len()),
        )),
        (Some(normals), _) => {
            match (normals.iter()).position(|v| !v.is_finite() || *v == Vec3::ZERO) {
                Some(i) => Err(InvalidField::new(
                    format!("normals[{i}]"),
                    "is zero or not finite",
                )),
                None => Ok(()),
            }
        }
        (None, _) => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat() -> Curves {
        Curves {
            kind: CurveKind::Flat,
            points: vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 1.0, 0.0), Vec3::Y],
            radii: vec![0.5, 0.4, 0.3, 0.0],
            normals: None,
            material: 0,
        }
    }

    #[test]
    fn curves_are_bounded_by_their_hull_grown_by_the_radius() {
        let c = flat();
        check_curves(&c).unwrap();
        assert_eq!(c.segment_count(), 1);
        assert_eq!(
            c.bounds(),
            (Vec3::new(-0.5, -0.5, -0.5), Vec3::new(2.5, 1.5, 0.5))
        );
    }

    #[test]
    fn curves_breaking_a_rule_are_named_by_field() {
        let field = |c: Curves| check_curves(&c).unwrap_err().field;
        let mut c = flat();
        c.points.pop();
        assert_eq!(field(c), "points");
        let mut c = flat();
        c.points[2].y = f32::INFINITY;
        assert_eq!(field(c), "points[2]");
        let mut c = flat();
        c.radii[1] = -1.0;
        assert_eq!(field(c), "radii[1]");
        let mut c = flat();
        c.radii = vec![0.0; 4];
        assert_eq!(field(c), "radii[0]");
        let mut c = flat();
        c.kind = CurveKind::Ribbon;
        assert_eq!(field(c.clone()), "normals");
        c.normals = Some(vec![Vec3::Z, Vec3::Z, Vec3::Z, Vec3::ZERO]);
        assert_eq!(field(c.clone()), "normals[3]");
        c.normals = Some(vec![Vec3::Z; 4]);
        check_curves(&c).unwrap();
        c.kind = CurveKind::Cylinder;
        assert_eq!(field(c), "normals");
    }
}
