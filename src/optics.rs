//! Geometric optics of perfect specular surfaces: reflection, refraction and the Fresnel
//! reflectance of a smooth dielectric. Pure functions of directions; no rays, no scenes.

use glam::Vec3;

/// Mirror `d` (travelling towards the surface) about the unit normal `n`.
pub fn reflect(d: Vec3, n: Vec3) -> Vec3 {
    d - 2.0 * d.dot(n) * n
}

/// Refract `d` (unit, travelling towards the surface) through unit normal `n` facing the
/// incoming side, with `eta` = n_incident / n_transmitted. `None` on total internal reflection.
pub fn refract(d: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -d.dot(n);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((eta * d + (eta * cos_i - cos_t) * n).normalize())
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface, `cos_i` ≥ 0 measured on
/// the incident side, `eta` = n_incident / n_transmitted. Returns 1 on total internal reflection.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn normal_incidence_reflectance_matches_the_closed_form() {
        for ior in [1.0f32, 1.33, 1.5, 2.4] {
            let want = ((1.0 - ior) / (1.0 + ior)).powi(2);
            assert!((fresnel_dielectric(1.0, 1.0 / ior) - want).abs() < 1e-6);
            assert!((fresnel_dielectric(1.0, ior) - want).abs() < 1e-6);
        }
    }

    #[test]
    fn total_internal_reflection_beyond_the_critical_angle() {
        let eta = 1.5f32; // glass to air
        let critical = (1.0 / eta).asin();
        let d = |theta: f32| Vec3::new(theta.sin(), 0.0, -theta.cos());
        assert!(refract(d(critical + 0.01), Vec3::Z, eta).is_none());
        assert_eq!(fresnel_dielectric((critical + 0.01).cos(), eta), 1.0);
        assert!(refract(d(critical - 0.01), Vec3::Z, eta).is_some());
        assert!(fresnel_dielectric((critical - 0.01).cos(), eta) < 1.0);
    }

    #[test]
    fn refraction_obeys_snell_and_reflection_preserves_angle() {
        let eta = 1.0 / 1.5;
        for theta in [0.0f32, 0.3, 0.7, 1.2, 1.5] {
            let d = Vec3::new(theta.sin(), 0.0, -theta.cos());
            let t = refract(d, Vec3::Z, eta).unwrap();
            let sin_t = (t.x * t.x + t.y * t.y).sqrt();
            assert!((theta.sin() * eta - sin_t).abs() < 1e-5);
            assert!(t.z < 0.0);
            let r = reflect(d, Vec3::Z);
            assert!((r.z - theta.cos()).abs() < 1e-6 && (r.x - d.x).abs() < 1e-6);
        }
    }
}
