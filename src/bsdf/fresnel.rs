//! Fresnel reflectance: of a dielectric interface (by pbrt-v4's convention, `eta` the index on
//! the far side over the near side, `cos` signed: negative from the far side) and of a
//! conductor of complex index η + ik per channel. Pure functions.

use glam::Vec3;

/// Unpolarised reflectance of a dielectric seen at `cos` (signed) for `eta` = n_inside /
/// n_outside, the outside where `cos` > 0; 1 under total internal reflection.
pub fn dielectric(cos: f32, eta: f32) -> f32 {
    let (cos, eta) = if cos < 0.0 {
        (-cos, 1.0 / eta)
    } else {
        (cos, eta)
    };
    crate::optics::fresnel_dielectric(cos.min(1.0), 1.0 / eta)
}

/// Unpolarised reflectance of a conductor of index `eta` + i`k` from a dielectric of index 1,
/// at `cos` ≥ 0 from the normal.
pub fn conductor(cos: f32, eta: Vec3, k: Vec3) -> Vec3 {
    let cos = cos.clamp(0.0, 1.0);
    let cos2 = cos * cos;
    let sin2 = 1.0 - cos2;
    let (eta2, k2) = (eta * eta, k * k);
    let t0 = eta2 - k2 - Vec3::splat(sin2);
    let a2b2 = (t0 * t0 + 4.0 * eta2 * k2).max(Vec3::ZERO).powf(0.5);
    let t1 = a2b2 + Vec3::splat(cos2);
    let a = (0.5 * (a2b2 + t0)).max(Vec3::ZERO).powf(0.5);
    let t2 = 2.0 * cos * a;
    let rs = (t1 - t2) / (t1 + t2).max(Vec3::splat(1e-12));
    let t3 = cos2 * a2b2 + Vec3::splat(sin2 * sin2);
    let t4 = t2 * sin2;
    let rp = rs * (t3 - t4) / (t3 + t4).max(Vec3::splat(1e-12));
    (0.5 * (rp + rs)).clamp(Vec3::ZERO, Vec3::ONE)
}

/// Schlick's approximation from the normal-incidence reflectance `f0`.
pub fn schlick(cos: f32, f0: Vec3) -> Vec3 {
    f0 + (Vec3::ONE - f0) * (1.0 - cos.abs().min(1.0)).powi(5)
}

/// What a diffuse base under a smooth coat of index `eta` gets back of the light it sends up:
/// the coat's reflectance from inside times the layer's transmittance there and back,
/// e^(−2·`thickness`/μ), cosine-weighted over the hemisphere (2∫ F e^(−2t/μ) μ dμ, 64-point
/// midpoint quadrature).
pub fn coat_round_trip(eta: f32, thickness: f32) -> f32 {
    let n = 64;
    (0..n)
        .map(|i| {
            let mu = (i as f32 + 0.5) / n as f32;
            2.0 * dielectric(-mu, eta) * (-2.0 * thickness / mu).exp() * mu / n as f32
        })
        .sum()
}
