//! The lobes pbrt's materials are built of, side by side, each with the same four answers:
//! its value f(wo, wi) (zero for a delta lobe), the density of its own samples, a sample, and
//! a cheap weight for choosing it among a BSDF's lobes. Local frame (z the shading normal);
//! `wo`, `wi` point away from the surface. Opaque lobes are two-sided (a ray from below sees
//! the same lobe mirrored); the dielectric's sides are its outside (+z) and inside. Owns the
//! lobes' formulas; must not know which lobes a material has.

use super::coated::CoatedConductor;
use super::fresnel;
use super::microfacet::TrowbridgeReitz;
use crate::sampling::cosine_hemisphere;
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// A sample of one lobe: a direction, its value, and its density (for a delta lobe, 1, with
/// `f` such that f·|cos θi| is the sample's weight).
#[derive(Clone, Copy, Debug)]
pub struct LobeSample {
    pub wi: Vec3,
    pub f: Vec3,
    pub pdf: f32,
    pub delta: bool,
}

/// Which side of a dielectric light meets depends, for pbrt-v3's coats, on the side of the
/// surface's own normal it arrives from: pbrt-v3 evaluates their `FresnelDielectric` at the
/// cosine to the normal turned to the upper side, so from below the normal the indices swap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fresnel {
    /// A dielectric of this index (inside over outside), seen from outside from either side
    /// (pbrt-v4's interfaces, which turn to the side light arrives from).
    Dielectric(f32),
    /// pbrt-v3's `FresnelDielectric(1, η)` (`uber`): seen from outside on the normal's side,
    /// from inside (totally reflecting past the critical angle) from the other.
    SidedDielectric(f32),
    /// pbrt-v3's `FresnelDielectric(η, 1)` (`plastic`, whose indices are swapped: pbrt-v3
    /// issue #210, kept there so that old images stay the same; dpm matches pbrt-v3's
    /// images): seen from inside on the normal's side, from outside from the other.
    DielectricFromInside(f32),
    Conductor {
        eta: Vec3,
        k: Vec3,
    },
}

impl Fresnel {
    /// The reflectance at `cos`, the cosine to the surface's own normal (negative below it).
    fn at(&self, cos: f32) -> Vec3 {
        match *self {
            Fresnel::Dielectric(eta) => Vec3::splat(fresnel::dielectric(cos.abs(), eta)),
            Fresnel::SidedDielectric(eta) => Vec3::splat(fresnel::dielectric(cos, eta)),
            Fresnel::DielectricFromInside(eta) => Vec3::splat(fresnel::dielectric(-cos, eta)),
            Fresnel::Conductor { eta, k } => fresnel::conductor(cos.abs(), eta, k),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Lobe {
    /// Lambert reflection of `r`.
    Lambert(Vec3),
    /// Lambert transmission of `t` (to the other side).
    LambertTransmission(Vec3),
    /// Microfacet reflection scaled by `scale` with Fresnel `fresnel` (a mirror when smooth).
    Reflection {
        scale: Vec3,
        fresnel: Fresnel,
        distribution: TrowbridgeReitz,
    },
    /// A conductor seen through a smooth dielectric coat ([`CoatedConductor`]).
    CoatedConductor(CoatedConductor),
    /// A dielectric interface of index `eta` (inside over outside, outside +z): microfacet
    /// (or, smooth, specular) reflection scaled by `reflect` and transmission by `transmit`.
    Dielectric {
        eta: f32,
        reflect: Vec3,
        transmit: Vec3,
        distribution: TrowbridgeReitz,
    },
    /// Specular transmission into a dielectric of index `eta`, weighted by 1 − F (pbrt-v3's
    /// SpecularTransmission; `eta` 1 passes straight through).
    SpecularTransmission { scale: Vec3, eta: f32 },
    /// pbrt-v4's thin dielectric slab: its summed internal reflections, transmitted light
    /// going straight on.
    ThinDielectric { eta: f32 },
    /// Ashikhmin–Shirley's Fresnel blend of a diffuse `rd` under a glossy coat of normal
    /// reflectance `rs` (pbrt-v3's `substrate`).
    FresnelBlend {
        rd: Vec3,
        rs: Vec3,
        distribution: TrowbridgeReitz,
    },
    /// A Lambert base of `rho` under a smooth dielectric coat of index `eta` (what the coat
    /// reflects is a lobe of its own): light refracted in, reflected by the base and back and
    /// forth under the coat, refracted out; `thickness` attenuates each crossing as pbrt-v4's
    /// layer does (e^(−thickness / |cos|)). `inner` is what a round trip from the base to the
    /// coat and back returns of diffuse light ([`fresnel::coat_round_trip`]).
    CoatedBase {
        rho: Vec3,
        eta: f32,
        thickness: f32,
        inner: f32,
    },
}

/// Both directions mirrored to the upper side when `wo` comes from below (a two-sided lobe).
#[inline]
fn upper(wo: Vec3, wi: Vec3) -> (Vec3, Vec3) {
    if wo.z < 0.0 { (-wo, -wi) } else { (wo, wi) }
}

#[inline]
fn flip_to(w: Vec3, side: f32) -> Vec3 {
    if side < 0.0 { -w } else { w }
}

/// The direction `wo` refracts into through micro-normal `m` (facing `wo`'s side) with
/// relative index `eta` (far side over near side); `None` under total internal reflection.
fn refract(wo: Vec3, m: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = wo.dot(m);
    let sin2_t = (1.0 - cos_i * cos_i).max(0.0) / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-wo / eta + (cos_i / eta - cos_t) * m).normalize())
}

fn reflect(wo: Vec3, m: Vec3) -> Vec3 {
    2.0 * wo.dot(m) * m - wo
}

impl Lobe {
    /// Whether the lobe is in [`super::Part::Estimated`] when microfacet reflection at least
    /// `min_alpha` rough is. The Fresnel blend is, however smooth: its diffuse term dominates
    /// what photons bring it.
    pub fn is_estimated(&self, min_alpha: f32) -> bool {
        match self {
            l if l.is_broad() => true,
            Lobe::Reflection { distribution, .. }
            | Lobe::CoatedConductor(CoatedConductor { distribution, .. }) => {
                !distribution.is_smooth() && distribution.alpha.min_element() >= min_alpha
            }
            _ => false,
        }
    }

    /// Whether the lobe is about as wide as a Lambert lobe ([`super::Part::Broad`]).
    pub fn is_broad(&self) -> bool {
        matches!(
            self,
            Lobe::Lambert(_) | Lobe::CoatedBase { .. } | Lobe::FresnelBlend { .. }
        )
    }

    /// Whether light crossing to the other side has a density here (rough or diffuse
    /// transmission), so that a light on that side can be sampled through it.
    pub fn transmits_spread(&self) -> bool {
        match self {
            Lobe::Dielectric {
                transmit,
                distribution,
                ..
            } => !distribution.is_smooth() && transmit.max_element() > 0.0,
            Lobe::LambertTransmission(t) => t.max_element() > 0.0,
            _ => false,
        }
    }

    pub fn is_delta(&self) -> bool {
        match self {
            Lobe::Reflection { distribution, .. }
            | Lobe::Dielectric { distribution, .. }
            | Lobe::CoatedConductor(CoatedConductor { distribution, .. }) => {
                distribution.is_smooth()
            }
            Lobe::SpecularTransmission { .. } | Lobe::ThinDielectric { .. } => true,
            _ => false,
        }
    }

    /// A weight for choosing this lobe to sample at `wo`: roughly its albedo, never zero
    /// where the lobe scatters.
    pub fn weight(&self, wo: Vec3) -> f32 {
        let c = wo.z.abs();
        match *self {
            Lobe::Lambert(r) => r.max_element(),
            Lobe::LambertTransmission(t) => t.max_element(),
            Lobe::Reflection { scale, fresnel, .. } => (scale * fresnel.at(wo.z)).max_element(),
            Lobe::CoatedConductor(coated) => coated.weight(Vec3::new(wo.x, wo.y, c)),
            Lobe::Dielectric {
                eta,
                reflect,
                transmit,
                ..
            } => {
                let f = fresnel::dielectric(wo.z, eta);
                (f * reflect + (1.0 - f) * transmit).max_element()
            }
            Lobe::SpecularTransmission { scale, eta } => {
                ((1.0 - fresnel::dielectric(c, eta)) * scale).max_element()
            }
            Lobe::ThinDielectric { .. } => 1.0,
            Lobe::FresnelBlend { rd, rs, .. } => rd.max_element() + rs.max_element(),
            Lobe::CoatedBase { rho, eta, .. } => {
                (1.0 - fresnel::dielectric(c, eta)) * rho.max_element()
            }
        }
    }

    /// f(wo, wi), zero for a delta lobe.
    pub fn f(&self, wo: Vec3, wi: Vec3) -> Vec3 {
        match *self {
            Lobe::Lambert(r) => {
                if wo.z * wi.z > 0.0 {
                    r * FRAC_1_PI
                } else {
                    Vec3::ZERO
                }
            }
            Lobe::LambertTransmission(t) => {
                if wo.z * wi.z < 0.0 {
                    t * FRAC_1_PI
                } else {
                    Vec3::ZERO
                }
            }
            Lobe::Reflection {
                scale,
                fresnel,
                distribution,
            } => {
                let side = if wo.z < 0.0 { -1.0 } else { 1.0 };
                let (wo, wi) = upper(wo, wi);
                if distribution.is_smooth() || wi.z <= 0.0 || wo.z <= 0.0 {
                    return Vec3::ZERO;
                }
                let m = (wo + wi).normalize_or_zero();
                if m == Vec3::ZERO {
                    return Vec3::ZERO;
                }
                let value = distribution.d(m) * distribution.g(wo, wi) / (4.0 * wo.z * wi.z);
                scale * fresnel.at(side * wo.dot(m)) * value
            }
            Lobe::CoatedConductor(coated) => {
                let (wo, wi) = upper(wo, wi);
                if coated.distribution.is_smooth() || wi.z <= 0.0 || wo.z <= 0.0 {
                    return Vec3::ZERO;
                }
                coated.f(wo, wi)
            }
            Lobe::Dielectric {
                eta,
                reflect,
                transmit,
                distribution,
            } => {
                if distribution.is_smooth() {
                    return Vec3::ZERO;
                }
                dielectric_f(wo, wi, eta, reflect, transmit, &distribution)
            }
            Lobe::SpecularTransmission { .. } | Lobe::ThinDielectric { .. } => Vec3::ZERO,
            Lobe::FresnelBlend {
                rd,
                rs,
                distribution,
            } => {
                let (wo, wi) = upper(wo, wi);
                if wi.z <= 0.0 || wo.z <= 0.0 {
                    return Vec3::ZERO;
                }
                let p5 = |x: f32| (1.0 - 0.5 * x).powi(5);
                let diffuse = rd
                    * (Vec3::ONE - rs)
                    * (28.0 / (23.0 * std::f32::consts::PI))
                    * (1.0 - p5(wi.z))
                    * (1.0 - p5(wo.z));
                let m = (wo + wi).normalize_or_zero();
                if m == Vec3::ZERO {
                    return diffuse;
                }
                let specular = fresnel::schlick(wi.dot(m), rs) * distribution.d(m)
                    / (4.0 * wi.dot(m).abs() * wi.z.max(wo.z));
                diffuse + specular
            }
            Lobe::CoatedBase {
                rho,
                eta,
                thickness,
                inner,
            } => {
                let (wo, wi) = upper(wo, wi);
                if wi.z <= 0.0 || wo.z <= 0.0 {
                    return Vec3::ZERO;
                }
                // Cosines of the refracted directions under the coat.
                let inside = |c: f32| (1.0 - (1.0 - c * c) / (eta * eta)).max(0.0).sqrt();
                let path =
                    thickness * (1.0 / inside(wi.z).max(1e-4) + 1.0 / inside(wo.z).max(1e-4));
                let rho = rho * (-path).exp();
                let t =
                    (1.0 - fresnel::dielectric(wi.z, eta)) * (1.0 - fresnel::dielectric(wo.z, eta));
                rho * (t * FRAC_1_PI / (eta * eta)) / (Vec3::ONE - rho * inner)
            }
        }
    }

    /// The density with which [`Lobe::sample`] draws the non-delta `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Lobe::Lambert(_) | Lobe::CoatedBase { .. } => {
                if wo.z * wi.z > 0.0 {
                    wi.z.abs() * FRAC_1_PI
                } else {
                    0.0
                }
            }
            Lobe::LambertTransmission(_) => {
                if wo.z * wi.z < 0.0 {
                    wi.z.abs() * FRAC_1_PI
                } else {
                    0.0
                }
            }
            Lobe::Reflection { distribution, .. } => {
                let (wo, wi) = upper(wo, wi);
                if distribution.is_smooth() || wi.z <= 0.0 || wo.z <= 0.0 {
                    return 0.0;
                }
                let m = (wo + wi).normalize_or_zero();
                distribution.visible_d(wo, m) / (4.0 * wo.dot(m).abs().max(1e-12))
            }
            Lobe::CoatedConductor(coated) => {
                let (wo, wi) = upper(wo, wi);
                if coated.distribution.is_smooth() || wi.z <= 0.0 || wo.z <= 0.0 {
                    return 0.0;
                }
                coated.pdf(wo, wi)
            }
            Lobe::Dielectric {
                eta,
                reflect,
                transmit,
                distribution,
            } => {
                if distribution.is_smooth() {
                    return 0.0;
                }
                dielectric_pdf(wo, wi, eta, reflect, transmit, &distribution)
            }
            Lobe::SpecularTransmission { .. } | Lobe::ThinDielectric { .. } => 0.0,
            Lobe::FresnelBlend { distribution, .. } => {
                let (wo, wi) = upper(wo, wi);
                if wi.z <= 0.0 || wo.z <= 0.0 {
                    return 0.0;
                }
                let m = (wo + wi).normalize_or_zero();
                let glossy = distribution.visible_d(wo, m) / (4.0 * wo.dot(m).abs().max(1e-12));
                0.5 * (wi.z * FRAC_1_PI + glossy)
            }
        }
    }

    pub fn sample(&self, wo: Vec3, uc: f32, u: (f32, f32)) -> Option<LobeSample> {
        let cosine = |side: f32| {
            let wi = flip_to(cosine_hemisphere(Vec3::Z, u), side);
            (wi.z != 0.0).then_some(wi)
        };
        let non_delta = |wi: Vec3| {
            let pdf = self.pdf(wo, wi);
            (pdf > 0.0).then(|| LobeSample {
                wi,
                f: self.f(wo, wi),
                pdf,
                delta: false,
            })
        };
        match *self {
            Lobe::Lambert(_) | Lobe::CoatedBase { .. } => non_delta(cosine(wo.z)?),
            Lobe::LambertTransmission(_) => non_delta(cosine(-wo.z)?),
            Lobe::CoatedConductor(coated) => {
                let up = if wo.z < 0.0 { -wo } else { wo };
                if coated.distribution.is_smooth() {
                    return Some(LobeSample {
                        wi: Vec3::new(-wo.x, -wo.y, wo.z),
                        f: coated.mirror_weight(up) / up.z.max(1e-12),
                        pdf: 1.0,
                        delta: true,
                    });
                }
                non_delta(flip_to(coated.sample(up, u)?, wo.z))
            }
            Lobe::Reflection {
                scale,
                fresnel,
                distribution,
            } => {
                if distribution.is_smooth() {
                    let wi = Vec3::new(-wo.x, -wo.y, wo.z);
                    let f = scale * fresnel.at(wo.z) / wo.z.abs().max(1e-12);
                    return Some(LobeSample {
                        wi,
                        f,
                        pdf: 1.0,
                        delta: true,
                    });
                }
                let up = if wo.z < 0.0 { -wo } else { wo };
                let m = distribution.sample_visible(up, u);
                let wi = reflect(up, m);
                if wi.z <= 0.0 {
                    return None;
                }
                non_delta(flip_to(wi, wo.z))
            }
            Lobe::Dielectric {
                eta,
                reflect: kr,
                transmit: kt,
                distribution,
            } => dielectric_sample(wo, uc, u, eta, kr, kt, &distribution, non_delta),
            Lobe::SpecularTransmission { scale, eta } => {
                let f = 1.0 - fresnel::dielectric(wo.z, eta);
                let wi = if eta == 1.0 {
                    -wo
                } else {
                    let (n, rel) = if wo.z > 0.0 {
                        (Vec3::Z, eta)
                    } else {
                        (-Vec3::Z, 1.0 / eta)
                    };
                    refract(wo, n, rel)?
                };
                Some(LobeSample {
                    wi,
                    f: scale * f / wi.z.abs().max(1e-12),
                    pdf: 1.0,
                    delta: true,
                })
            }
            Lobe::ThinDielectric { eta } => {
                let mut r = fresnel::dielectric(wo.z.abs(), eta);
                let mut t = 1.0 - r;
                if r < 1.0 {
                    r += t * t * r / (1.0 - r * r);
                    t = 1.0 - r;
                }
                let (wi, p) = if uc < r / (r + t) {
                    (Vec3::new(-wo.x, -wo.y, wo.z), r)
                } else {
                    (-wo, t)
                };
                Some(LobeSample {
                    wi,
                    f: Vec3::splat(p / wi.z.abs().max(1e-12)),
                    pdf: p,
                    delta: true,
                })
            }
            Lobe::FresnelBlend { distribution, .. } => {
                let up = if wo.z < 0.0 { -wo } else { wo };
                let wi = if uc < 0.5 {
                    cosine(1.0)?
                } else {
                    let m = distribution.sample_visible(up, u);
                    let wi = reflect(up, m);
                    if wi.z <= 0.0 {
                        return None;
                    }
                    wi
                };
                non_delta(flip_to(wi, wo.z))
            }
        }
    }
}

/// The generalised half vector of `wo`, `wi` through a dielectric of index `eta` (outside
/// +z), facing +z, with the relative index of the far side; `None` when degenerate or when
/// a micro-normal would face away from either direction.
fn dielectric_half(wo: Vec3, wi: Vec3, eta: f32) -> Option<(Vec3, f32, bool)> {
    let reflection = wo.z * wi.z > 0.0;
    let etap = if reflection {
        1.0
    } else if wo.z > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let m = wi * etap + wo;
    if wo.z == 0.0 || wi.z == 0.0 || m.length_squared() == 0.0 {
        return None;
    }
    let m = m.normalize();
    let m = if m.z < 0.0 { -m } else { m };
    if m.dot(wi) * wi.z < 0.0 || m.dot(wo) * wo.z < 0.0 {
        return None;
    }
    Some((m, etap, reflection))
}

fn dielectric_f(
    wo: Vec3,
    wi: Vec3,
    eta: f32,
    kr: Vec3,
    kt: Vec3,
    distribution: &TrowbridgeReitz,
) -> Vec3 {
    let Some((m, etap, reflection)) = dielectric_half(wo, wi, eta) else {
        return Vec3::ZERO;
    };
    let f = fresnel::dielectric(wo.dot(m), eta);
    let dg = distribution.d(m) * distribution.g(wo, wi);
    if reflection {
        kr * (dg * f / (4.0 * wo.z * wi.z).abs())
    } else {
        let denom = (wi.dot(m) + wo.dot(m) / etap).powi(2) * wi.z * wo.z;
        kt * (dg * (1.0 - f) * (wi.dot(m) * wo.dot(m) / denom).abs())
    }
}

/// The probabilities of reflecting and of transmitting at micro-normal `m`, by the Fresnel
/// reflectance weighted by the tints.
fn split(wo: Vec3, m: Vec3, eta: f32, kr: Vec3, kt: Vec3) -> (f32, f32, f32) {
    let f = fresnel::dielectric(wo.dot(m), eta);
    let (r, t) = (f * kr.max_element(), (1.0 - f) * kt.max_element());
    (f, r / (r + t).max(1e-12), t / (r + t).max(1e-12))
}

fn dielectric_pdf(
    wo: Vec3,
    wi: Vec3,
    eta: f32,
    kr: Vec3,
    kt: Vec3,
    distribution: &TrowbridgeReitz,
) -> f32 {
    let Some((m, etap, reflection)) = dielectric_half(wo, wi, eta) else {
        return 0.0;
    };
    let (_, pr, pt) = split(wo, m, eta, kr, kt);
    let visible = distribution.visible_d(wo, m);
    if reflection {
        visible / (4.0 * wo.dot(m).abs()) * pr
    } else {
        let denom = (wi.dot(m) + wo.dot(m) / etap).powi(2);
        visible * wi.dot(m).abs() / denom * pt
    }
}

#[allow(clippy::too_many_arguments)]
fn dielectric_sample(
    wo: Vec3,
    uc: f32,
    u: (f32, f32),
    eta: f32,
    kr: Vec3,
    kt: Vec3,
    distribution: &TrowbridgeReitz,
    non_delta: impl Fn(Vec3) -> Option<LobeSample>,
) -> Option<LobeSample> {
    // Micro-normal facing wo's side.
    let m_up = if distribution.is_smooth() {
        Vec3::Z
    } else {
        distribution.sample_visible(wo, u)
    };
    let m = if wo.z < 0.0 { -m_up } else { m_up };
    let (f, pr, _) = split(wo, m_up, eta, kr, kt);
    let reflects = uc < pr;
    let wi = if reflects {
        reflect(wo, m)
    } else {
        let rel = if wo.z > 0.0 { eta } else { 1.0 / eta };
        refract(wo, m, rel)?
    };
    if distribution.is_smooth() {
        let (p, tint, fraction) = if reflects {
            (pr, kr, f)
        } else {
            (1.0 - pr, kt, 1.0 - f)
        };
        return Some(LobeSample {
            wi,
            f: tint * fraction / wi.z.abs().max(1e-12),
            pdf: p,
            delta: true,
        });
    }
    if (wi.z * wo.z > 0.0) != reflects || wi.z == 0.0 {
        return None;
    }
    non_delta(wi)
}
