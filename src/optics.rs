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
    fresnel_with_cos_t(cos_i, (1.0 - sin2_t).sqrt(), eta)
}

#[inline(always)]
fn fresnel_with_cos_t(cos_i: f32, cos_t: f32, eta: f32) -> f32 {
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_s * r_s + r_p * r_p)
}

/// Which way [`scatter_dielectric`] sent a ray (a tinted glass scales each branch by its own
/// tint).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scattered {
    Reflected,
    Transmitted,
}

impl Scattered {
    /// `reflected` or `transmitted`, by the way the ray went.
    #[inline(always)]
    pub fn pick<T>(self, reflected: T, transmitted: T) -> T {
        match self {
            Scattered::Reflected => reflected,
            Scattered::Transmitted => transmitted,
        }
    }
}

/// Where a photon arriving along unit `d` at a smooth dielectric with unit normal `n` (facing
/// the incoming side, `eta` = n_incident / n_transmitted) goes, and by which branch: reflected
/// with the Fresnel probability (`u` uniform in [0, 1) decides), refracted otherwise;
/// reflected on total internal reflection. The same as choosing between [`reflect`] and
/// [`refract`] by [`fresnel_dielectric`], with the transmitted cosine computed once and the
/// refracted direction left unnormalised: it is unit by construction, to a few ulps.
#[inline]
pub fn scatter_dielectric(d: Vec3, n: Vec3, eta: f32, u: f32) -> (Vec3, Scattered) {
    let cos_i = (-d.dot(n)).clamp(0.0, 1.0);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
    if sin2_t >= 1.0 {
        return (reflect(d, n), Scattered::Reflected);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    if u < fresnel_with_cos_t(cos_i, cos_t, eta) {
        (reflect(d, n), Scattered::Reflected)
    } else {
        (eta * d + (eta * cos_i - cos_t) * n, Scattered::Transmitted)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Scattering in one step picks the same branch as Fresnel then refraction, and its
    /// refracted direction is the normalised one to within 1e-6.
    #[test]
    fn scatter_dielectric_matches_fresnel_then_refract() {
        let mut s = 11u32;
        let mut r = || {
            s = s.wrapping_mul(1664525).wrapping_add(1013904223);
            (s >> 8) as f32 / (1u32 << 24) as f32
        };
        let mut refracted = 0;
        for _ in 0..100_000 {
            let n = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize();
            let mut d = Vec3::new(r() - 0.5, r() - 0.5, r() - 0.5).normalize();
            if d.dot(n) > 0.0 {
                d = -d;
            }
            let eta = if r() < 0.5 { 1.0 / 1.5 } else { 1.5 };
            let u = r();
            let cos_i = -d.dot(n);
            let (want, want_branch) = if u < fresnel_dielectric(cos_i, eta) {
                (reflect(d, n), Scattered::Reflected)
            } else {
                refracted += 1;
                match refract(d, n, eta) {
                    Some(t) => (t, Scattered::Transmitted),
                    None => (reflect(d, n), Scattered::Reflected),
                }
            };
            let (got, branch) = scatter_dielectric(d, n, eta, u);
            assert_eq!(branch, want_branch, "{d} {n} {eta} {u}");
            assert!(
                (got - want).length() < 1e-6,
                "{d} {n} {eta}: {got} vs {want}"
            );
        }
        assert!(refracted > 50_000, "only {refracted} refracted");
    }

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
