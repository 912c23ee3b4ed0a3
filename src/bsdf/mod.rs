//! Surface scattering: the BSDFs of pbrt's materials behind one interface (evaluate, sample,
//! pdf, albedo) over lobes kept side by side ([`lobes`]), in the local shading frame: z is the
//! shading normal as the surface gives it (not turned to the ray), `wo` and `wi` unit and
//! pointing away from the surface, on either side (`wo.z` < 0: the ray came from below, or
//! from inside a dielectric). Owns the lobes' arithmetic (Lambert, Trowbridge–Reitz microfacets
//! with visible-normal sampling, Fresnel of conductors and dielectrics, Ashikhmin–Shirley, a
//! coated base) and which lobes each of pbrt's materials has; must not trace rays, read scenes
//! or know of photons.
//!
//! Which lobes a renderer estimates from photons and which it samples and follows: a [`Part`]
//! splits a BSDF into its broad lobes (Lambert, a coated Lambert base, the Fresnel blend), its
//! glossy lobes rough enough to read photons (microfacet reflection at least
//! [`ESTIMATED_MIN_ALPHA`] rough, or the threshold given to [`Bsdf::split_at`]) and the rest.
//!
//! Convention: no transmission lobe scales radiance by 1/η² (nor does dpm's smooth glass): on
//! a closed object the factor on the way in cancels the one on the way out.

mod coated;
pub mod fresnel;
mod lobes;
pub mod microfacet;
mod model;

pub use microfacet::{pbrt_v3_roughness_to_alpha, pbrt_v4_roughness_to_alpha};
pub use model::{Axes, Model, ModelParameter, Remap};

/// The Trowbridge–Reitz α below which a reflection lobe is sampled and followed rather than
/// read from photons, by default: photons evaluated against a lobe narrower than this are too
/// few per estimate (its variance grows as 1/α² at equal photons), while a followed lobe loses
/// what only photons find (a caustic lit by a point light) and a gather ray from a broad lobe
/// shows the global map's blotches. Chosen by measurement (docs/materials.md,
/// "The glossy threshold").
pub const ESTIMATED_MIN_ALPHA: f32 = 0.1;

use glam::{Vec2, Vec3};
use lobes::{Fresnel, Lobe};
use microfacet::TrowbridgeReitz;

/// Which lobes a call concerns. A renderer reads photons at the [`Part::Estimated`] lobes and
/// samples and follows the rest; of the estimated ones, the broad lobes read every photon map,
/// while a glossy lobe reads the caustic map alone and samples what else reaches it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// Every lobe.
    All,
    /// The lobes that receive photons: [`Part::Broad`] and [`Part::Glossy`].
    Estimated,
    /// Lambert reflection, the coated Lambert base and the Fresnel blend: lobes about as wide
    /// as a Lambert lobe, whose light a photon estimate gives whatever its paths.
    Broad,
    /// Microfacet reflection at least as rough as the split's threshold
    /// ([`ESTIMATED_MIN_ALPHA`] by default): its caustics come from photons, weighed by f
    /// for each photon's direction; the rest of its light is sampled.
    Glossy,
    /// Every other lobe (specular, smoother microfacet reflection, transmission), which a
    /// renderer samples and follows as it would a mirror.
    Followed,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BsdfSample {
    pub wi: Vec3,
    /// The value for `wi`; for a delta lobe, the value that makes f·|cos θi|/pdf the sample's
    /// weight.
    pub f: Vec3,
    /// Solid-angle density (the lobes of the part mixed); for a delta lobe, the probability
    /// with which it was chosen.
    pub pdf: f32,
    pub delta: bool,
    pub transmission: bool,
}

const MAX_LOBES: usize = 5;

/// A material's lobes at a hit: no heap, cheap to build per hit.
#[derive(Clone, Copy, Debug)]
pub struct Bsdf {
    lobes: [Lobe; MAX_LOBES],
    count: usize,
    /// Microfacet reflection at least this rough is in [`Part::Estimated`].
    estimated_min_alpha: f32,
}

/// Index 1.5, pbrt-v3's plastic and translucent coats.
const COAT_ETA: f32 = 1.5;

impl Bsdf {
    /// The lobes of `model`, split at [`ESTIMATED_MIN_ALPHA`].
    pub fn new(model: &Model) -> Bsdf {
        Bsdf::split_at(model, ESTIMATED_MIN_ALPHA)
    }

    /// The lobes of `model`, microfacet reflection at least `estimated_min_alpha` rough in
    /// [`Part::Estimated`] (infinity: none).
    pub fn split_at(model: &Model, estimated_min_alpha: f32) -> Bsdf {
        let mut b = Bsdf {
            lobes: [Lobe::Lambert(Vec3::ZERO); MAX_LOBES],
            count: 0,
            estimated_min_alpha,
        };
        let tr = TrowbridgeReitz::new;
        match *model {
            Model::Plastic { kd, ks, alpha } => {
                b.push(Lobe::Lambert(kd));
                b.push(Lobe::Reflection {
                    scale: ks,
                    fresnel: Fresnel::DielectricFromInside(COAT_ETA),
                    distribution: tr(alpha),
                });
            }
            Model::Uber {
                kd,
                ks,
                kr,
                kt,
                alpha,
                eta,
                opacity,
            } => {
                b.push(Lobe::SpecularTransmission {
                    scale: Vec3::ONE - opacity,
                    eta: 1.0,
                });
                b.push(Lobe::Lambert(opacity * kd));
                b.push(Lobe::Reflection {
                    scale: opacity * ks,
                    fresnel: Fresnel::SidedDielectric(eta),
                    distribution: tr(alpha),
                });
                b.push(Lobe::Reflection {
                    scale: opacity * kr,
                    fresnel: Fresnel::SidedDielectric(eta),
                    distribution: tr(Vec2::ZERO),
                });
                b.push(Lobe::SpecularTransmission {
                    scale: opacity * kt,
                    eta,
                });
            }
            Model::Substrate { kd, ks, alpha } => b.push(Lobe::FresnelBlend {
                rd: kd,
                rs: ks,
                distribution: tr(alpha),
            }),
            Model::Translucent {
                kd,
                ks,
                reflect,
                transmit,
                alpha,
            } => {
                b.push(Lobe::Lambert(kd * reflect));
                b.push(Lobe::LambertTransmission(kd * transmit));
                b.push(Lobe::Dielectric {
                    eta: COAT_ETA,
                    reflect: ks * reflect,
                    transmit: ks * transmit,
                    distribution: tr(alpha),
                });
            }
            Model::Conductor { eta, k, alpha } => b.push(Lobe::Reflection {
                scale: Vec3::ONE,
                fresnel: Fresnel::Conductor { eta, k },
                distribution: tr(alpha),
            }),
            Model::Dielectric {
                eta,
                alpha,
                reflect_tint,
                transmit_tint,
            } => b.push(Lobe::Dielectric {
                eta,
                reflect: reflect_tint,
                transmit: transmit_tint,
                distribution: tr(alpha),
            }),
            Model::ThinDielectric { eta } => b.push(Lobe::ThinDielectric { eta }),
            Model::CoatedDiffuse {
                reflectance,
                alpha,
                eta,
                thickness,
                ..
            } => {
                b.push(Lobe::Reflection {
                    scale: Vec3::ONE,
                    fresnel: Fresnel::Dielectric(eta),
                    distribution: tr(alpha),
                });
                b.push(Lobe::CoatedBase {
                    rho: reflectance,
                    eta,
                    thickness,
                    inner: fresnel::coat_round_trip(eta, thickness),
                });
            }
            Model::CoatedConductor {
                interface_alpha,
                interface_eta,
                thickness,
                conductor_eta,
                conductor_k,
                conductor_alpha,
                ..
            } => {
                b.push(Lobe::Reflection {
                    scale: Vec3::ONE,
                    fresnel: Fresnel::Dielectric(interface_eta),
                    distribution: tr(interface_alpha),
                });
                // The conductor seen through the coat, its index relative to the coat's.
                b.push(Lobe::CoatedConductor(coated::CoatedConductor {
                    eta: conductor_eta / interface_eta,
                    k: conductor_k / interface_eta,
                    distribution: tr(conductor_alpha.max(interface_alpha)),
                    coat: interface_eta,
                    thickness,
                }));
            }
            Model::DiffuseTransmission {
                reflectance,
                transmittance,
            } => {
                b.push(Lobe::Lambert(reflectance));
                b.push(Lobe::LambertTransmission(transmittance));
            }
        }
        b
    }

    fn push(&mut self, lobe: Lobe) {
        let zero = match lobe {
            Lobe::Lambert(c) | Lobe::LambertTransmission(c) => c.max_element() <= 0.0,
            // Index 1 reflects nothing (pbrt's uber with `index` 1).
            Lobe::Reflection {
                fresnel: Fresnel::Dielectric(1.0) | Fresnel::SidedDielectric(1.0),
                ..
            } => true,
            Lobe::Reflection { scale, .. } | Lobe::SpecularTransmission { scale, .. } => {
                scale.max_element() <= 0.0
            }
            Lobe::Dielectric {
                reflect, transmit, ..
            } => reflect.max_element() <= 0.0 && transmit.max_element() <= 0.0,
            Lobe::FresnelBlend { rd, rs, .. } => rd.max_element() <= 0.0 && rs.max_element() <= 0.0,
            Lobe::CoatedBase { rho, .. } => rho.max_element() <= 0.0,
            Lobe::CoatedConductor(_) => false,
            Lobe::ThinDielectric { .. } => false,
        };
        if !zero && self.count < MAX_LOBES {
            self.lobes[self.count] = lobe;
            self.count += 1;
        }
    }

    fn lobes(&self, part: Part) -> impl Iterator<Item = &Lobe> {
        let min_alpha = self.estimated_min_alpha;
        self.lobes[..self.count].iter().filter(move |l| match part {
            Part::All => true,
            Part::Estimated => l.is_estimated(min_alpha),
            Part::Broad => l.is_broad(),
            Part::Glossy => !l.is_broad() && l.is_estimated(min_alpha),
            Part::Followed => !l.is_estimated(min_alpha),
        })
    }

    /// f(wo, wi) of the non-delta lobes in `part` (not times the cosine).
    pub fn f(&self, wo: Vec3, wi: Vec3, part: Part) -> Vec3 {
        self.lobes(part).map(|l| l.f(wo, wi)).sum()
    }

    /// A cheap weight of the lobes in `part` at `wo` (about their albedo), for choosing
    /// between parts.
    pub fn weight(&self, wo: Vec3, part: Part) -> f32 {
        self.lobes(part).map(|l| l.weight(wo)).sum()
    }

    /// The density with which [`Bsdf::sample`] draws the non-delta `wi`.
    pub fn pdf(&self, wo: Vec3, wi: Vec3, part: Part) -> f32 {
        let total = self.weight(wo, part);
        if total <= 0.0 {
            return 0.0;
        }
        self.lobes(part)
            .filter(|l| !l.is_delta())
            .map(|l| l.weight(wo) * l.pdf(wo, wi))
            .sum::<f32>()
            / total
    }

    /// Draws `wi` from the lobes in `part`: one lobe chosen with `u_lobe` by its weight, the
    /// direction from `u`. `None` when nothing is scattered that way.
    pub fn sample(&self, wo: Vec3, u_lobe: f32, u: (f32, f32), part: Part) -> Option<BsdfSample> {
        let total = self.weight(wo, part);
        if total.is_nan() || total <= 0.0 {
            return None;
        }
        let mut pick = u_lobe * total;
        let mut chosen = None;
        for lobe in self.lobes(part) {
            let w = lobe.weight(wo);
            if w <= 0.0 {
                continue;
            }
            chosen = Some((lobe, w));
            if pick < w {
                break;
            }
            pick -= w;
        }
        // Rounding can leave `pick` past the last lobe: that lobe it is.
        let (lobe, w) = chosen?;
        // The lobe's own choices (reflect or transmit) use what is left of u_lobe.
        let uc = (pick / w).clamp(0.0, 0.999_999);
        let s = lobe.sample(wo, uc, u)?;
        let transmission = s.wi.z * wo.z < 0.0;
        if s.delta {
            return Some(BsdfSample {
                wi: s.wi,
                f: s.f,
                pdf: s.pdf * w / total,
                delta: true,
                transmission,
            });
        }
        let pdf = self.pdf(wo, s.wi, part);
        (pdf > 0.0).then(|| BsdfSample {
            wi: s.wi,
            f: self.f(wo, s.wi, part),
            pdf,
            delta: false,
            transmission,
        })
    }

    /// Directional albedo ∫ f |cos θi| dωi of the lobes in `part`, delta lobes included:
    /// deterministic (a fixed stratified set of 16 × 16 samples of each lobe).
    pub fn albedo(&self, wo: Vec3, part: Part) -> Vec3 {
        let n = 16;
        let mut sum = Vec3::ZERO;
        for lobe in self.lobes(part) {
            let mut lobe_sum = Vec3::ZERO;
            for i in 0..n {
                for j in 0..n {
                    let u = ((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    // The golden-ratio sequence: spread, and apart from the grid's (u, v).
                    let uc = (0.5 + (i * n + j) as f32 * 0.618_034).fract();
                    if let Some(s) = lobe.sample(wo, uc, u) {
                        let weight = s.f * s.wi.z.abs() / s.pdf;
                        if weight.is_finite() {
                            lobe_sum += weight;
                        }
                    }
                }
            }
            sum += lobe_sum / (n * n) as f32;
        }
        sum
    }

    /// Whether a lobe in `part` spreads light crossing to the other side over directions
    /// (rough or diffuse transmission), so that lights on that side can be sampled through it.
    pub fn transmits_spread(&self, part: Part) -> bool {
        self.lobes(part).any(Lobe::transmits_spread)
    }

    /// Whether any lobe is in `part`.
    pub fn has(&self, part: Part) -> bool {
        self.lobes(part).next().is_some()
    }

    /// The reflectance of a BSDF that is one Lambert lobe and nothing else (pbrt's uber of
    /// index 1, a plastic without `Ks`): a diffuse surface, and should be rendered as one.
    pub fn lambert_only(&self) -> Option<Vec3> {
        match self.lobes[..self.count] {
            [Lobe::Lambert(r)] => Some(r),
            _ => None,
        }
    }

    /// Whether every lobe is a delta lobe.
    pub fn is_delta(&self) -> bool {
        self.lobes(Part::All).all(Lobe::is_delta)
    }

    /// The summed reflectance of the lobes in `part` when every one of them is a Lambert lobe
    /// (their f is that over π whatever the directions): a photon estimate there needs
    /// irradiance only, not each photon's direction.
    pub fn lambert_reflectance(&self, part: Part) -> Option<Vec3> {
        let mut sum = Vec3::ZERO;
        for lobe in self.lobes(part) {
            match lobe {
                Lobe::Lambert(r) => sum += *r,
                _ => return None,
            }
        }
        Some(sum)
    }
}

#[cfg(test)]
mod tests;
