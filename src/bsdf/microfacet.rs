//! The Trowbridge–Reitz (GGX) microfacet distribution, anisotropic by α along the shading
//! frame's x and y: its density of normals D, Smith's masking Λ, G1 and G, and sampling of the
//! normals visible from a direction (Heitz 2018) with their density. Local frame, z the
//! macro-surface normal. Pure functions; no lobes, no Fresnel.

use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Below this α a lobe is a mirror (delta) lobe.
pub const SMOOTH_ALPHA: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    pub alpha: Vec2,
}

impl TrowbridgeReitz {
    pub fn new(alpha: Vec2) -> Self {
        Self {
            alpha: alpha.max(Vec2::splat(1e-4)),
        }
    }

    pub fn is_smooth(&self) -> bool {
        self.alpha.max_element() < SMOOTH_ALPHA
    }

    /// Density of micro-normals `m` (upper hemisphere), per unit projected area.
    pub fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let (ax, ay) = (self.alpha.x, self.alpha.y);
        let e = (m.x / ax).powi(2) + (m.y / ay).powi(2) + m.z * m.z;
        1.0 / (PI * ax * ay * e * e)
    }

    /// Smith's Λ for direction `w` (either side).
    pub fn lambda(&self, w: Vec3) -> f32 {
        let cos2 = w.z * w.z;
        if cos2 <= 0.0 {
            return f32::INFINITY;
        }
        let a2 = (self.alpha.x * w.x).powi(2) + (self.alpha.y * w.y).powi(2);
        let tan2_alpha2 = a2 / cos2;
        0.5 * ((1.0 + tan2_alpha2).sqrt() - 1.0)
    }

    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing.
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// Density of the normals visible from `w` (either side: the side `w` is on counts as up),
    /// per solid angle of `m`.
    pub fn visible_d(&self, w: Vec3, m: Vec3) -> f32 {
        let cos = w.z.abs();
        if cos <= 0.0 {
            return 0.0;
        }
        self.g1(w) / cos * self.d(m) * w.dot(m).abs()
    }

    /// A micro-normal visible from `w` (Heitz 2018's sampling of visible normals), in the
    /// upper hemisphere.
    pub fn sample_visible(&self, w: Vec3, u: (f32, f32)) -> Vec3 {
        let w = if w.z < 0.0 { -w } else { w };
        // The direction in the hemisphere configuration.
        let wh = Vec3::new(self.alpha.x * w.x, self.alpha.y * w.y, w.z).normalize();
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        // A point of the projected disc, warped towards the visible half.
        let r = u.0.sqrt();
        let phi = 2.0 * PI * u.1;
        let (mut px, py0) = (r * phi.cos(), r * phi.sin());
        let h = (1.0 - px * px).max(0.0).sqrt();
        let s = 0.5 * (1.0 + wh.z);
        let py = (1.0 - s) * h + s * py0;
        let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
        if !px.is_finite() {
            px = 0.0;
        }
        let nh = px * t1 + py * t2 + pz * wh;
        Vec3::new(self.alpha.x * nh.x, self.alpha.y * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// pbrt-v3's `RoughnessToAlpha` (`remaproughness`): a polynomial in ln r.
pub fn pbrt_v3_roughness_to_alpha(roughness: f32) -> f32 {
    let x = roughness.max(1e-3).ln();
    1.62142 + 0.819955 * x + 0.1734 * x * x + 0.0171201 * x * x * x + 0.000640711 * x * x * x * x
}

/// pbrt-v4's: α = √r.
pub fn pbrt_v4_roughness_to_alpha(roughness: f32) -> f32 {
    roughness.max(0.0).sqrt()
}
