//! Placement of a mesh in the world: scale, then rotate about x, then y, then z (fixed world
//! axes, degrees, right-hand rule), then translate. Owns the point and normal maps only; the
//! values are checked in `validate` and applied to vertices in `mesh`.

use glam::{Mat3, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Transform {
    /// Rotation times scale.
    linear: Mat3,
    /// Inverse transpose of `linear`: maps normals so they stay perpendicular to surfaces.
    normal_map: Mat3,
    translation: Vec3,
}

impl Transform {
    /// `scale` has positive finite factors, so the map is invertible and keeps orientation.
    pub(crate) fn new(translate: Vec3, rotate_degrees: Vec3, scale: Vec3) -> Transform {
        let rotation = rotation(Vec3::Z, rotate_degrees.z)
            * rotation(Vec3::Y, rotate_degrees.y)
            * rotation(Vec3::X, rotate_degrees.x);
        let linear = rotation * Mat3::from_diagonal(scale);
        // (R S)^-T = R S^-1, exact without a general inverse.
        let normal_map = rotation * Mat3::from_diagonal(scale.recip());
        Transform {
            linear,
            normal_map,
            translation: translate,
        }
    }

    pub(crate) fn point(&self, p: Vec3) -> Vec3 {
        self.linear * p + self.translation
    }

    /// The unit world normal for object-space normal `n` (not necessarily unit); zero when `n`
    /// is zero. In f64, so that a normal whose length squared overflows or underflows f32 (a
    /// file's `vn 0 5e21 1` or `vn 1e-30 0 0`) still has a direction.
    pub(crate) fn normal(&self, n: Vec3) -> Vec3 {
        (self.normal_map.as_dmat3() * n.as_dvec3())
            .normalize_or_zero()
            .as_vec3()
    }
}

/// Sine and cosine of an angle in degrees, exact (0 and ±1) at multiples of 90°, so that a
/// quarter turn maps vertices exactly and two formats placing a mesh the same way agree to
/// the bit.
pub(crate) fn sin_cos_degrees(degrees: f32) -> (f32, f32) {
    let quarter = degrees / 90.0;
    if quarter.fract() == 0.0 && quarter.abs() < 1e6 {
        return match (quarter as i64).rem_euclid(4) {
            0 => (0.0, 1.0),
            1 => (1.0, 0.0),
            2 => (0.0, -1.0),
            _ => (-1.0, 0.0),
        };
    }
    degrees.to_radians().sin_cos()
}

/// Rotation by `degrees` about the unit `axis`, right-hand rule.
pub(crate) fn rotation(axis: Vec3, degrees: f32) -> Mat3 {
    let (s, c) = sin_cos_degrees(degrees);
    let a = axis;
    let t = 1.0 - c;
    Mat3::from_cols(
        Vec3::new(
            a.x * a.x + (1.0 - a.x * a.x) * c,
            a.x * a.y * t + a.z * s,
            a.x * a.z * t - a.y * s,
        ),
        Vec3::new(
            a.x * a.y * t - a.z * s,
            a.y * a.y + (1.0 - a.y * a.y) * c,
            a.y * a.z * t + a.x * s,
        ),
        Vec3::new(
            a.x * a.z * t + a.y * s,
            a.y * a.z * t - a.x * s,
            a.z * a.z + (1.0 - a.z * a.z) * c,
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn rotation_matches_glam_and_is_exact_at_quarter_turns() {
        let axis = Vec3::new(1.0, 2.0, -0.5).normalize();
        let ours = rotation(axis, 37.0);
        let glam = Mat3::from_axis_angle(axis, 37f32.to_radians());
        assert!(ours.abs_diff_eq(glam, 1e-6), "{ours} vs {glam}");
        let q = rotation(Vec3::X, -90.0);
        assert_eq!(q * Vec3::new(0.3, 0.7, 1.9), Vec3::new(0.3, 1.9, -0.7));
        assert_eq!(sin_cos_degrees(540.0), (0.0, -1.0));
    }

    #[test]
    fn rotations_follow_the_right_hand_rule_in_x_y_z_order() {
        let about_x = Transform::new(Vec3::ZERO, Vec3::new(90.0, 0.0, 0.0), Vec3::ONE);
        assert!(close(about_x.point(Vec3::Y), Vec3::Z));
        let about_y = Transform::new(Vec3::ZERO, Vec3::new(0.0, 90.0, 0.0), Vec3::ONE);
        assert!(close(about_y.point(Vec3::Z), Vec3::X));
        // x first (y → z), then z (z stays): a z-first order would give -x instead.
        let x_then_z = Transform::new(Vec3::ZERO, Vec3::new(90.0, 0.0, 90.0), Vec3::ONE);
        assert!(close(x_then_z.point(Vec3::Y), Vec3::Z));
        assert!(close(x_then_z.point(Vec3::X), Vec3::Y));
    }

    #[test]
    fn normals_too_long_or_too_short_for_f32_keep_their_direction() {
        let t = Transform::new(Vec3::ZERO, Vec3::ZERO, Vec3::ONE);
        let long = t.normal(Vec3::new(0.0, 5.5e21, 1.0));
        assert!((long - Vec3::Y).length() < 1e-6, "{long}");
        let short = t.normal(Vec3::new(1e-30, 0.0, 0.0));
        assert_eq!(short, Vec3::X);
        let scaled = Transform::new(Vec3::ZERO, Vec3::ZERO, Vec3::new(1e-20, 1.0, 1.0));
        let n = scaled.normal(Vec3::new(3e30, 1.0, 0.0));
        assert!((n - Vec3::X).length() < 1e-6, "{n}");
        assert_eq!(t.normal(Vec3::ZERO), Vec3::ZERO);
    }

    #[test]
    fn normals_stay_perpendicular_under_non_uniform_scale() {
        let t = Transform::new(
            Vec3::ONE,
            Vec3::new(10.0, 20.0, 30.0),
            Vec3::new(3.0, 0.5, 1.0),
        );
        let tangent = Vec3::new(1.0, -1.0, 0.0);
        let normal = Vec3::new(1.0, 1.0, 0.0);
        let world_tangent = t.point(tangent) - t.point(Vec3::ZERO);
        let world_normal = t.normal(normal);
        assert!((world_normal.length() - 1.0).abs() < 1e-6);
        assert!(world_normal.dot(world_tangent).abs() < 1e-5);
    }
}
