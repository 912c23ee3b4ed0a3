//! The classical dipole's diffuse reflectance (Jensen, Marschner, Levoy and Hanrahan 2001)
//! and its inverse: what albedo a medium under a dielectric surface needs to reflect a given
//! diffuse colour, as pbrt's `kdsubsurface` asks. Pure numerics; must not read scenes.

/// The classical dipole's total diffuse reflectance of a half-space of reduced albedo `a`
/// under a boundary of relative index `eta` (Jensen et al. 2001, Eq. 5 with the internal
/// reflection parameter `A` from the diffuse Fresnel reflectance's fit).
pub fn dipole_reflectance(a: f32, eta: f32) -> f32 {
    let fdr = -1.440 / (eta * eta) + 0.710 / eta + 0.668 + 0.0636 * eta;
    let big_a = (1.0 + fdr) / (1.0 - fdr);
    let root = (3.0 * (1.0 - a)).sqrt();
    0.5 * a * (1.0 + (-4.0 / 3.0 * big_a * root).exp()) * (-root).exp()
}

/// The albedo whose [`dipole_reflectance`] is `reflectance` (by bisection: the reflectance
/// rises with the albedo), clamped to what albedos 0..1 reach.
pub fn dipole_albedo(reflectance: f32, eta: f32) -> f32 {
    let (mut lo, mut hi) = (0.0f32, 1.0f32);
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if dipole_reflectance(mid, eta) < reflectance {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_dipole_inversion_returns_the_albedo_it_was_given() {
        for eta in [1.0, 1.33, 1.5] {
            for a in [0.1f32, 0.5, 0.9, 0.99, 0.999] {
                let r = dipole_reflectance(a, eta);
                assert!((dipole_albedo(r, eta) - a).abs() < 1e-4, "eta {eta} a {a}");
            }
            // A white surface needs an albedo of 1, a black one 0.
            assert!(dipole_reflectance(0.0, eta) == 0.0);
            assert!(dipole_albedo(2.0, eta) > 0.9999);
        }
    }
}
