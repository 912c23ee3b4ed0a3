//! pbrt's `curve` shape as dpm's [`Curves`]: its control points (`P`, Bézier or uniform
//! B-spline `basis`, `degree` 2 or 3) turned into world-space cubic Bézier segments exactly (a
//! B-spline segment by its Bézier points, a quadratic raised to a cubic), its width
//! (`width`, or `width0` to `width1` along the whole curve) into Bézier control radii, and a
//! ribbon's end normals (`N`, which pbrt interpolates along each segment by spherical
//! interpolation) into control normals that match them at the ends and at a third and two
//! thirds of the way. `splitdepth` is read past: Embree intersects curves whole. Owns that
//! conversion; must not choose materials or know Embree.

use super::super::parser::ShapeItem;
use super::shapes::Geometry;
use super::{Mapper, param_error, require, value_error};
use crate::scene::{CurveKind, Curves, SceneError, check_curves};
use glam::{Mat3, Vec3};

impl Mapper<'_> {
    pub(super) fn curve(&mut self, shape: &ShapeItem) -> Result<Geometry, SceneError> {
        let item = &shape.item;
        let p = |e| param_error("Shape", e);
        let degree = item.params.integer("degree").map_err(p)?.unwrap_or(3);
        if degree != 2 && degree != 3 {
            return Err(value_error(
                item,
                "Shape",
                "degree",
                format!("degree {degree}: curves are of degree 2 or 3"),
            ));
        }
        let degree = degree as usize;
        let bspline = match item.params.string("basis").map_err(p)?.as_deref() {
            None | Some("bezier") => false,
            Some("bspline") => true,
            Some(other) => {
                return Err(value_error(
                    item,
                    "Shape",
                    "basis",
                    format!("basis \"{other}\": a curve's basis is \"bezier\" or \"bspline\""),
                ));
            }
        };
        let kind = match item.params.string("type").map_err(p)?.as_deref() {
            None | Some("flat") => CurveKind::Flat,
            Some("ribbon") => CurveKind::Ribbon,
            Some("cylinder") => CurveKind::Cylinder,
            Some(other) => {
                return Err(value_error(
                    item,
                    "Shape",
                    "type",
                    format!("type \"{other}\": a curve is \"flat\", \"ribbon\" or \"cylinder\""),
                ));
            }
        };
        let points = require(item.params.vec3s("P"), item, "P", "Shape")?;
        let n = points.len();
        let segments = match bspline {
            false if n > degree && (n - 1) % degree == 0 => (n - 1) / degree,
            true if n > degree => n - degree,
            false => {
                return Err(value_error(
                    item,
                    "Shape",
                    "P",
                    format!(
                        "{n} control points: a degree {degree} Bézier curve has {} + {degree}·k",
                        degree + 1
                    ),
                ));
            }
            true => {
                return Err(value_error(
                    item,
                    "Shape",
                    "P",
                    format!(
                        "{n} control points: a degree {degree} B-spline has at least {}",
                        degree + 1
                    ),
                ));
            }
        };
        let width = item.params.float("width").map_err(p)?.unwrap_or(1.0);
        let width0 = item.params.float("width0").map_err(p)?.unwrap_or(width);
        let width1 = item.params.float("width1").map_err(p)?.unwrap_or(width);
        for (name, w) in [("width", width), ("width0", width0), ("width1", width1)] {
            if !(w.is_finite() && w >= 0.0) {
                return Err(value_error(
                    item,
                    "Shape",
                    name,
                    format!("width {w} is negative or not finite"),
                ));
            }
        }
        if width0 == 0.0 && width1 == 0.0 {
            let given = ["width0", "width1"]
                .into_iter()
                .find(|n| item.params.at(n).is_some());
            return Err(value_error(
                item,
                "Shape",
                given.unwrap_or("width"),
                "the curve has no width".into(),
            ));
        }
        let end_normals = item.params.vec3s("N").map_err(p)?;
        let end_normals = match (kind, end_normals) {
            (CurveKind::Ribbon, None) => {
                return Err(item.at.error(
                    "Shape",
                    "a \"ribbon\" curve needs \"normal N\": one normal at each segment's ends",
                ));
            }
            (CurveKind::Ribbon, Some(normals)) if normals.len() != segments + 1 => {
                return Err(value_error(
                    item,
                    "Shape",
                    "N",
                    format!(
                        "{} normals for {segments} segments: a ribbon has one more normal than segments",
                        normals.len()
                    ),
                ));
            }
            (CurveKind::Ribbon, Some(normals)) => {
                if let Some(i) = normals
                    .iter()
                    .position(|n| !n.is_finite() || *n == Vec3::ZERO)
                {
                    return Err(value_error(
                        item,
                        "Shape",
                        "N",
                        format!("normal {i} is zero or not finite"),
                    ));
                }
                Some(normals)
            }
            (_, Some(_)) => {
                self.warn(&item.at, "Shape \"curve\": \"N\" is read only for \"ribbon\" curves, and ignored (as pbrt does)".into());
                None
            }
            (_, None) => None,
        };
        item.params.mark_used("splitdepth");

        let scale = self.curve_scale(shape);
        let ctm = shape.ctm;
        let normal_matrix = Mat3::from_mat4(ctm).inverse().transpose();
        let mut curves = Curves {
            kind,
            points: Vec::with_capacity(4 * segments),
            radii: Vec::with_capacity(4 * segments),
            normals: end_normals
                .as_ref()
                .map(|_| Vec::with_capacity(4 * segments)),
            material: 0,
        };
        for k in 0..segments {
            let bezier = bezier_segment(&points, k, degree, bspline);
            curves
                .points
                .extend(bezier.map(|p| ctm.transform_point3(p)));
            for j in 0..4 {
                // The width is linear along the whole curve: its cubic control values on
                // segment k are its values at k/n, (k + 1/3)/n, (k + 2/3)/n and (k + 1)/n.
                let t = (k as f32 + j as f32 / 3.0) / segments as f32;
                curves
                    .radii
                    .push(0.5 * scale * ((1.0 - t) * width0 + t * width1));
            }
            if let (Some(out), Some(ends)) = (&mut curves.normals, &end_normals) {
                let control = ribbon_normals(ends[k], ends[k + 1]);
                out.extend(control.map(|n| normal_matrix * n));
            }
        }
        if curves.points.iter().any(|p| !p.is_finite()) {
            return Err(item
                .at
                .error("Shape", "a transformed control point is not finite"));
        }
        if let Some(normals) = &curves.normals
            && normals.iter().any(|n| !n.is_finite() || *n == Vec3::ZERO)
        {
            return Err(value_error(
                item,
                "Shape",
                "N",
                "a transformed normal is zero or not finite".into(),
            ));
        }
        check_curves(&curves).map_err(|why| item.at.error("Shape", format!("the curve: {why}")))?;
        Ok(Geometry::Curves(curves))
    }

    /// What the shape's transform scales a curve's width by: its scale when it is a uniform
    /// scale with a rotation, else the cube root of its determinant's size (the scale that
    /// keeps volumes), with a warning, since pbrt's width then stretches with the direction.
    fn curve_scale(&mut self, shape: &ShapeItem) -> f32 {
        let m = Mat3::from_mat4(shape.ctm);
        let scales = [m.x_axis.length(), m.y_axis.length(), m.z_axis.length()];
        let mean = scales.iter().sum::<f32>() / 3.0;
        let skew = m.x_axis.dot(m.y_axis).abs()
            + m.y_axis.dot(m.z_axis).abs()
            + m.x_axis.dot(m.z_axis).abs();
        if scales.iter().all(|s| (s - mean).abs() <= 1e-5 * mean) && skew <= 1e-5 * mean * mean {
            return mean;
        }
        let scale = m.determinant().abs().cbrt();
        let at = shape.item.at.clone();
        self.warn(&at, format!("Shape \"curve\": the transform does not scale evenly; the width is scaled by {scale} (the cube root of its determinant)"));
        scale
    }
}

/// The cubic Bézier control points of segment `k` of a curve of `degree` (2 or 3) given by
/// `p` in the Bézier basis (segments sharing end points) or the uniform B-spline basis.
pub(super) fn bezier_segment(p: &[Vec3], k: usize, degree: usize, bspline: bool) -> [Vec3; 4] {
    // The quadratic with control points a, b, c as a cubic.
    let raise =
        |a: Vec3, b: Vec3, c: Vec3| [a, a / 3.0 + b * (2.0 / 3.0), b * (2.0 / 3.0) + c / 3.0, c];
    match (bspline, degree) {
        (false, 2) => raise(p[2 * k], p[2 * k + 1], p[2 * k + 2]),
        (false, _) => [p[3 * k], p[3 * k + 1], p[3 * k + 2], p[3 * k + 3]],
        // A quadratic B-spline segment's Bézier points: the midpoints around its middle point.
        (true, 2) => raise(
            0.5 * (p[k] + p[k + 1]),
            p[k + 1],
            0.5 * (p[k + 1] + p[k + 2]),
        ),
        (true, _) => {
            let [a, b, c, d] = [p[k], p[k + 1], p[k + 2], p[k + 3]];
            [
                (a + 4.0 * b + c) / 6.0,
                (2.0 * b + c) / 3.0,
                (b + 2.0 * c) / 3.0,
                (b + 4.0 * c + d) / 6.0,
            ]
        }
    }
}

/// pbrt's ribbon normal a fraction `u` along a segment with (unit) end normals `n0`, `n1`:
/// their spherical interpolation, the angle between them taken as pbrt takes it (from their
/// dot product clamped to [0, 1], so at most 90°); nearly parallel ends interpolate linearly.
fn slerp(n0: Vec3, n1: Vec3, u: f32) -> Vec3 {
    let angle = n0.dot(n1).clamp(0.0, 1.0).acos();
    let sin = angle.sin();
    if sin < 1e-4 {
        return (1.0 - u) * n0 + u * n1;
    }
    (((1.0 - u) * angle).sin() * n0 + (u * angle).sin() * n1) / sin
}

/// Cubic Bézier control normals whose curve is pbrt's interpolated normal at u = 0, 1/3, 2/3
/// and 1 of the segment from end normal `a` to `b`. The Bézier values at 1/3 and 2/3 are
/// (8N0 + 12N1 + 6N2 + N3)/27 and (N0 + 6N1 + 12N2 + 8N3)/27; solved for N1 and N2.
pub(super) fn ribbon_normals(a: Vec3, b: Vec3) -> [Vec3; 4] {
    let (n0, n3) = (a.normalize(), b.normalize());
    let s1 = 27.0 * slerp(n0, n3, 1.0 / 3.0) - 8.0 * n0 - n3;
    let s2 = 27.0 * slerp(n0, n3, 2.0 / 3.0) - n0 - 8.0 * n3;
    [n0, (2.0 * s1 - s2) / 18.0, (2.0 * s2 - s1) / 18.0, n3]
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bezier_at(c: [Vec3; 4], u: f32) -> Vec3 {
        let v = 1.0 - u;
        v * v * v * c[0] + 3.0 * v * v * u * c[1] + 3.0 * v * u * u * c[2] + u * u * u * c[3]
    }

    #[test]
    fn ribbon_control_normals_follow_pbrt_s_interpolation() {
        for (a, b) in [
            (Vec3::Z, Vec3::X),
            (Vec3::Z, Vec3::Z),
            (Vec3::new(-0.1, 0.0, 1.0), Vec3::new(-0.7, 0.1, 0.4)),
        ] {
            let c = ribbon_normals(a, b);
            let (a, b) = (a.normalize(), b.normalize());
            for u in [0.0, 1.0 / 3.0, 2.0 / 3.0, 1.0] {
                let want = slerp(a, b, u);
                assert!((bezier_at(c, u) - want).length() < 1e-5, "{u}");
            }
            // In between, the direction is within a degree of pbrt's.
            for k in 0..=20 {
                let u = k as f32 / 20.0;
                let cos = bezier_at(c, u).normalize().dot(slerp(a, b, u).normalize());
                assert!(cos > 1f32.to_radians().cos(), "{u}: {cos}");
            }
        }
    }

    #[test]
    fn bases_and_degrees_become_the_same_cubic() {
        // The quadratic a, b, c is a(1−u)² + 2b(1−u)u + cu².
        let [a, b, c] = [
            Vec3::ZERO,
            Vec3::new(1.0, 2.0, 0.0),
            Vec3::new(3.0, 0.0, 1.0),
        ];
        let cubic = bezier_segment(&[a, b, c], 0, 2, false);
        for u in [0.0, 0.3, 0.5, 0.9, 1.0] {
            let v = 1.0 - u;
            let want = a * v * v + 2.0 * b * v * u + c * u * u;
            assert!((bezier_at(cubic, u) - want).length() < 1e-5);
        }
    }
}
