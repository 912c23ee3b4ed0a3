//! A conductor under a smooth dielectric coat (pbrt-v4's `coatedconductor` seen through its
//! coat): light refracts in with the coat's transmission, crosses the layer (attenuated by
//! e^(−thickness/cos) as pbrt-v4's layer attenuates it), reflects off the rough conductor in
//! the coat's medium (Trowbridge–Reitz, the conductor's index relative to the coat's) and
//! refracts out. The conductor's lobe is evaluated and sampled in the refracted directions, so
//! the lobe widens as it leaves the coat and its Fresnel reflectance is the one inside. Light
//! the coat reflects back down returns as a geometric series at the angle it left at (exact
//! for a smooth conductor); what a rough conductor scatters past the coat's critical angle,
//! trapped and reflected on, is what this lobe leaves out (measured against a random walk in
//! `super::tests`). Upper hemisphere, `wo` and
//! `wi` pointing away from the surface. Owns those formulas; must not know which material it
//! belongs to.

use super::fresnel;
use super::microfacet::TrowbridgeReitz;
use glam::Vec3;

/// The conductor under its coat: index `eta` + i`k` relative to the coat's index `coat`,
/// roughness `distribution`, the layer `thickness` thick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoatedConductor {
    pub eta: Vec3,
    pub k: Vec3,
    pub distribution: TrowbridgeReitz,
    pub coat: f32,
    pub thickness: f32,
}

/// `w` (above the coat) refracted into the coat, turned to point up: the same azimuth, sin θ
/// divided by the index.
#[inline]
fn inside(w: Vec3, coat: f32) -> Vec3 {
    let (x, y) = (w.x / coat, w.y / coat);
    Vec3::new(x, y, (1.0 - x * x - y * y).max(0.0).sqrt())
}

/// `w` (in the coat, pointing up) refracted out; `None` past the critical angle.
#[inline]
fn outside(w: Vec3, coat: f32) -> Option<Vec3> {
    let (x, y) = (w.x * coat, w.y * coat);
    let z2 = 1.0 - x * x - y * y;
    (z2 > 0.0).then(|| Vec3::new(x, y, z2.sqrt()))
}

impl CoatedConductor {
    /// What the coat lets through at `cos` from outside.
    #[inline]
    fn transmission(&self, cos: f32) -> f32 {
        1.0 - fresnel::dielectric(cos, self.coat)
    }

    /// Transmittance of the layer along a direction of cosine `cos` inside it.
    #[inline]
    fn layer(&self, cos: f32) -> f32 {
        (-self.thickness / cos.max(1e-4)).exp()
    }

    /// What light leaving the conductor at `w` inside (upper) gains by the coat's reflections
    /// back down, each returned to the conductor and reflected at about the same angle (exact
    /// for a smooth conductor): the geometric series 1/(1 − F·R·T²) of the coat's internal
    /// reflectance F, the conductor's R and the layer's transmittance T there and back.
    #[inline]
    fn returns(&self, w: Vec3) -> Vec3 {
        let back = fresnel::dielectric(-w.z, self.coat) * self.layer(w.z).powi(2);
        let r = fresnel::conductor(w.z, self.eta, self.k);
        (Vec3::ONE - back * r).max(Vec3::splat(1e-3)).recip()
    }

    /// A cheap weight for choosing this lobe at `wo` (upper): about its albedo.
    pub fn weight(&self, wo: Vec3) -> f32 {
        let w = inside(wo, self.coat);
        let f = fresnel::conductor(w.z, self.eta, self.k);
        self.transmission(wo.z) * (f * self.layer(w.z).powi(2)).max_element()
    }

    /// f(wo, wi) for a rough conductor (both upper).
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        let (o, i) = (inside(wo, self.coat), inside(wi, self.coat));
        let m = (o + i).normalize_or_zero();
        if m == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let d = &self.distribution;
        let inner = d.d(m) * d.g(o, i) / (4.0 * o.z * i.z);
        let through = self.transmission(wo.z) * self.transmission(wi.z);
        // Radiance is compressed by η² going in and expanded coming out; the solid angles
        // inside are narrower by the same factor: what is left is 1/η² once.
        let scale = through * self.layer(o.z) * self.layer(i.z) * inner / (self.coat * self.coat);
        // The returns at the two ends, their geometric mean keeping f reciprocal.
        let returns = (self.returns(o) * self.returns(i)).powf(0.5);
        fresnel::conductor(o.dot(m), self.eta, self.k) * returns * scale
    }

    /// The density of [`CoatedConductor::sample`]'s `wi` (both upper).
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let (o, i) = (inside(wo, self.coat), inside(wi, self.coat));
        let m = (o + i).normalize_or_zero();
        if m == Vec3::ZERO {
            return 0.0;
        }
        let inner = self.distribution.visible_d(o, m) / (4.0 * o.dot(m).abs().max(1e-12));
        // dω inside = dω outside · cos θ / (η² cos θ inside).
        inner * wi.z / (self.coat * self.coat * i.z.max(1e-12))
    }

    /// A direction from the conductor's visible normals inside the coat, refracted out; `None`
    /// when it stays inside (past the critical angle) or points down.
    pub fn sample(&self, wo: Vec3, u: (f32, f32)) -> Option<Vec3> {
        let o = inside(wo, self.coat);
        let m = self.distribution.sample_visible(o, u);
        let i = 2.0 * o.dot(m) * m - o;
        if i.z <= 0.0 {
            return None;
        }
        outside(i, self.coat)
    }

    /// A smooth conductor under the coat: the mirror direction's weight f·cos/pdf.
    pub fn mirror_weight(&self, wo: Vec3) -> Vec3 {
        let o = inside(wo, self.coat);
        let t = self.transmission(wo.z);
        fresnel::conductor(o.z, self.eta, self.k)
            * self.returns(o)
            * (t * t * self.layer(o.z).powi(2))
    }
}
